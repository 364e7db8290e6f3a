// The chord measures' medium (vtex/octree/chord_medium.h): its dense levels answer every step of a
// walk as the octree's own descent does (forEachVoxelOnSegment), the same voxels with the same
// extinction and the same distances to the last bit, on a tree with leaves above the finest level
// and empty blocks at every level, and past the deepest dense level, where it walks the octree.
#include <gtest/gtest.h>
#include <vtex/octree/chord_medium.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/octree/voxel.h>

#include <random>
#include <tuple>
#include <vector>

#include "random_volume.h"

namespace vtex::octree {
namespace {

using Visits = std::vector<std::tuple<double, double, double>>;  // (ρÂ, t0, t1)

// Scattered random voxels over a solid slab, which the compression stores as leaves above the
// finest level.
Octree slabTree(std::uint32_t levels) {
    const std::uint32_t n = 1u << levels;
    return test::scatteredOverSlab(levels, n / 4, n / 2, 0.03f, 5,
                                   [](std::uint32_t, std::uint32_t, std::uint32_t, std::mt19937& rng) { return test::randomVoxel(rng); });
}

Visits octreeVisits(const Octree& tree, std::uint32_t level, const Vec3& a, const Vec3& b) {
    Visits out;
    const Vec3 w = (b - a).normalized();
    forEachVoxelOnSegment(tree, level, a, b, [&](const OctreeNode& node, double t0, double t1) {
        out.emplace_back(voxelExtinction(node, w), t0, t1);
    });
    return out;
}

Visits mediumVisits(const ChordMedium& medium, std::uint32_t level, const Vec3& a, const Vec3& b) {
    Visits out;
    medium.forEachVoxel(level, a, b, [&](double extinction, double t0, double t1) {
        out.emplace_back(extinction, t0, t1);
        return true;
    });
    return out;
}

void expectSameWalks(const Octree& tree, std::uint32_t firstLevel, int segments) {
    const ChordMedium medium(tree);
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(0, 1);
    std::size_t visits = 0;
    for (std::uint32_t level = firstLevel; level < tree.levels.size(); ++level)
        for (int k = 0; k < segments; ++k) {
            // Ends inside the cube, some on voxel faces (a multiple of 1/64) and some axis-aligned.
            Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
            if (k % 5 == 0) a = (a * 64).array().floor() / 64;
            if (k % 7 == 0) b.x() = a.x();
            const Visits want = octreeVisits(tree, level, a, b);
            EXPECT_EQ(mediumVisits(medium, level, a, b), want)
                << "level " << level << ", segment " << k;
            visits += want.size();
            // The depth is those visits summed with the profile's factor (1 at unprofiled levels).
            double depth = 0;
            DensityProfile::Line line(medium.profile(), int(level), a, (b - a).normalized());
            for (const auto& [e, t0, t1] : want) depth += e * (t1 - t0) * line.mean(t0, t1);
            EXPECT_EQ(medium.depth(level, a, b), depth);
        }
    EXPECT_GT(visits, std::size_t(segments));  // the walks met voxels
}

TEST(ChordMedium, DenseLevelsWalkAsTheOctreeDoes) {
    const Octree tree = slabTree(6);
    // The slab is stored above level 6 (leaves standing for blocks of voxels).
    bool leafAbove = false;
    for (std::size_t l = 0; l + 1 < tree.levels.size(); ++l)
        for (const auto& node : tree.levels[l])
            leafAbove = leafAbove || (node.isLeaf() && !node.data.isEmpty());
    ASSERT_TRUE(leafAbove);
    expectSameWalks(tree, 0, 200);
}

TEST(ChordMedium, PastTheDeepestDenseLevelItWalksTheOctree) {
    static_assert(ChordMedium::kMaxDenseLevel == 6);
    NullProgress progress;
    const Octree tree = buildOctree(test::randomVolume(8, 20000, 4), BuildOptions{}, progress);
    ASSERT_EQ(tree.levels.size(), 9u);
    expectSameWalks(tree, 6, 100);  // 6 dense, 7 and 8 through the octree
}

TEST(MortonEncode8, IsMortonEncodeBelow256) {
    for (std::uint32_t z = 0; z < 256; ++z)
        for (std::uint32_t y = 0; y < 256; ++y)
            for (std::uint32_t x = 0; x < 256; x += 1 + (y + z) % 3)
                ASSERT_EQ(std::uint64_t(mortonEncode8(x, y, z)), mortonEncode(x, y, z))
                    << x << " " << y << " " << z;
}

}  // namespace
}  // namespace vtex::octree
