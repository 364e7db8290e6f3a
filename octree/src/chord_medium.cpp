// See chord_medium.h.
#include <vtex/octree/chord_medium.h>

namespace vtex::octree {
namespace {

// Fills the voxels of `level` below `node` (at `nodeLevel`, voxel x, y, z there) into `dense`:
// the voxels a leaf above the level stands for take its entry, as OctreeCursor::locate answers.
template <class Grid>
void fill(const Octree& tree, const OctreeNode& node, std::uint32_t nodeLevel, std::int64_t x,
          std::int64_t y, std::int64_t z, std::uint32_t level, Grid& dense) {
    if (nodeLevel == level || node.isLeaf()) {
        if (node.data.isEmpty()) return;
        dense.voxels.push_back({unpackS(node.data), double(node.data.density)});
        const auto entry = std::uint32_t(dense.voxels.size());
        const std::int64_t size = std::int64_t(1) << (level - nodeLevel);
        for (std::int64_t k = z * size; k < (z + 1) * size; ++k)
            for (std::int64_t j = y * size; j < (y + 1) * size; ++j)
                for (std::int64_t i = x * size; i < (x + 1) * size; ++i)
                    dense.cells[mortonEncode8(std::uint32_t(i), std::uint32_t(j),
                                              std::uint32_t(k))] = entry;
        return;
    }
    const auto& children = tree.levels[nodeLevel + 1];
    for (unsigned c = 0; c < 8; ++c)
        if (node.childMask & (1u << c))
            fill(tree, children[node.firstChild + detail::kBitsBelow[node.childMask][c]],
                 nodeLevel + 1, 2 * x + (c & 1), 2 * y + (c >> 1 & 1), 2 * z + (c >> 2 & 1), level,
                 dense);
}

}  // namespace

ChordMedium::ChordMedium(const Octree& tree) : mTree(tree), mProfile(tree) {}
ChordMedium::~ChordMedium() = default;

const ChordMedium::Dense& ChordMedium::dense(std::uint32_t level) const {
    std::call_once(mBuilt[level], [&] {
        auto grid = std::make_unique<Dense>();
        grid->cells.assign(std::size_t(1) << (3 * level), 0);
        fill(mTree, mTree.levels[0][0], 0, 0, 0, 0, level, *grid);
        mDense[level] = std::move(grid);
    });
    return *mDense[level];
}

double ChordMedium::depth(std::uint32_t level, const Vec3& a, const Vec3& b) const {
    double depth = 0;
    const Vec3 delta = b - a;
    const double length = delta.norm();
    if (!(length > 0)) return depth;
    DensityProfile::Line line(mProfile, int(level), a, delta / length);
    forEachVoxel(level, a, b, [&](double extinction, double t0, double t1) {
        depth += extinction * (t1 - t0) * line.mean(t0, t1);
        return true;
    });
    return depth;
}

}  // namespace vtex::octree
