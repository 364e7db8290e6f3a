// See density_profile.h.
#include <vtex/octree/density_profile.h>

#include <vtex/octree/chord_transmittance.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtex::octree {
namespace {

// The profile level's mean density per layer of each axis: [0] per x column (over y and z),
// [1] per y column, [2] per z layer (over x and y), from one vertical walk through the middle of
// each of its columns.
std::array<std::vector<double>, 3> axisMeans(const Octree& tree, int level) {
    const int n = 1 << level;
    std::array<std::vector<double>, 3> means;
    for (auto& m : means) m.assign(std::size_t(n), 0.0);
    for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y) {
            const Vec3 a((x + 0.5) / n, (y + 0.5) / n, 0), b((x + 0.5) / n, (y + 0.5) / n, 1);
            forEachVoxelOnSegment(tree, std::uint32_t(level), a, b, [&](const OctreeNode& node, double t0, double t1) {
                const int k = std::clamp(int(0.5 * (t0 + t1) * n), 0, n - 1);
                const double mass = double(node.data.density) * (t1 - t0) * n;  // in layer units
                means[0][std::size_t(x)] += mass;
                means[1][std::size_t(y)] += mass;
                means[2][std::size_t(k)] += mass;
            });
        }
    for (auto& m : means)
        for (double& v : m) v /= double(n) * double(n);
    return means;
}

// Each layer's mean over the mean of the `per` layers of the voxel it lies in (1 where they are
// all empty).
std::vector<double> normalised(const std::vector<double>& means, int per) {
    std::vector<double> factor(means.size(), 1.0);
    for (std::size_t first = 0; first < means.size(); first += std::size_t(per)) {
        double mean = 0;
        for (std::size_t k = first; k < first + std::size_t(per); ++k) mean += means[k] / per;
        if (mean > 0)
            for (std::size_t k = first; k < first + std::size_t(per); ++k) factor[k] = means[k] / mean;
    }
    return factor;
}

}  // namespace

DensityProfile::DensityProfile(const Octree& tree) {
    if (tree.levels.empty()) return;
    const int level = std::min(kProfileLevel, int(tree.levelCount()) - 1);
    const int profiled = profiledLevels(level);
    if (profiled <= 0) return;
    tree.loadLevels(std::uint32_t(level));
    if (tree.levels[0].empty()) return;
    const std::array<std::vector<double>, 3> means = axisMeans(tree, level);
    mLayers = 1 << level;
    for (int l = 0; l < profiled; ++l) {
        const int per = 1 << (level - l);
        std::vector<double> factor = normalised(means[2], per), cumulative(std::size_t(mLayers) + 1, 0.0);
        for (int k = 0; k < mLayers; ++k) cumulative[std::size_t(k) + 1] = cumulative[std::size_t(k)] + factor[std::size_t(k)];
        mFactor.push_back(std::move(factor));
        mCumulative.push_back(std::move(cumulative));
        if (l < profiledAcrossLevels(level)) {
            // mLayers ≥ kMinColumns ≥ kColumns here: each of the profile's columns is the mean of
            // `group` of the profile level's, and a voxel spans per / group ≥ 1 of them.
            const int group = mLayers / kColumns;
            std::array<std::vector<double>, 2> coarse;
            for (int ax = 0; ax < 2; ++ax) {
                coarse[ax].assign(std::size_t(kColumns), 0.0);
                for (int k = 0; k < mLayers; ++k) coarse[ax][std::size_t(k / group)] += means[ax][std::size_t(k)] / group;
                coarse[ax] = normalised(coarse[ax], per / group);
            }
            mAcross.push_back(std::move(coarse));
        }
    }
}

double DensityProfile::meanFactor(int level, double z0, double z1) const {
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

double DensityProfile::meanFactor(int level, const Vec3& a, const Vec3& b) const {
    if (!profilesAcross(level)) return meanFactor(level, a.z(), b.z());
    const Vec3 d = b - a;
    if (!a.allFinite() || !d.allFinite()) return meanFactor(level, a.z(), b.z());
    const std::array<std::vector<double>, 2>& across = mAcross[std::size_t(level)];
    const double n = double(kColumns);
    // The walk's end: the whole segment, or its first kMaxAcrossTiles tiles across.
    const double end = std::min(1.0, kMaxAcrossTiles / std::max(std::abs(d.x()) + std::abs(d.y()), 1e-300));
    // An Amanatides–Woo walk through the columns along t ∈ [0, end], x and y wrapping with the
    // tile: within a column p_x·p_y is constant and p's mean over the piece's heights comes from
    // the cumulative sums.
    std::array<std::int64_t, 2> cell;
    std::array<double, 2> next, inc;
    std::array<int, 2> step;
    for (int k = 0; k < 2; ++k) {
        // The start's place in its tile (periodic), in columns: no overflow however far a is.
        const double u = (a[k] - std::floor(a[k])) * n;
        cell[std::size_t(k)] = std::min(std::int64_t(u), std::int64_t(kColumns) - 1);
        step[std::size_t(k)] = d[k] > 0 ? 1 : -1;
        inc[std::size_t(k)] = d[k] != 0 ? 1 / (std::abs(d[k]) * n) : std::numeric_limits<double>::infinity();
        const double boundary = d[k] > 0 ? double(cell[std::size_t(k)] + 1) : double(cell[std::size_t(k)]);
        next[std::size_t(k)] = d[k] != 0 ? (boundary - u) / (d[k] * n) : std::numeric_limits<double>::infinity();
    }
    const auto wrap = [m = std::int64_t(kColumns)](std::int64_t i) { return std::size_t(((i % m) + m) % m); };
    const auto product = [&](double t0, double t1) {
        return across[0][wrap(cell[0])] * across[1][wrap(cell[1])] * meanFactor(level, a.z() + t0 * d.z(), a.z() + t1 * d.z());
    };
    double sum = 0, t = 0;
    // At most (kMaxAcrossTiles + 2)·n column crossings; the bound only guards against rounding.
    const std::size_t maxSteps = std::size_t((kMaxAcrossTiles + 4) * n) + 8;
    for (std::size_t steps = 0; steps < maxSteps && t < end; ++steps) {
        const std::size_t k = next[0] <= next[1] ? 0 : 1;
        const double t1 = std::clamp(next[k], t, end);
        sum += product(t, t1) * (t1 - t);
        t = t1;
        cell[k] += step[k];
        next[k] += inc[k];
    }
    // end > 0, so t > 0 (a point, d = 0, took the product at it once).
    return t > 0 ? sum / t : product(0, 0);
}

}  // namespace vtex::octree
