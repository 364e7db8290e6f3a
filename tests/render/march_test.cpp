// The marches of march.h: the block march (one octree cursor per march, reusing its path) against
// a lookup from the root for every block, and the dense-grid walk against the block march.
#include "fixtures.h"
#include "../../render/src/march.h"

#include <gtest/gtest.h>

#include <vtex/octree/cursor.h>
#include <vtex/octree/voxel.h>
#include <vtex/render/texel_march.h>

#include <algorithm>
#include <iostream>
#include <random>
#include <vector>

using namespace vtex::render;
using namespace vtex::render::test;

TEST(March, CursorFindsWhatTheLookupFromTheRootFinds) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    const int levels = 5, n = 1 << levels;
    std::vector<float> column(std::size_t(n * n));
    for (auto& c : column) c = u(rng) < 0.4f ? u(rng) : 0.0f;
    const auto tree = makeOctree(levels, [&](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        if (float(z) / float(n) >= column[std::size_t(y * n + x)]) return std::nullopt;
        return sphereVoxel(1.0f + float((x + 3 * y + 5 * z) % 4));
    }, true);
    std::uniform_real_distribution<double> p(-0.5, 1.5);
    int compared = 0;
    for (int ray = 0; ray < 300; ++ray) {
        const Eigen::Vector3d p0(p(rng), p(rng), u(rng));
        Eigen::Vector3d dir(p(rng) - 0.5, p(rng) - 0.5, p(rng) - 0.5);
        if (ray % 7 == 0) dir = Eigen::Vector3d(1, 0, 0);  // axis-aligned: block faces hit exactly
        dir.normalize();
        const int level = ray % (levels + 1);
        detail::marchBlocks(*tree, level, p0, dir, 1.7, [&](const vtex::octree::OctreeNode& node, double s, double ds) {
            const Eigen::Vector3d q = p0 + (s + 0.5 * ds) * dir;
            const std::int64_t m = std::int64_t(1) << level;
            const auto wrap = [m](double c) { return std::uint32_t(((std::int64_t(std::floor(c * double(m))) % m) + m) % m); };
            const auto z = std::uint32_t(std::clamp<std::int64_t>(std::int64_t(std::floor(q.z() * double(m))), 0, m - 1));
            const vtex::octree::Located expected = vtex::octree::OctreeCursor(*tree).locate(level, wrap(q.x()), wrap(q.y()), z);
            EXPECT_EQ(expected.node, &node);
            ++compared;
            return true;
        });
    }
    EXPECT_GT(compared, 1000);
}

// The grid's table-driven Morton index is the octree's key, for every voxel of the deepest grid.
TEST(March, GridMortonIndexIsTheOctreeKey) {
    std::uint64_t mismatches = 0;
    for (std::uint32_t z = 0; z < 256; ++z)
        for (std::uint32_t y = 0; y < 256; ++y)
            for (std::uint32_t x = 0; x < 256; ++x)
                mismatches += LevelGrid::morton(x, y, z) != vtex::octree::mortonEncode(x, y, z);
    EXPECT_EQ(mismatches, 0u);
}

// The empty-space distances of levels 0…6 (march.cpp's bit-parallel transform) at every voxel,
// against the definition: the Chebyshev distance to the nearest non-empty voxel of the level,
// x and y wrapping (the texel tiles), z not, capped at kCap. Scattered voxels, some on the faces
// of the texel so that the wrap and the z border matter, and one 6-voxel clump.
TEST(March, EmptySpaceDistancesAreExactAtEveryVoxelUpToLevel6) {
    const int levels = 6, last = (1 << levels) - 1;
    const auto tree = makeOctree(levels, [&](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        const bool border = (x == 0 && y == 5 && z == 10) || (x == 33 && y == last && z == 2) || (x == 60 && y == 61 && z == last) ||
                            (x == 7 && y == 0 && z == 0);
        const bool clump = x >= 20 && x < 23 && y >= 44 && y < 46 && z == 12;
        const std::uint32_t h = std::uint32_t(x) * 73856093u ^ std::uint32_t(y) * 19349663u ^ std::uint32_t(z) * 83492791u;
        // Scattered below z = 16 only: the layers half way up to the top row are beyond the cap.
        if (!border && !clump && (z >= 16 || (h * 2654435761u) % 500u != 0)) return std::nullopt;
        return sphereVoxel(1.0f);
    });
    const MarchVolume volume(tree);
    constexpr int cap = LevelGrid::kCap;
    for (int l = 0; l <= levels; ++l) {
        const int m = 1 << l;
        std::vector<std::array<int, 3>> occupied;
        for (int z = 0; z < m; ++z)
            for (int y = 0; y < m; ++y)
                for (int x = 0; x < m; ++x)
                    if (vtex::octree::OctreeCursor(*tree).locate(l, std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)).node)
                        occupied.push_back({x, y, z});
        ASSERT_FALSE(occupied.empty());
        const LevelGrid* grid = volume.grid(l);
        ASSERT_NE(grid, nullptr);
        const auto cyclic = [m](int a, int b) { const int d = std::abs(a - b); return std::min(d, m - d); };
        int mismatches = 0, capped = 0;
        for (int z = 0; z < m; ++z)
            for (int y = 0; y < m; ++y)
                for (int x = 0; x < m; ++x) {
                    int best = cap;
                    for (const auto& o : occupied) best = std::min(best, std::max({cyclic(x, o[0]), cyclic(y, o[1]), std::abs(z - o[2])}));
                    capped += best == cap;
                    const int d = grid->distance(std::uint32_t(x), std::uint32_t(y), std::uint32_t(z));
                    if (d != best && ++mismatches <= 5) {
                        ADD_FAILURE() << "level " << l << " (" << x << ", " << y << ", " << z << "): " << d << " != " << best;
                    }
                }
        EXPECT_EQ(mismatches, 0) << "level " << l;
        if (l == levels) {
            EXPECT_GT(capped, 0);  // the cap is reached somewhere, so it is tested too
        }
    }
}

// The dense-grid walk (marchGrid, with its empty-space leaps) visits the same voxels over the
// same intervals, bit for bit, as the block march through the octree, once consecutive visits of
// one node are merged; the empty-space distances are exact up to level 6 and lower bounds
// beyond.
TEST(March, GridWalkVisitsWhatTheBlockMarchVisits) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0, 1);
    const int levels = 7;
    const auto tree = makeOctree(levels, [&](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        // Scattered voxels (about one in 300, like leaves), and a solid slab whose octree leaves
        // stand for blocks: the octree's empty blocks are small, the runs along a ray long.
        if (z >= 100 && z < 112 && x < 64) return sphereVoxel(2.0f);
        const std::uint32_t h = std::uint32_t(x) * 73856093u ^ std::uint32_t(y) * 19349663u ^ std::uint32_t(z) * 83492791u;
        if ((h * 2654435761u) % 300u != 0) return std::nullopt;
        return sphereVoxel(1.0f + float((x + y + z) % 3));
    }, true);
    const MarchVolume volume(tree);
    // The distances against a brute-force search: equal up to level 6, never above it beyond.
    for (int probe = 0; probe < 240; ++probe) {
        const int l = probe % (levels + 1), m = 1 << l;
        const int x = int(u(rng) * float(m)) % m, y = int(u(rng) * float(m)) % m, z = int(u(rng) * float(m)) % m;
        constexpr int cap = LevelGrid::kCap;
        int best = cap;
        for (int dz = -cap; dz <= cap; ++dz)
            for (int dy = -cap; dy <= cap; ++dy)
                for (int dx = -cap; dx <= cap; ++dx) {
                    const int zz = z + dz;
                    if (zz < 0 || zz >= m) continue;
                    const auto wrap = [m](int c) { return std::uint32_t(((c % m) + m) % m); };
                    if (vtex::octree::OctreeCursor(*tree).locate(l, wrap(x + dx), wrap(y + dy), std::uint32_t(zz)).node)
                        best = std::min(best, std::max({std::abs(dx), std::abs(dy), std::abs(dz)}));
                }
        const LevelGrid* grid = volume.grid(l);
        ASSERT_NE(grid, nullptr);
        const int d = grid->distance(std::uint32_t(x), std::uint32_t(y), std::uint32_t(z));
        if (l <= 6) {
            EXPECT_EQ(d, best) << l << " " << x << " " << y << " " << z;
        } else {
            EXPECT_TRUE(d <= best && (d == 0) == (best == 0)) << l << " " << x << " " << y << " " << z << ": " << d << " " << best;
        }
    }
    std::uniform_real_distribution<double> p(-0.5, 1.5);
    std::uint64_t gridSteps = 0, blockSteps = 0;
    int compared = 0;
    for (int ray = 0; ray < 400; ++ray) {
        const Eigen::Vector3d p0(p(rng), p(rng), u(rng));
        Eigen::Vector3d dir(p(rng) - 0.5, p(rng) - 0.5, p(rng) - 0.5);
        if (ray % 7 == 0) dir = Eigen::Vector3d(1, 0, 0);
        if (ray % 11 == 0) dir = Eigen::Vector3d(0.6, 0.8, 0);
        if (ray % 13 == 0) dir = Eigen::Vector3d(0, 0, ray % 2 ? 1 : -1);
        dir.normalize();
        const int level = 1 + ray % levels;  // level 0 is one node, which wraps onto itself
        // Inside the texel's height, as the renderer's spans are.
        double length = 2.3;
        if (dir.z() > 0) length = std::min(length, (1 - p0.z()) / dir.z());
        if (dir.z() < 0) length = std::min(length, -p0.z() / dir.z());
        struct Visit {
            GridVoxel voxel;
            double s, ds;
        };
        std::vector<Visit> blocks, walk;
        const vtex::octree::OctreeNode* last = nullptr;
        blockSteps += detail::marchBlocks(*tree, level, p0, dir, length, [&](const vtex::octree::OctreeNode& node, double s, double ds) {
            if (&node == last && blocks.back().s + blocks.back().ds == s) blocks.back().ds = s + ds - blocks.back().s;
            else blocks.push_back({gridVoxel(node.data), s, ds});
            last = &node;
            return true;
        });
        gridSteps += detail::marchGrid(*volume.grid(level), p0, dir, length, [&](const GridVoxel& voxel, double s, double ds) {
            walk.push_back({voxel, s, ds});
            return true;
        });
        ASSERT_EQ(blocks.size(), walk.size()) << ray;
        for (std::size_t i = 0; i < blocks.size(); ++i) {
            EXPECT_EQ(blocks[i].voxel.density, walk[i].voxel.density) << ray << " " << i;
            EXPECT_EQ(blocks[i].voxel.s.quadratic(dir), walk[i].voxel.s.quadratic(dir)) << ray << " " << i;
            EXPECT_EQ(blocks[i].s, walk[i].s) << ray << " " << i;
            EXPECT_NEAR(blocks[i].s + blocks[i].ds, walk[i].s + walk[i].ds, 1e-15) << ray << " " << i;
            ++compared;
        }
    }
    std::cout << "grid walk: " << gridSteps << " steps, block march: " << blockSteps << " (" << compared << " visits compared)\n";
    EXPECT_GT(compared, 300);
}
