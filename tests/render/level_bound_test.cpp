// The bound on the levels a render can use: never finer than what the renderer really uses
// (the histogram of its level choices), tight within one level, and following resolution and
// LoD bias exactly.
#include "fixtures.h"

#include <vtex/render/level_bound.h>

#include <gtest/gtest.h>

namespace vtex::render {
namespace {

using namespace vtex::render::test;

// The deepest level with any weight in the renderer's histogram.
int deepestUsedLevel(const RenderStats& stats) {
    int deepest = -1;
    for (std::size_t l = 0; l < stats.levelHistogram.size(); ++l)
        if (stats.levelHistogram[l] > 0) deepest = int(l);
    return deepest;
}

// A 4×4 grid of cells under a 64³ volume of isotropic voxels seen obliquely from afar, so that
// the levels used (about 1 to 5 across the sizes and biases below) lie inside the octree's range.
Scene farScene(int imageSize) {
    Scene scene = baseScene(Eigen::Vector3d(0.3, -9, 5), Eigen::Vector3d(0, 0, 0), 30, imageSize);
    const auto tree = makeOctree(6, [](int x, int y, int z) -> std::optional<octree::VoxelData> {
        if (z > 10 || (x + y) % 7 == 0) return std::nullopt;
        return sphereVoxel(40.0f);
    }, true);
    addSurface(scene, gridMesh(-1, -1, 1, 1, 0, 4), addTexel(scene, tree), 0.3);
    addTexel(scene, tree);  // referenced by no surface
    return scene;
}

TEST(LevelBound, TheRendererNeverUsesALevelFinerThanTheBoundAndReachesWithinOneOfIt) {
    for (int size : {32, 64, 128}) {
        const Scene scene = farScene(size);
        for (double bias : {-1.0, 0.0, 1.0}) {
            RenderOptions options;
            options.lodBias = bias;
            const auto needs = finestUsefulLevels(scene, options);
            ASSERT_EQ(needs.size(), 2u);
            ASSERT_TRUE(needs[0].used);
            EXPECT_FALSE(needs[1].used) << "no surface references the second texel";
            ASSERT_FALSE(needs[0].unbounded);
            const int used = deepestUsedLevel(renderQuiet(scene, options).stats);
            EXPECT_LE(used, needs[0].finestLevel) << "size " << size << " bias " << bias;
            EXPECT_GE(used, needs[0].finestLevel - 1) << "size " << size << " bias " << bias;
        }
    }
}

TEST(LevelBound, DoublingTheResolutionOrLoweringTheBiasNeedsExactlyOneLevelMore) {
    const Scene scene = farScene(64);
    RenderOptions options;
    const int base = finestUsefulLevels(scene, options)[0].finestLevel;
    options.width = options.height = 128;
    EXPECT_EQ(finestUsefulLevels(scene, options)[0].finestLevel, base + 1);
    options.lodBias = 1;
    EXPECT_EQ(finestUsefulLevels(scene, options)[0].finestLevel, base);
    options.spp = 4;  // 2×2 strata: each sample's cone is half as wide
    EXPECT_EQ(finestUsefulLevels(scene, options)[0].finestLevel, base + 1);
}

TEST(LevelBound, ACameraInsideAShellNeedsEveryLevel) {
    Scene scene = baseScene(Eigen::Vector3d(0.1, 0.1, 0.1), Eigen::Vector3d(1, 1, 0.1), 40, 32);
    addSurface(scene, gridMesh(-1, -1, 1, 1, 0, 2), addTexel(scene, makeOctree(3, [](int, int, int) {
                   return std::optional<octree::VoxelData>(sphereVoxel(1.0f));
               })),
               0.5);
    const auto needs = finestUsefulLevels(scene, RenderOptions{});
    EXPECT_TRUE(needs[0].unbounded);
    EXPECT_EQ(needs[0].nearestDistance, 0);
}

}  // namespace
}  // namespace vtex::render
