// One level of an octree as constant cubes (interop/level_export.h), against the octree's own
// expansion of the level (a depth-first walk that replicates the leaves).
#include "texel_fixture.h"

#include <vtex/interop/level_export.h>

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>

namespace vtex::interop {
namespace {

TEST(LevelBlocks, CoverExactlyWhatExpandLevelLists) {
    const octree::Octree tree = test::exportTestOctree();
    ASSERT_EQ(tree.levelCount(), 6u);
    for (std::uint32_t level = 0; level < tree.levelCount(); ++level) {
        std::map<std::uint64_t, const octree::VoxelData*> covered;
        for (const LevelBlock& b : levelBlocks(tree, level)) {
            ASSERT_EQ(b.size, 1u << (level - b.storedLevel));
            for (std::uint32_t dz = 0; dz < b.size; ++dz)
                for (std::uint32_t dy = 0; dy < b.size; ++dy)
                    for (std::uint32_t dx = 0; dx < b.size; ++dx) {
                        const auto key = octree::mortonEncode(b.origin[0] + dx, b.origin[1] + dy, b.origin[2] + dz);
                        ASSERT_TRUE(covered.emplace(key, b.data).second) << "voxel covered twice at level " << level;
                    }
        }
        const auto expanded = tree.expandLevel(level);
        ASSERT_EQ(covered.size(), expanded.size()) << "level " << level;
        for (const octree::VolumeBlock& v : expanded) {
            const auto it = covered.find(v.key);
            ASSERT_NE(it, covered.end()) << "level " << level << " key " << v.key;
            EXPECT_EQ(*it->second, v.data);
        }
    }
}

TEST(LevelBlocks, StoredLeavesAboveTheLevelAreOneBlockEach) {
    const octree::Octree tree = test::exportTestOctree();
    // The fixture's 16³ solid block is one leaf at level 1: a single cube of 16 voxels a side at
    // the finest level, not 4096 voxels.
    std::size_t big = 0;
    for (const LevelBlock& b : levelBlocks(tree, 5))
        if (b.size == 16) {
            ++big;
            EXPECT_EQ(b.storedLevel, 1u);
            EXPECT_EQ(b.origin, (std::array<std::uint32_t, 3>{0, 0, 0}));
            EXPECT_EQ(b.data->density, 7.5f);
        }
    EXPECT_EQ(big, 1u);
}

TEST(LevelBlocks, RefuseALevelTheOctreeDoesNotHave) {
    const octree::Octree tree = test::exportTestOctree();
    EXPECT_THROW(levelBlocks(tree, tree.levelCount()), std::out_of_range);
}

TEST(LevelBlocks, AnEmptyVolumeHasNoBlocks) {
    octree::SparseVolume empty;
    empty.info.levels = 3;
    NullProgress progress;
    const octree::Octree tree = octree::buildOctree(empty, {}, progress);
    for (std::uint32_t level = 0; level < tree.levelCount(); ++level) EXPECT_TRUE(levelBlocks(tree, level).empty());
}

TEST(SggxEntries, AreSInTheNamedOrder) {
    const octree::Octree tree = test::exportTestOctree();
    const octree::VoxelData& voxel = tree.levels.back().front().data;
    const octree::Mat3 s = octree::unpackS(voxel).matrix();
    const auto e = sggxEntries(voxel);
    const int rows[6] = {0, 1, 2, 0, 0, 1}, cols[6] = {0, 1, 2, 1, 2, 2};
    for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(e[std::size_t(i)], s(rows[i], cols[i])) << kSggxEntryNames[std::size_t(i)];
        const std::string name = kSggxEntryNames[std::size_t(i)];
        EXPECT_EQ(name, std::string(1, "xyz"[rows[i]]) + "xyz"[cols[i]]);
    }
    EXPECT_NE(e[3], 0.0) << "the fixture's first finest voxel is rotated: S has off-diagonal entries";
}

}  // namespace
}  // namespace vtex::interop
