// Level choice and the transmittance march (see texel_march.h).
#include <vtex/render/texel_march.h>

#include "march.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

namespace vtex::render {

LevelChoice chooseLevel(double width, double lodBias, int maxLevel) {
    LevelChoice c;
    double level = double(maxLevel);
    if (std::isfinite(width) && width > 0) level = -std::log2(width);
    if (std::isnan(width) || width == INFINITY) level = 0;
    c.requested = width == 0 ? std::numeric_limits<double>::infinity() : level - lodBias;
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
    v.s = octree::unpackS(data);
    v.albedo = data.albedo;
    return v;
}

namespace {

// Sets the voxel index (1 + position in grid.voxels) of every voxel of grid.level under `node`
// (at `level`, coordinates x, y, z there) in `index` (row-major), adding the voxels of the nodes
// that stand for them.
void fillIndex(const octree::Octree& tree, const octree::OctreeNode& node, int level, std::uint32_t x, std::uint32_t y,
               std::uint32_t z, LevelGrid& grid, std::vector<std::uint32_t>& index) {
    if (level < grid.level && !node.isLeaf()) {
        for (unsigned c = 0, stored = 0; c < 8; ++c) {
            if (!(node.childMask & (1u << c))) continue;
            fillIndex(tree, tree.levels[std::size_t(level + 1)][node.firstChild + stored++], level + 1,
                      2 * x + (c & 1u), 2 * y + ((c >> 1) & 1u), 2 * z + ((c >> 2) & 1u), grid, index);
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
            std::uint32_t* row = &index[(std::size_t(k) * n + j) * n + (std::size_t(x) << shift)];
            std::fill(row, row + size, voxel);
        }
}

// One line of the Chebyshev transform below, n ≤ 64 voxels: f(i) = min_j max(|i − j|, g(j)),
// capped at kFar, the offsets wrapping around the line or not. f(i) ≤ v exactly where the voxels
// with g ≤ v, grown by v on both sides, reach; so each threshold v is one 64-bit mask, grown in
// log2(v) steps (a set grown by a, joined with itself shifted by ±s, s ≤ a + 1, is grown by
// a + s, without leaving the line between a voxel and what it reaches), and each voxel takes the
// first threshold that reaches it.
void chebyshevLine(const std::uint8_t* g, std::uint8_t* f, int n, bool wrap) {
    constexpr int kFar = LevelGrid::kCap;
    const std::uint64_t full = n == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << n) - 1;
    std::array<std::uint64_t, kFar> at{};  // at[v]: the voxels with g = v
    for (int i = 0; i < n; ++i)
        if (g[i] < kFar) at[g[i]] |= std::uint64_t(1) << i;
    const auto withShifts = [&](std::uint64_t x, int s) {  // x ∪ (x shifted by ±s)
        if (wrap) {
            s %= n;
            return s == 0 ? x : x | (((x << s) | (x >> (n - s))) & full) | (((x >> s) | (x << (n - s))) & full);
        }
        return s >= n ? x : x | ((x << s) & full) | (x >> s);
    };
    std::uint64_t within = 0, reached = 0;  // within: the voxels with g ≤ v
    std::fill(f, f + n, std::uint8_t(kFar));
    for (int v = 0; v < kFar && reached != full; ++v) {
        within |= at[std::size_t(v)];
        std::uint64_t grown = within;
        for (int a = 0; a < v && grown != full;) {
            const int s = std::min(a + 1, v - a);
            grown = withShifts(grown, s);
            a += s;
        }
        for (std::uint64_t fresh = grown & ~reached; fresh; fresh &= fresh - 1) f[std::countr_zero(fresh)] = std::uint8_t(v);
        reached |= grown;
    }
}

// The Chebyshev distances of a level (row-major, from its row-major voxel index), exactly, for
// levels of at most 64 voxels a side. The L∞ distance is separable: along x, then the max-min
// along y, then along z (x and y wrap, z does not).
std::vector<std::uint8_t> exactDistances(const std::vector<std::uint32_t>& index, int n) {
    const auto at = [n](int x, int y, int z) { return (std::size_t(z) * std::size_t(n) + std::size_t(y)) * std::size_t(n) + std::size_t(x); };
    std::vector<std::uint8_t> d(index.size(), std::uint8_t(LevelGrid::kCap));
    for (std::size_t i = 0; i < d.size(); ++i)
        if (index[i]) d[i] = 0;
    std::array<std::uint8_t, 64> in{}, out{};
    const auto pass = [&](int axis) {
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) {
                const auto lineIndex = [&](int i) { return axis == 0 ? at(i, a, b) : axis == 1 ? at(a, i, b) : at(a, b, i); };
                for (int i = 0; i < n; ++i) in[std::size_t(i)] = d[lineIndex(i)];
                chebyshevLine(in.data(), out.data(), n, axis < 2);
                for (int i = 0; i < n; ++i) d[lineIndex(i)] = out[std::size_t(i)];
            }
    };
    pass(0);
    pass(1);
    pass(2);
    return d;
}

// Exact distances up to this level (64³: the search's cost grows with the level's 8^ℓ voxels and
// the cap). Beyond it, lower bounds from the parent level's: around an empty parent at distance
// D, the empty parents span at least 2(D − 1) child voxels on every side of any child inside it,
// so the child's distance is at least 2D − 1 (a smaller distance only means a shorter leap).
constexpr int kExactDistanceLevel = 6;
static_assert(kExactDistanceLevel <= 6, "chebyshevLine holds a line of voxels in 64 bits");

}  // namespace

struct MarchVolume::Slot {
    std::once_flag once;
    std::unique_ptr<const LevelGrid> grid;
    // The grid once built: every shadow query asks for its level, and call_once's own check
    // (a pthread_once call) was 2.6 % of the bush field's middle view.
    std::atomic<const LevelGrid*> ready{nullptr};
};

struct MarchVolume::ProfileSlot {
    std::once_flag once;
    octree::DensityProfile profile;
    std::atomic<bool> ready{false};
};

MarchVolume::MarchVolume(std::shared_ptr<const octree::Octree> tree, int maxGridLevel)
    : mTree(std::move(tree)), mProfile(std::make_unique<ProfileSlot>()) {
    if (mTree) mTree->loadLevels(0);
    if (mTree && !mTree->levels.empty() && !mTree->levels[0].empty()) mMaxLevel = std::min(int(mTree->levels.size()) - 1, 30);
    mMaxGridLevel = std::clamp(maxGridLevel, -1, std::min(mMaxLevel, LevelGrid::kMaxLevel));
    if (mMaxGridLevel >= 0) mSlots = std::make_unique<Slot[]>(std::size_t(mMaxGridLevel + 1));
    mProfiledLevels = mMaxLevel >= 0 ? octree::DensityProfile::profiledLevels(mMaxLevel) : 0;
}

MarchVolume::~MarchVolume() = default;

const octree::DensityProfile* MarchVolume::measuredProfile(int level) const {
    if (!mProfile->ready.load(std::memory_order_acquire))
        std::call_once(mProfile->once, [&] {
            mProfile->profile = octree::DensityProfile(*mTree);
            mProfile->ready.store(true, std::memory_order_release);
        });
    return mProfile->profile.profiles(level) ? &mProfile->profile : nullptr;
}

const LevelGrid* MarchVolume::grid(int level) const {
    if (level < 0 || level > mMaxGridLevel) return nullptr;
    Slot& slot = mSlots[std::size_t(level)];
    if (const LevelGrid* grid = slot.ready.load(std::memory_order_acquire)) return grid;
    std::call_once(slot.once, [&] {
        mTree->loadLevels(std::uint32_t(level));  // a tree opened with openVto reads the level now
        auto grid = std::make_unique<LevelGrid>();
        grid->level = level;
        const std::uint32_t n = grid->n = 1u << level;
        grid->voxels.emplace_back();  // index 0: empty
        std::vector<std::uint32_t> index(std::size_t(n) * n * n, 0);
        fillIndex(*mTree, mTree->levels[0][0], 0, 0, 0, 0, *grid, index);
        std::vector<std::uint8_t> distance;
        if (level <= kExactDistanceLevel) distance = exactDistances(index, int(n));
        grid->cells.resize(index.size());
        const LevelGrid* parent = level > kExactDistanceLevel ? this->grid(level - 1) : nullptr;
        for (std::uint32_t z = 0, i = 0; z < n; ++z)
            for (std::uint32_t y = 0; y < n; ++y)
                for (std::uint32_t x = 0; x < n; ++x, ++i) {
                    std::uint32_t d = 0;
                    if (!index[i]) {
                        if (parent) {
                            const int dp = parent->distance(x / 2, y / 2, z / 2);
                            d = std::uint32_t(dp == 0 ? 1 : std::min(2 * dp - 1, LevelGrid::kCap));
                        } else {
                            d = distance[i];
                        }
                    }
                    grid->cells[LevelGrid::morton(x, y, z)] = index[i] ? index[i] : LevelGrid::kEmpty | d;
                }
        slot.grid = std::move(grid);
        slot.ready.store(slot.grid.get(), std::memory_order_release);
    });
    return slot.grid.get();
}

SegmentTransmittance marchTransmittance(const MarchVolume& volume, double tau, const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to, int level, double cutoff, double ownFactor) {
    SegmentTransmittance out;
    const Eigen::Vector3d delta = to - from;
    const double length = delta.norm();
    if (!(length > 0)) return out;
    const Eigen::Vector3d dir = delta / length;
    double opticalDepth = 0;
    const double maxDepth = cutoff > 0 ? -std::log(cutoff) : INFINITY;
    detail::ProfileFactor profile(volume, level, from, dir);
    // The own voxel's stretch: its density times ownFactor. A march visits runs of voxels that
    // share a stored node, so the stretch is marched apart from the rest.
    const double own = ownFactor == 1 ? 0.0 : octree::voxelExit(from, dir, std::min(level, volume.maxLevel()), length);
    if (own > 0) {
        out.blocks = detail::march(volume, level, from, dir, own, [&](const GridVoxel& voxel, double s, double ds) {
            opticalDepth += ownFactor * voxel.extinction(tau, dir) * ds * profile(s, ds);
            return true;
        });
    }
    if (own < length && opticalDepth < maxDepth) {
        out.blocks += detail::march(volume, level, from + own * dir, dir, length - own, [&](const GridVoxel& voxel, double s, double ds) {
            opticalDepth += voxel.extinction(tau, dir) * ds * profile(own + s, ds);
            return opticalDepth < maxDepth;
        });
    }
    out.transmittance = std::exp(-opticalDepth);
    return out;
}

}  // namespace vtex::render
