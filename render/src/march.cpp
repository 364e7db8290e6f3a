// Level choice and the transmittance march (see texel_march.h).
#include <vtex/render/texel_march.h>

#include "march.h"

#include <cmath>

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

SegmentTransmittance marchTransmittance(const octree::Octree& octree, double tau, const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to, int level, double cutoff) {
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
                                     });
    out.transmittance = std::exp(-opticalDepth);
    return out;
}

}  // namespace vtex::render
