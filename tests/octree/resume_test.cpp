// OctreeBuilder::resume: the builder of a tree rebuilt from the tree alone, so that `vtex build
// --update` re-filters only the ancestors of the changed region and still writes the full
// build's tree bit for bit.
#include "random_volume.h"

#include <vtex/octree/octree.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <random>

namespace vtex::octree {
namespace {

using test::randomVolume;
using test::randomVoxel;

TEST(ResumeBuild, ATreeRebuildsItsBuilderAndAnUpdateGivesTheFullBuildBitForBit) {
    NullProgress progress;
    for (const FilterRule rule : {FilterRule::Sggx, FilterRule::Neyret}) {
        BuildOptions options;
        options.rule = rule;
        const SparseVolume before = randomVolume(5, 3000, 1);
        const Octree tree = buildOctree(before, options, progress);
        auto resumed = OctreeBuilder::resume(tree, before.info, options);
        ASSERT_TRUE(resumed.has_value());
        EXPECT_EQ(serializeVto(resumed->compress(progress)), serializeVto(tree));

        // Inside a region, other voxels: the update re-filters only the region's ancestors.
        const VoxelBox region{{3, 7, 0}, {19, 20, 11}};
        SparseVolume after = randomVolume(5, 3000, 2);
        std::vector<VolumeBlock> blocks, inside;
        for (const auto& b : before.blocks) {
            const auto c = mortonDecode(b.key);
            if (!region.contains(c[0], c[1], c[2])) blocks.push_back(b);
        }
        for (const auto& b : after.blocks) {
            const auto c = mortonDecode(b.key);
            if (region.contains(c[0], c[1], c[2])) inside.push_back(b);
        }
        after.blocks = blocks;
        after.blocks.insert(after.blocks.end(), inside.begin(), inside.end());
        after.sortBlocks();
        auto updated = OctreeBuilder::resume(tree, after.info, options);
        ASSERT_TRUE(updated.has_value());
        updated->updateRegion(region, inside, progress);
        EXPECT_LT(updated->filteredNodeCount(), tree.storedNodes() / 2);
        EXPECT_EQ(serializeVto(updated->compress(progress)), serializeVto(buildOctree(after, options, progress)));
    }
}

TEST(ResumeBuild, ATreeWithMergedNodesOrASolidInteriorCannotResume) {
    NullProgress progress;
    // A full constant 4³ block: tolerance 0 merges it into one node above the finest level.
    SparseVolume constant;
    constant.info.levels = 3;
    std::mt19937 rng(5);
    const VoxelData d = randomVoxel(rng);
    for (std::uint32_t z = 0; z < 4; ++z)
        for (std::uint32_t y = 0; y < 4; ++y)
            for (std::uint32_t x = 0; x < 4; ++x) constant.blocks.push_back(VolumeBlock{mortonEncode(x, y, z), 3, 0, d});
    constant.sortBlocks();
    const Octree merged = buildOctree(constant, {}, progress);
    ASSERT_LT(merged.storedNodes(), 64u);
    EXPECT_FALSE(OctreeBuilder::resume(merged, constant.info, {}).has_value());
    SparseVolume solid = randomVolume(4, 100, 3);
    solid.info.solidDensity = 64;
    EXPECT_FALSE(OctreeBuilder::resume(buildOctree(solid, {}, progress), solid.info, {}).has_value());
    // An empty volume resumes to an empty tree.
    SparseVolume empty;
    empty.info.levels = 3;
    const auto none = OctreeBuilder::resume(buildOctree(empty, {}, progress), empty.info, {});
    ASSERT_TRUE(none.has_value());
    EXPECT_EQ(serializeVto(none->compress(progress)), serializeVto(buildOctree(empty, {}, progress)));
}

}  // namespace
}  // namespace vtex::octree
