// The block march's incremental lookup (march.h, LocateCursor) against the lookup from the root.
#include "fixtures.h"
#include "../../render/src/march.h"

#include <gtest/gtest.h>

#include <random>

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
            const detail::Located expected = detail::locate(*tree, level, wrap(q.x()), wrap(q.y()), z);
            EXPECT_EQ(expected.node, &node);
            ++compared;
            return true;
        });
    }
    EXPECT_GT(compared, 1000);
}
