// The one descent of the octree (OctreeCursor): against the tree expanded level by level
// (Octree::expandLevel, a depth-first walk of its own), whatever the order of the lookups, and
// its block level against the voxels of the block it vouches for.
#include <vtex/octree/cursor.h>
#include <vtex/octree/octree.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "random_volume.h"

namespace vtex::octree {
namespace {

constexpr std::uint32_t kLevels = 5;

// Scattered voxels of a few distinct values over a solid slab, whose constant blocks the
// compression stores as leaves above the finest level.
Octree testTree() {
    return test::scatteredOverSlab(kLevels, 8, 16, 0.05f, 3, [](std::uint32_t x, std::uint32_t y, std::uint32_t z, std::mt19937&) {
        VoxelData d;
        d.density = 1.0f + float((x + 2 * y + 3 * z) % 3);
        packIsotropic(d);
        d.albedo = {0.5f, 0.5f, 0.5f};
        return d;
    });
}

struct Voxel {
    int level;
    std::uint32_t x, y, z;
};

std::vector<Voxel> allVoxels() {
    std::vector<Voxel> out;
    for (int l = 0; l <= int(kLevels); ++l) {
        const std::uint32_t n = 1u << l;
        for (std::uint32_t z = 0; z < n; ++z)
            for (std::uint32_t y = 0; y < n; ++y)
                for (std::uint32_t x = 0; x < n; ++x) out.push_back({l, x, y, z});
    }
    return out;
}

TEST(OctreeCursor, FindsWhatTheExpandedLevelsHoldInAnyOrder) {
    const Octree tree = testTree();
    ASSERT_LT(tree.storedNodes(), std::uint64_t(tree.stats.back().occupiedNodes)) << "leaves above the finest level";
    std::vector<std::map<std::uint64_t, VoxelData>> expanded(kLevels + 1);
    for (std::uint32_t l = 0; l <= kLevels; ++l)
        for (const VolumeBlock& b : tree.expandLevel(l)) expanded[l][b.key] = b.data;
    std::vector<Voxel> voxels = allVoxels();
    std::mt19937 rng(9);
    // Raster order level by level (neighbours), then a shuffle (levels and places mixed: the
    // cached path must not be trusted across levels).
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) std::shuffle(voxels.begin(), voxels.end(), rng);
        OctreeCursor cursor(tree);
        std::uint64_t found = 0;
        for (const Voxel& v : voxels) {
            const Located got = cursor.locate(v.level, v.x, v.y, v.z);
            const auto& level = expanded[std::size_t(v.level)];
            const auto want = level.find(mortonEncode(v.x, v.y, v.z));
            ASSERT_EQ(got.node != nullptr, want != level.end()) << pass << " " << v.level << " " << v.x << " " << v.y << " " << v.z;
            if (!got.node) continue;
            ++found;
            EXPECT_EQ(got.node->data, want->second);
            // A fresh cursor descends from the root: the same node, not only the same data.
            EXPECT_EQ(OctreeCursor(tree).locate(v.level, v.x, v.y, v.z).node, got.node);
        }
        std::uint64_t stored = 0;
        for (const auto& level : expanded) stored += level.size();
        EXPECT_EQ(found, stored) << pass;
    }
}

// The block level is where the answer becomes uniform: every voxel of the 2^(level − blockLevel)
// block around a voxel gets the same node (or empty space), and for a stored node it is the
// level the node is stored at.
TEST(OctreeCursor, TheBlockLevelNamesAUniformBlock) {
    const Octree tree = testTree();
    OctreeCursor cursor(tree), probe(tree);
    int coarseBlocks = 0;
    for (const Voxel& v : allVoxels()) {
        const Located got = cursor.locate(v.level, v.x, v.y, v.z);
        ASSERT_GE(got.blockLevel, 0);
        ASSERT_LE(got.blockLevel, v.level);
        if (got.node) {
            const std::size_t stored = std::size_t(got.node - tree.levels[std::size_t(got.blockLevel)].data());
            EXPECT_LT(stored, tree.levels[std::size_t(got.blockLevel)].size()) << "stored at its block level";
        }
        const int shift = v.level - got.blockLevel;
        if (shift == 0) continue;
        ++coarseBlocks;
        const std::uint32_t size = 1u << shift;
        const std::uint32_t x0 = v.x & ~(size - 1), y0 = v.y & ~(size - 1), z0 = v.z & ~(size - 1);
        for (std::uint32_t dz = 0; dz < size; dz += std::max(1u, size - 1))
            for (std::uint32_t dy = 0; dy < size; dy += std::max(1u, size - 1))
                for (std::uint32_t dx = 0; dx < size; dx += std::max(1u, size - 1))
                    EXPECT_EQ(probe.locate(v.level, x0 + dx, y0 + dy, z0 + dz).node, got.node)
                        << v.level << " " << v.x << " " << v.y << " " << v.z;
    }
    EXPECT_GT(coarseBlocks, 1000);
}

TEST(OctreeCursor, AnEmptyTreeIsEmptyEverywhere) {
    SparseVolume v;
    v.info.levels = 4;
    NullProgress progress;
    const Octree tree = buildOctree(v, BuildOptions{}, progress);
    OctreeCursor cursor(tree);
    for (int l = 0; l <= 4; ++l) {
        const Located got = cursor.locate(l, 0, 0, 0);
        EXPECT_EQ(got.node, nullptr);
        EXPECT_EQ(got.blockLevel, 0) << "the empty root stands for everything";
    }
}

}  // namespace
}  // namespace vtex::octree
