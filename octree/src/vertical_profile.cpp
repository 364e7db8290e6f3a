// See vertical_profile.h.
#include <vtex/octree/vertical_profile.h>

#include <vtex/octree/chord_transmittance.h>

#include <algorithm>

namespace vtex::octree {
namespace {

// The profile level's mean density per layer (over x and y), from one vertical walk through the
// middle of each of its columns.
std::vector<double> layerMeans(const Octree& tree, int level) {
    const int n = 1 << level;
    std::vector<double> layers(std::size_t(n), 0.0);
    for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y) {
            const Vec3 a((x + 0.5) / n, (y + 0.5) / n, 0), b((x + 0.5) / n, (y + 0.5) / n, 1);
            forEachVoxelOnSegment(tree, std::uint32_t(level), a, b, [&](const OctreeNode& node, double t0, double t1) {
                const int k = std::clamp(int(0.5 * (t0 + t1) * n), 0, n - 1);
                layers[std::size_t(k)] += double(node.data.density) * (t1 - t0) * n;
            });
        }
    for (double& m : layers) m /= double(n) * double(n);
    return layers;
}

}  // namespace

VerticalProfile::VerticalProfile(const Octree& tree) {
    if (tree.levels.empty()) return;
    const int level = std::min(kProfileLevel, int(tree.levelCount()) - 1);
    const int profiled = profiledLevels(level);
    if (profiled <= 0) return;
    tree.loadLevels(std::uint32_t(level));
    if (tree.levels[0].empty()) return;
    const std::vector<double> layers = layerMeans(tree, level);
    mLayers = 1 << level;
    for (int l = 0; l < profiled; ++l) {
        const int per = 1 << (level - l);
        std::vector<double> factor(std::size_t(mLayers), 1.0), cumulative(std::size_t(mLayers) + 1, 0.0);
        for (int first = 0; first < mLayers; first += per) {
            double mean = 0;
            for (int k = first; k < first + per; ++k) mean += layers[std::size_t(k)] / per;
            if (mean > 0)
                for (int k = first; k < first + per; ++k) factor[std::size_t(k)] = layers[std::size_t(k)] / mean;
        }
        for (int k = 0; k < mLayers; ++k) cumulative[std::size_t(k) + 1] = cumulative[std::size_t(k)] + factor[std::size_t(k)];
        mFactor.push_back(std::move(factor));
        mCumulative.push_back(std::move(cumulative));
    }
}

double VerticalProfile::meanFactor(int level, double z0, double z1) const {
    if (!profiles(level)) return 1;
    const std::vector<double>& f = mFactor[std::size_t(level)];
    const std::vector<double>& cum = mCumulative[std::size_t(level)];
    // In layer widths; NaN heights count as the floor.
    const double n = double(mLayers);
    double a = std::clamp(z0 * n, 0.0, n), b = std::clamp(z1 * n, 0.0, n);
    if (!(a == a)) a = 0;
    if (!(b == b)) b = 0;
    if (a > b) std::swap(a, b);
    const int i = std::min(int(a), mLayers - 1), j = std::min(int(b), mLayers - 1);
    if (i == j) return f[std::size_t(i)];
    // Summed per layer, not as cum(b) − cum(a): a segment that barely crosses a layer boundary
    // (a near-horizontal ray) keeps its precision.
    const double inside = cum[std::size_t(j)] - cum[std::size_t(i) + 1];
    return (f[std::size_t(i)] * (double(i + 1) - a) + inside + f[std::size_t(j)] * (b - double(j))) / (b - a);
}

}  // namespace vtex::octree
