// Level choice and the transmittance march (see texel_march.h).
#include <vtex/render/texel_march.h>

#include "march.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <vector>

namespace vtex::render {

LevelChoice chooseLevel(double width, double lodBias, int maxLevel) {
    LevelChoice c;
    double level = double(maxLevel);
    if (std::isfinite(width) && width > 0) level = -std::log2(width);
    if (std::isnan(width) || width == INFINITY) level = 0;
    level = std::clamp(level - lodBias, 0.0, double(std::max(maxLevel, 0)));
    c.level = level;
    c.coarse = int(std::floor(level));
    c.fine = std::min(c.coarse + 1, maxLevel);
    c.fineWeight = c.fine == c.coarse ? 0.0 : level - c.coarse;
    return c;
}

GridVoxel gridVoxel(const octree::VoxelData& data) {
    GridVoxel v;
    v.density = data.density;
    v.s = voxelS(data);
    v.albedo = data.albedo;
    return v;
}

namespace {

// Writes into grid.cells the voxel index of every voxel of grid.level under `node` (at `level`,
// coordinates x, y, z there), adding the voxels of the nodes that stand for them.
void fillCells(const octree::Octree& tree, const octree::OctreeNode& node, int level, std::uint32_t x, std::uint32_t y,
               std::uint32_t z, LevelGrid& grid) {
    if (level < grid.level && !node.isLeaf()) {
        for (unsigned c = 0, stored = 0; c < 8; ++c) {
            if (!(node.childMask & (1u << c))) continue;
            fillCells(tree, tree.levels[std::size_t(level + 1)][node.firstChild + stored++], level + 1,
                      2 * x + (c & 1u), 2 * y + ((c >> 1) & 1u), 2 * z + ((c >> 2) & 1u), grid);
        }
        return;
    }
    if (node.data.isEmpty()) return;
    const auto voxel = std::uint32_t(grid.voxels.size());
    grid.voxels.push_back(gridVoxel(node.data));
    const int shift = grid.level - level;
    const std::uint32_t size = 1u << shift;
    const std::size_t n = grid.n;
    for (std::uint32_t k = z << shift; k < (z + 1) << shift; ++k)
        for (std::uint32_t j = y << shift; j < (y + 1) << shift; ++j) {
            std::uint32_t* row = &grid.cells[(std::size_t(k) * n + j) * n + (std::size_t(x) << shift)];
            std::fill(row, row + size, voxel);
        }
}

// The Chebyshev distances of a level, exactly. The L∞ distance is separable: along x, then the
// max-min along y, then along z, each a search outward that stops once the offset reaches the
// best distance found (x and y wrap, z does not).
void exactDistances(LevelGrid& grid) {
    const int n = int(grid.n);
    constexpr int kFar = LevelGrid::kCap;
    const auto at = [n](int x, int y, int z) { return (std::size_t(z) * std::size_t(n) + std::size_t(y)) * std::size_t(n) + std::size_t(x); };
    std::vector<std::uint8_t>& d = grid.distance;
    d.assign(grid.cells.size(), std::uint8_t(kFar));
    for (std::size_t i = 0; i < d.size(); ++i)
        if (grid.cells[i]) d[i] = 0;
    std::vector<std::uint8_t> line(static_cast<std::size_t>(n));
    const auto pass = [&](int axis) {
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) {
                const auto index = [&](int i) { return axis == 0 ? at(i, a, b) : axis == 1 ? at(a, i, b) : at(a, b, i); };
                for (int i = 0; i < n; ++i) line[std::size_t(i)] = d[index(i)];
                for (int i = 0; i < n; ++i) {
                    int best = line[std::size_t(i)];
                    for (int k = 1; k < best && k < n; ++k) {
                        for (const int j : {i - k, i + k}) {
                            int w = j;
                            if (axis < 2) w = ((j % n) + n) % n;
                            else if (j < 0 || j >= n) continue;
                            best = std::min(best, std::max(k, int(line[std::size_t(w)])));
                        }
                    }
                    d[index(i)] = std::uint8_t(std::min(best, kFar));
                }
            }
    };
    pass(0);
    pass(1);
    pass(2);
}

// Lower bounds of a level's distances from its parent level's, for levels where the exact search
// costs too much: around an empty parent at distance D, the empty parents span at least
// 2(D − 1) child voxels on every side of any child inside it, so the child's distance is at
// least 2D − 1. A smaller distance only means a shorter leap.
void distancesFromParent(LevelGrid& grid, const LevelGrid& parent) {
    const std::size_t n = grid.n, pn = parent.n;
    grid.distance.resize(grid.cells.size());
    for (std::size_t z = 0; z < n; ++z)
        for (std::size_t y = 0; y < n; ++y)
            for (std::size_t x = 0; x < n; ++x) {
                const std::size_t i = (z * n + y) * n + x;
                const int d = parent.distance[((z / 2) * pn + y / 2) * pn + x / 2];
                grid.distance[i] = grid.cells[i] ? 0 : std::uint8_t(d == 0 ? 1 : std::min(2 * d - 1, LevelGrid::kCap));
            }
}

// Exact distances up to this level (64³: the search's cost grows with the level's 8^ℓ voxels and
// the cap), bounds from the parent beyond.
constexpr int kExactDistanceLevel = 6;

}  // namespace

struct MarchVolume::Slot {
    std::once_flag once;
    std::unique_ptr<const LevelGrid> grid;
};

MarchVolume::MarchVolume(std::shared_ptr<const octree::Octree> tree, int maxGridLevel) : mTree(std::move(tree)) {
    if (mTree && !mTree->levels.empty() && !mTree->levels[0].empty()) mMaxLevel = std::min(int(mTree->levels.size()) - 1, 30);
    mMaxGridLevel = std::clamp(maxGridLevel, -1, std::min(mMaxLevel, 10));
    if (mMaxGridLevel >= 0) mSlots = std::make_unique<Slot[]>(std::size_t(mMaxGridLevel + 1));
}

MarchVolume::~MarchVolume() = default;

const LevelGrid* MarchVolume::grid(int level) const {
    if (level < 0 || level > mMaxGridLevel) return nullptr;
    Slot& slot = mSlots[std::size_t(level)];
    std::call_once(slot.once, [&] {
        auto grid = std::make_unique<LevelGrid>();
        grid->level = level;
        grid->n = 1u << level;
        grid->cells.assign(std::size_t(grid->n) * grid->n * grid->n, 0);
        grid->voxels.emplace_back();  // the empty sentinel
        fillCells(*mTree, mTree->levels[0][0], 0, 0, 0, 0, *grid);
        if (level <= kExactDistanceLevel) exactDistances(*grid);
        else distancesFromParent(*grid, *this->grid(level - 1));
        slot.grid = std::move(grid);
    });
    return slot.grid.get();
}

SegmentTransmittance marchTransmittance(const MarchVolume& volume, double tau, const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to, int level, double cutoff) {
    SegmentTransmittance out;
    const Eigen::Vector3d delta = to - from;
    const double length = delta.norm();
    if (!(length > 0)) return out;
    const Eigen::Vector3d dir = delta / length;
    double opticalDepth = 0;
    const double maxDepth = cutoff > 0 ? -std::log(cutoff) : INFINITY;
    out.blocks = detail::march(volume, level, from, dir, length, [&](const GridVoxel& voxel, double, double ds) {
        opticalDepth += tau * voxel.density * detail::normalizedArea(voxel.s, dir) * ds;
        return opticalDepth < maxDepth;
    });
    out.transmittance = std::exp(-opticalDepth);
    return out;
}

}  // namespace vtex::render
