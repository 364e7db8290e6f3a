// The sparse octree: filtering, compression, lossless tolerance 0, partial recompute.
#include <vtex/octree/cursor.h>
#include "random_volume.h"

#include <vtex/octree/octree.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

namespace vtex::octree {
namespace {

using test::randomVolume;
using test::randomVoxel;

// Solid half-space x + 2y + 3z < 3N: a constant region with a slanted boundary.
SparseVolume halfSpace(std::uint32_t levels) {
    SparseVolume v;
    v.info.levels = levels;
    const std::uint32_t n = 1u << levels;
    VoxelData d;
    d.density = 5;
    packIsotropic(d);
    d.albedo = {0.5f, 0.5f, 0.5f};
    for (std::uint32_t z = 0; z < n; ++z)
        for (std::uint32_t y = 0; y < n; ++y)
            for (std::uint32_t x = 0; x < n; ++x)
                if (x + 2 * y + 3 * z < 3 * n) v.blocks.push_back(VolumeBlock{mortonEncode(x, y, z), std::uint8_t(levels), 0, d});
    v.sortBlocks();
    return v;
}

Octree build(const SparseVolume& v, double tolerance = 0, bool compress = true,
             FilterRule rule = FilterRule::Sggx) {
    BuildOptions o;
    o.tolerance = tolerance;
    o.compress = compress;
    o.rule = rule;
    NullProgress progress;
    return buildOctree(v, o, progress);
}

std::vector<VolumeBlock> expandBlocks(const SparseVolume& v) {
    std::vector<VolumeBlock> out;
    for (const auto& b : v.blocks) {
        const std::uint32_t s = v.info.levels - b.level;
        for (std::uint64_t c = 0; c < (std::uint64_t(1) << (3 * s)); ++c)
            out.push_back(VolumeBlock{(b.key << (3 * s)) | c, std::uint8_t(v.info.levels), 0, b.data});
    }
    return out;
}

TEST(OctreeBuild, MortonKeysRoundTrip) {
    std::mt19937 rng(1);
    std::uniform_int_distribution<std::uint32_t> c(0, (1u << 20) - 1);
    for (int i = 0; i < 10000; ++i) {
        const std::array<std::uint32_t, 3> p{c(rng), c(rng), c(rng)};
        EXPECT_EQ(mortonDecode(mortonEncode(p[0], p[1], p[2])), p);
    }
    EXPECT_EQ(mortonEncode(1, 0, 0), 1u);
    EXPECT_EQ(mortonEncode(0, 1, 0), 2u);
    EXPECT_EQ(mortonEncode(0, 0, 1), 4u);
}

TEST(OctreeBuild, EmptyVolumeStoresOneNode) {
    SparseVolume v;
    v.info.levels = 6;
    const Octree tree = build(v);
    EXPECT_EQ(tree.storedNodes(), 1u);
    EXPECT_EQ(tree.levels[0][0].data.density, 0.0f);
    EXPECT_TRUE(tree.levels[0][0].isLeaf());
    EXPECT_DOUBLE_EQ(tree.compression(), 1.0 - 1.0 / (64.0 * 64 * 64));
    EXPECT_EQ(OctreeCursor(tree).locate(6, 3, 4, 5).node, nullptr);
}

TEST(OctreeBuild, ConstantHalfSpaceStoresOrderNSquaredNodes) {
    std::uint64_t stored[3];
    for (std::uint32_t l = 4; l <= 6; ++l) {
        const auto v = halfSpace(l);
        const Octree tree = build(v);
        stored[l - 4] = tree.storedNodes();
        const double n = double(1u << l);
        EXPECT_LT(double(tree.storedNodes()), 16 * n * n) << l;
        EXPECT_LT(tree.storedNodes(), v.blocks.size() / 3) << l;
        // Every finest voxel is still there, exactly.
        EXPECT_EQ(tree.expandLevel(l), v.blocks);
    }
    // Doubling N multiplies the storage by about 4 (the boundary), not 8 (the volume).
    for (int i = 0; i < 2; ++i) {
        const double growth = double(stored[i + 1]) / double(stored[i]);
        EXPECT_GT(growth, 3.0);
        EXPECT_LT(growth, 5.0);
    }
}

TEST(OctreeBuild, ParentIsTheMeanOfItsChildren) {
    const auto v = randomVolume(4, 600, 3);
    const Octree tree = build(v, 0, false);
    // Density: the mean of 8 children (empty ones count 0), so the level mean is conserved.
    for (std::uint32_t l = 0; l <= 4; ++l) EXPECT_NEAR(tree.stats[l].meanDensity, tree.stats[4].meanDensity, 1e-5);
    for (std::uint32_t l = 0; l < 4; ++l) {
        for (const auto& node : tree.levels[l]) {
            double sum = 0, albedo = 0;
            for (int c = 0; c < std::popcount(unsigned(node.childMask)); ++c) {
                const auto& child = tree.levels[l + 1][node.firstChild + std::size_t(c)];
                sum += child.data.density;
                albedo += child.data.density * child.data.albedo[0];
            }
            ASSERT_NEAR(node.data.density, sum / 8, 1e-5 * sum);
            ASSERT_NEAR(node.data.albedo[0], albedo / sum, 1e-5);
        }
    }
}

TEST(OctreeBuild, ToleranceZeroLosesNothing) {
    // Random voxels plus constant blocks so that something collapses.
    auto v = randomVolume(5, 3000, 4);
    VoxelData solid;
    solid.density = 80;
    packIsotropic(solid);
    solid.albedo = {0.2f, 0.3f, 0.4f};
    std::vector<VolumeBlock> blocks;
    for (const auto& b : v.blocks)
        if (mortonDecode(b.key)[2] < 16) blocks.push_back(b);
    for (std::uint32_t y = 0; y < 4; ++y)
        for (std::uint32_t x = 0; x < 4; ++x)
            blocks.push_back(VolumeBlock{mortonEncode(x, y, 3), 2, kBlockSolid, solid});  // z ∈ [24, 32)
    // Equal finest voxels in z ∈ [16, 24), x, y < 16: they collapse only if filtering is exact.
    for (std::uint32_t z = 16; z < 24; ++z)
        for (std::uint32_t y = 0; y < 16; ++y)
            for (std::uint32_t x = 0; x < 16; ++x) blocks.push_back(VolumeBlock{mortonEncode(x, y, z), 5, 0, solid});
    v.blocks = blocks;
    v.sortBlocks();
    const Octree compressed = build(v, 0), full = build(v, 0, false);
    EXPECT_LT(compressed.storedNodes(), full.storedNodes());
    for (std::uint32_t l = 0; l <= 5; ++l) EXPECT_EQ(compressed.expandLevel(l), full.expandLevel(l)) << l;
    EXPECT_EQ(compressed.expandLevel(5), expandBlocks(v));
    // A rebuild from the compressed tree's finest level gives the uncompressed tree again.
    SparseVolume rebuilt;
    rebuilt.info = v.info;
    rebuilt.blocks = compressed.expandLevel(5);
    const Octree again = build(rebuilt, 0, false);
    for (std::uint32_t l = 0; l <= 5; ++l) EXPECT_EQ(again.expandLevel(l), full.expandLevel(l)) << l;
}

// The tolerance bounds what a render sees (issue 13): under every leaf at level ℓ, each finest
// voxel's density is within ε / (√(tr S)·√3·2^−ℓ) of the leaf's (so a chord of the leaf's voxel
// changes its transmittance by at most ε), and S and albedo within ε. On a noisy constant region
// and on a surface texel (partly empty nodes, which the old relative rule never merged below 1).
TEST(OctreeBuild, ToleranceBoundsTheTransmittanceChangeOfEveryLeaf) {
    auto noisy = halfSpace(5);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> jitter(0.97f, 1.03f);
    for (auto& b : noisy.blocks) b.data.density *= jitter(rng);  // ±3% noise on a constant region
    // A thin noisy sheet (a surface texel: every parent of its voxels is partly empty).
    SparseVolume sheet;
    sheet.info.levels = 5;
    for (std::uint32_t y = 0; y < 32; ++y)
        for (std::uint32_t x = 0; x < 32; ++x) {
            VoxelData d;
            d.density = 2.0f * jitter(rng);
            packIsotropic(d);
            d.albedo = {0.3f, 0.6f, 0.2f};
            sheet.blocks.push_back(VolumeBlock{mortonEncode(x, y, 16), 5, 0, d});
        }
    sheet.sortBlocks();
    for (const SparseVolume* v : {&noisy, &sheet}) {
        for (const double eps : {0.01, 0.1, 0.5}) {
            const Octree exact = build(*v, 0), loose = build(*v, eps);
            OctreeCursor exactCursor(exact);
            EXPECT_LE(loose.storedNodes(), exact.storedNodes());
            // Every leaf above the finest level: the finest voxels below it.
            for (std::uint32_t l = 0; l < 5; ++l)
                for (const auto& leaf : loose.expandLevel(l)) {
                    const auto at = octree::mortonDecode(leaf.key);
                    const Located found = OctreeCursor(loose).locate(int(l), at[0], at[1], at[2]);
                    if (!found.node || found.blockLevel != int(l) || !found.node->isLeaf()) continue;
                    const SggxMatrix S = unpackS(found.node->data);
                    const double h = std::ldexp(1.0, -int(l)), bound = eps / (std::sqrt(S.xx + S.yy + S.zz) * std::sqrt(3.0) * h);
                    const std::uint32_t shift = 5 - l;
                    const auto xyz = octree::mortonDecode(leaf.key);
                    for (std::uint32_t z = 0; z < (1u << shift); ++z)
                        for (std::uint32_t y = 0; y < (1u << shift); ++y)
                            for (std::uint32_t x = 0; x < (1u << shift); ++x) {
                                const Located fine = exactCursor.locate(5, (xyz[0] << shift) + x, (xyz[1] << shift) + y,
                                                                        (xyz[2] << shift) + z);
                                const double rho = fine.node ? double(fine.node->data.density) : 0.0;
                                ASSERT_LE(std::abs(rho - double(found.node->data.density)), bound * (1 + 1e-5))
                                    << "eps " << eps << " level " << l;
                            }
                }
        }
        EXPECT_LT(build(*v, 0.5).storedNodes(), build(*v, 0).storedNodes());
    }
}

TEST(OctreeBuild, BothRulesMeasureAFilterErrorPerLevel) {
    const auto v = randomVolume(4, 800, 6);
    const Octree sggx = build(v, 0, true, FilterRule::Sggx), neyret = build(v, 0, true, FilterRule::Neyret);
    for (std::uint32_t l = 0; l < 4; ++l) {
        EXPECT_GT(sggx.stats[l].filterErrorSamples, 0u);
        EXPECT_GT(sggx.stats[l].filterErrorMean, 0.0);
        EXPECT_GT(neyret.stats[l].filterErrorMean, 0.0);
        EXPECT_NE(sggx.stats[l].filterErrorMean, neyret.stats[l].filterErrorMean);
    }
    EXPECT_EQ(sggx.stats[4].filterErrorSamples, 0u);
    EXPECT_NE(sggx.levels[0][0].data, neyret.levels[0][0].data);
}

TEST(OctreeBuild, PartialRecomputeEqualsAFullRebuild) {
    for (int scenario = 0; scenario < 4; ++scenario) {
        const double tolerance = scenario % 2 ? 0.2 : 0.0;
        const bool withSolid = scenario >= 2;
        // Before: random voxels (and a solid block); after: the region's content replaced.
        auto before = randomVolume(5, 2500, 7);
        VoxelData solid;
        solid.density = 50;
        packIsotropic(solid);
        if (withSolid) before.blocks.push_back(VolumeBlock{mortonEncode(1, 1, 1), 3, kBlockSolid, solid});  // [4,8)³
        // Remove random voxels that overlap the solid block.
        std::vector<VolumeBlock> kept;
        for (const auto& b : before.blocks) {
            const auto c = mortonDecode(b.key);
            if (b.level == 5 && c[0] >= 4 && c[0] < 8 && c[1] >= 4 && c[1] < 8 && c[2] >= 4 && c[2] < 8) continue;
            kept.push_back(b);
        }
        before.blocks = kept;
        before.sortBlocks();
        const VoxelBox region{{6, 5, 3}, {13, 21, 30}};  // cuts through the solid block
        const auto replacement = randomVolume(5, 2500, 8);
        std::vector<VolumeBlock> inside;
        for (const auto& b : replacement.blocks) {
            const auto c = mortonDecode(b.key);
            if (region.contains(c[0], c[1], c[2])) inside.push_back(b);
        }
        // The expected volume: outside the region as before (the solid block's outside part as
        // voxels), inside the replacement.
        SparseVolume after;
        after.info = before.info;
        for (const auto& b : expandBlocks(before)) {
            const auto c = mortonDecode(b.key);
            if (!region.contains(c[0], c[1], c[2])) after.blocks.push_back(b);
        }
        for (const auto& b : inside) after.blocks.push_back(b);
        after.sortBlocks();

        BuildOptions o;
        o.tolerance = tolerance;
        NullProgress progress;
        OctreeBuilder builder(before, o, progress);
        const std::uint64_t fullCount = builder.filteredNodeCount();
        builder.updateRegion(region, inside, progress);
        const std::uint64_t updateCount = builder.filteredNodeCount() - fullCount;
        const Octree updated = builder.compress(progress);
        const Octree rebuilt = buildOctree(after, o, progress);
        for (std::uint32_t l = 0; l <= 5; ++l) EXPECT_EQ(updated.expandLevel(l), rebuilt.expandLevel(l)) << l;
        EXPECT_LT(updateCount, fullCount / 2) << scenario;  // only the ancestors of the region
        if (!withSolid) {
            EXPECT_EQ(updated.levels, rebuilt.levels) << scenario;
            EXPECT_EQ(updated.stats, rebuilt.stats) << scenario;
        } else {
            // The solid block's outside part stays as coarse blocks after the update, where the
            // reference holds it voxel by voxel: the same values (above), stored differently.
            for (std::uint32_t l = 0; l <= 5; ++l) {
                EXPECT_EQ(updated.stats[l].occupiedNodes, rebuilt.stats[l].occupiedNodes);
                EXPECT_NEAR(updated.stats[l].meanDensity, rebuilt.stats[l].meanDensity, 1e-9);
            }
        }
    }
}

}  // namespace
}  // namespace vtex::octree
