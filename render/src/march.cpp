// Level choice and the transmittance march (see texel_march.h).
#include <vtex/render/texel_march.h>

#include "march.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vtex::render {

LevelChoice chooseLevel(double width, double lodBias, int maxLevel) {
    LevelChoice c;
    double level = double(maxLevel);
    if (std::isfinite(width) && width > 0) level = -std::log2(width);
    if (std::isnan(width) || width == INFINITY) level = 0;
    level = std::clamp(level - lodBias, 0.0, double(std::max(maxLevel, 0)));
    c.level = level;
    c.coarse = int(std::floor(level));
    c.fine = std::min(c.coarse + 1, maxLevel);
    c.fineWeight = c.fine == c.coarse ? 0.0 : level - c.coarse;
    return c;
}

EmptySpace emptySpace(const octree::Octree& tree) {
    EmptySpace out;
    if (tree.levels.empty() || tree.levels[0].empty()) return out;
    const int deepest = std::min(int(tree.levels.size()) - 1, EmptySpace::kMaxLevel);
    out.levels.resize(std::size_t(deepest + 1));
    constexpr int kFar = EmptySpace::kCap;
    for (int l = 0; l <= deepest; ++l) {
        const int n = 1 << l;
        const auto at = [n](int x, int y, int z) { return (std::size_t(z) * std::size_t(n) + std::size_t(y)) * std::size_t(n) + std::size_t(x); };
        std::vector<std::uint8_t> d(std::size_t(n) * std::size_t(n) * std::size_t(n), std::uint8_t(kFar));
        detail::LocateCursor cursor;
        for (int z = 0; z < n; ++z)
            for (int y = 0; y < n; ++y)
                for (int x = 0; x < n; ++x)
                    if (cursor.find(tree, l, std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)).node) d[at(x, y, z)] = 0;
        // The L∞ distance is separable: along x, then the max-min along y, then along z, each a
        // search outward that stops once the offset reaches the best distance found (x and y
        // wrap, z does not).
        std::vector<std::uint8_t> line(static_cast<std::size_t>(n));
        const auto pass = [&](int axis) {
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    const auto index = [&](int i) {
                        return axis == 0 ? at(i, a, b) : axis == 1 ? at(a, i, b) : at(a, b, i);
                    };
                    for (int i = 0; i < n; ++i) line[std::size_t(i)] = d[index(i)];
                    for (int i = 0; i < n; ++i) {
                        int best = line[std::size_t(i)];
                        for (int k = 1; k < best && k < n; ++k) {
                            for (const int j : {i - k, i + k}) {
                                int w = j;
                                if (axis < 2) w = ((j % n) + n) % n;
                                else if (j < 0 || j >= n) continue;
                                best = std::min(best, std::max(k, int(line[std::size_t(w)])));
                            }
                        }
                        d[index(i)] = std::uint8_t(std::min(best, kFar));
                    }
                }
        };
        pass(0);
        pass(1);
        pass(2);
        out.levels[std::size_t(l)] = std::move(d);
    }
    return out;
}

SegmentTransmittance marchTransmittance(const octree::Octree& octree, double tau, const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to, int level, double cutoff, const EmptySpace* empty) {
    SegmentTransmittance out;
    const Eigen::Vector3d delta = to - from;
    const double length = delta.norm();
    if (!(length > 0)) return out;
    const Eigen::Vector3d dir = delta / length;
    double opticalDepth = 0;
    const double maxDepth = cutoff > 0 ? -std::log(cutoff) : INFINITY;
    out.blocks = detail::marchBlocks(octree, level, from, dir, length,
                                     [&](const octree::OctreeNode& node, double, double ds) {
                                         opticalDepth += tau * node.data.density * detail::normalizedArea(voxelS(node.data), dir) * ds;
                                         return opticalDepth < maxDepth;
                                     },
                                     empty ? empty->level(level) : nullptr);
    out.transmittance = std::exp(-opticalDepth);
    return out;
}

}  // namespace vtex::render
