// The builder's output bytes, pinned (issue 13): the build was sped up without changing a byte of
// any .vto. Each case serialises the tree of a seeded volume and compares a digest of the bytes
// with the one the builder of 2cb2550 (before the speed-up) gave; a change of any filtered node,
// statistic, compression decision or filter-error sample fails here, not only in the bench's cmp.
// The cases cover both rules, tolerance 0 (the default: only exact constant regions merge) and
// tolerances that merge partly empty nodes, solid blocks above the finest level, and filter
// errors measured on all nodes and on a sample.
#include "random_volume.h"

#include <vtex/octree/octree.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>

namespace vtex::octree {
namespace {

// FNV-1a, 64 bits: explicit, so the literals below mean the same on every standard library.
std::uint64_t fnv1a(const std::string& bytes) {
    std::uint64_t h = 14695981039346656037ull;
    for (const char c : bytes) {
        h ^= std::uint8_t(c);
        h *= 1099511628211ull;
    }
    return h;
}

// Random surface-like voxels, a solid block at level 2, a constant slab of finest voxels that
// collapses exactly, and a noisy slab that collapses only within a tolerance.
SparseVolume goldenVolume(unsigned seed) {
    SparseVolume v = test::randomVolume(5, 2500, seed);
    std::vector<VolumeBlock> blocks;
    for (const auto& b : v.blocks)
        if (mortonDecode(b.key)[2] < 16) blocks.push_back(b);
    VoxelData solid;
    solid.density = 40;
    packIsotropic(solid);
    solid.albedo = {0.2f, 0.3f, 0.4f};
    for (std::uint32_t y = 0; y < 4; ++y)
        for (std::uint32_t x = 0; x < 2; ++x) blocks.push_back(VolumeBlock{mortonEncode(x, y, 3), 2, kBlockSolid, solid});
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> jitter(0.97f, 1.03f);
    for (std::uint32_t z = 16; z < 24; ++z)
        for (std::uint32_t y = 0; y < 16; ++y)
            for (std::uint32_t x = 0; x < 32; ++x) {
                VoxelData d = solid;
                if (x >= 16) d.density *= jitter(rng);
                blocks.push_back(VolumeBlock{mortonEncode(x, y, z), 5, 0, d});
            }
    v.blocks = blocks;
    v.sortBlocks();
    return v;
}

std::uint64_t digest(const SparseVolume& v, FilterRule rule, double tolerance, std::uint64_t samples) {
    BuildOptions o;
    o.rule = rule;
    o.tolerance = tolerance;
    o.filterErrorSamples = samples;
    NullProgress progress;
    // The levels and statistics as the goldens were taken; the density profile's layer means,
    // stored since (the PROF section), are measured from those levels (DensityProfile's tests).
    Octree tree = buildOctree(v, o, progress);
    tree.layerMeans.reset();
    return fnv1a(serializeVto(tree));
}

TEST(OctreeBuildGolden, BytesAreThoseOfTheBuilderBeforeTheSpeedUp) {
    struct Case {
        unsigned seed;
        FilterRule rule;
        double tolerance;
        std::uint64_t samples;
        std::uint64_t expected;
    };
    const Case cases[] = {
        {11, FilterRule::Sggx, 0.0, 4096, 1715724131158229995ull},
        {11, FilterRule::Neyret, 0.0, 4096, 12266634071261967169ull},
        {11, FilterRule::Sggx, 0.05, 64, 13715959774248535658ull},
        {11, FilterRule::Neyret, 0.5, 0, 1455237142244164667ull},
        {12, FilterRule::Sggx, 0.01, 0, 10845445302175581445ull},
        {12, FilterRule::Sggx, 2.0, 100, 12096481552261991693ull},
    };
    for (const Case& c : cases)
        EXPECT_EQ(digest(goldenVolume(c.seed), c.rule, c.tolerance, c.samples), c.expected)
            << "seed " << c.seed << " rule " << filterRuleName(c.rule) << " tolerance " << c.tolerance << " samples "
            << c.samples;
}

}  // namespace
}  // namespace vtex::octree
