// See density_profile.h.
#include <vtex/octree/density_profile.h>

#include <vtex/octree/chord_transmittance.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtex::octree {
namespace {

// The profile level's mean density per layer of each axis: [0] per x column (over y and z),
// [1] per y column, [2] per z layer (over x and y). One descent of the stored nodes down to
// `level`: a node there, or a leaf above it, stands for a block of s = 2^(level − ℓ) voxels a
// side, which puts s² of its density into each of the s layers it spans on every axis. (A vertical
// walk per column gave these sums up to rounding, with a lookup per voxel: 5–10 ms at level 6, inside the first
// render that marched a profiled level.)
std::array<std::vector<double>, 3> axisMeans(const Octree& tree, int level) {
    const int n = 1 << level;
    tree.loadLevels(std::uint32_t(level));
    std::array<std::vector<double>, 3> means;
    for (auto& m : means) m.assign(std::size_t(n), 0.0);
    struct Item {
        int l;
        std::size_t index;
        std::uint32_t x, y, z;  ///< the node's voxel at its own level
    };
    std::vector<Item> stack{{0, 0, 0, 0, 0}};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const OctreeNode& node = tree.levels[std::size_t(it.l)][it.index];
        if (it.l == level || node.isLeaf()) {
            if (node.data.isEmpty()) continue;
            const std::uint32_t span = 1u << (level - it.l);
            const double mass = double(node.data.density) * double(span) * double(span);
            const std::array<std::uint32_t, 3> first{it.x * span, it.y * span, it.z * span};
            for (std::size_t axis = 0; axis < 3; ++axis)
                for (std::uint32_t k = 0; k < span; ++k) means[axis][first[axis] + k] += mass;
            continue;
        }
        std::size_t child = node.firstChild;
        for (unsigned c = 0; c < 8; ++c)
            if (node.childMask & (1u << c))
                stack.push_back({it.l + 1, child++, 2 * it.x + (c & 1u), 2 * it.y + ((c >> 1) & 1u), 2 * it.z + ((c >> 2) & 1u)});
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

// The mean of p (f per layer, cum its cumulative sums) between heights a ≤ b, in layers, within
// [0, layers]. Summed per layer, not as cum(b) − cum(a): a segment that barely crosses a layer
// boundary (a near-horizontal ray) keeps its precision.
inline double layerMean(const double* f, const double* cum, int layers, double a, double b) {
    const int i = std::min(int(a), layers - 1), j = std::min(int(b), layers - 1);
    if (i == j) return f[i];
    return (f[i] * (double(i + 1) - a) + (cum[j] - cum[i + 1]) + f[j] * (b - double(j))) / (b - a);
}

}  // namespace

LayerMeans measureLayerMeans(const Octree& tree) {
    LayerMeans m;
    if (tree.levels.empty()) return m;
    m.level = std::uint32_t(std::min(DensityProfile::kProfileLevel, int(tree.levelCount()) - 1));
    m.axis = axisMeans(tree, int(m.level));
    return m;
}

DensityProfile::DensityProfile(const Octree& tree) {
    if (tree.levels.empty()) return;
    const int level = std::min(kProfileLevel, int(tree.levelCount()) - 1);
    if (profiledLevels(level) <= 0) return;
    tree.loadLevels(0);
    if (tree.levels[0].empty()) return;
    if (tree.layerMeans && tree.layerMeans->level == std::uint32_t(level)) *this = DensityProfile(*tree.layerMeans);
    else *this = DensityProfile(measureLayerMeans(tree));
}

DensityProfile::DensityProfile(const LayerMeans& layerMeans) {
    const int level = int(layerMeans.level);
    const int profiled = profiledLevels(level);
    const std::array<std::vector<double>, 3>& means = layerMeans.axis;
    mLayers = 1 << level;
    for (int l = 0; l < profiled; ++l) {
        const int per = 1 << (level - l);
        std::vector<double> factor = normalised(means[2], per), cumulative(std::size_t(mLayers) + 1, 0.0);
        for (int k = 0; k < mLayers; ++k) cumulative[std::size_t(k) + 1] = cumulative[std::size_t(k)] + factor[std::size_t(k)];
        mFactor.push_back(std::move(factor));
        mCumulative.push_back(std::move(cumulative));
        // Across: columnsAcross(l) columns a side, each the mean of `group` of the profile
        // level's, and a voxel spans columns >> l of them.
        const int columns = std::min(mLayers, columnsAcross(l)), group = mLayers / columns;
        std::array<std::vector<double>, 2> coarse;
        for (int ax = 0; ax < 2; ++ax) {
            coarse[ax].assign(std::size_t(columns), 0.0);
            for (int k = 0; k < mLayers; ++k) coarse[ax][std::size_t(k / group)] += means[ax][std::size_t(k)] / group;
            coarse[ax] = normalised(coarse[ax], columns >> l);
        }
        mAcross.push_back(std::move(coarse));
    }
}

double DensityProfile::meanFactor(int level, double z0, double z1) const {
    if (!profiles(level)) return 1;
    // In layer widths; NaN heights count as the floor.
    const double n = double(mLayers);
    double a = std::clamp(z0 * n, 0.0, n), b = std::clamp(z1 * n, 0.0, n);
    if (!(a == a)) a = 0;
    if (!(b == b)) b = 0;
    if (a > b) std::swap(a, b);
    return layerMean(mFactor[std::size_t(level)].data(), mCumulative[std::size_t(level)].data(), mLayers, a, b);
}

double DensityProfile::meanFactor(int level, const Vec3& a, const Vec3& b) const {
    const Vec3 d = b - a;
    const double length = d.norm();
    if (!a.allFinite() || !std::isfinite(length)) return meanFactor(level, a.z(), b.z());
    // A point takes the product at it (any direction).
    return Line(*this, level, a, length > 0 ? Vec3(d / length) : Vec3(0, 0, 1)).mean(0, length);
}

// An Amanatides–Woo walk through the columns, x and y wrapping with the tile: within a column
// p_x·p_y is constant and p's mean over the piece's heights comes from the cumulative sums.
DensityProfile::Line::Line(const DensityProfile& profile, int level, const Vec3& origin, const Vec3& dir)
    : mOrigin(origin), mDir(dir) {
    if (!profile.profiles(level)) return;
    const std::array<std::vector<double>, 2>& across = profile.mAcross[std::size_t(level)];
    mFactor = profile.mFactor[std::size_t(level)].data();
    mCumulative = profile.mCumulative[std::size_t(level)].data();
    mAcross[0] = across[0].data();
    mAcross[1] = across[1].data();
    mLayers = profile.mLayers;
    mZ0 = origin.z() * mLayers;
    mDz = dir.z() * mLayers;
    mMask = std::int64_t(across[0].size()) - 1;
    const double n = double(across[0].size());
    mColumnsPerUnit = (std::abs(dir.x()) + std::abs(dir.y())) * n;
    mLongest = kMaxAcrossTiles * n / std::max(mColumnsPerUnit, 1e-300);
    for (std::size_t k = 0; k < 2; ++k) {
        mStep[k] = dir[int(k)] > 0 ? 1 : -1;
        mInc[k] = dir[int(k)] != 0 ? 1 / (std::abs(dir[int(k)]) * n) : std::numeric_limits<double>::infinity();
    }
}

void DensityProfile::Line::start(double s) {
    const double n = double(mMask + 1);
    for (std::size_t k = 0; k < 2; ++k) {
        // The point's place in its tile (periodic), in columns: no overflow however far it is.
        const double x = mOrigin[int(k)] + s * mDir[int(k)];
        const double u = std::isfinite(x) ? (x - std::floor(x)) * n : 0.0;
        mCell[k] = std::min(std::int64_t(u), mMask);
        const double boundary = mStep[k] > 0 ? double(mCell[k] + 1) : double(mCell[k]);
        mNext[k] = mDir[int(k)] != 0 ? s + (boundary - u) / (mDir[int(k)] * n) : std::numeric_limits<double>::infinity();
    }
    mAt = s;
}

bool DensityProfile::Line::advanceTo(double s) {
    if (!(s >= mAt) || (s - mAt) * mColumnsPerUnit > kRestartColumns) return false;
    // Within kRestartColumns columns, up to rounding: the cap only guards against it.
    for (int steps = 0; steps < int(kRestartColumns) + 8; ++steps) {
        const std::size_t k = nextAxis();
        if (mNext[k] > s) {
            mAt = s;
            return true;
        }
        cross(k);
    }
    return false;
}

// p's mean between the line's heights at s0 and s1 (finite), clamped to the texel.
inline double DensityProfile::Line::heightMean(double s0, double s1) const {
    const double top = double(mLayers);
    double a = std::clamp(mZ0 + s0 * mDz, 0.0, top), b = std::clamp(mZ0 + s1 * mDz, 0.0, top);
    if (a > b) std::swap(a, b);
    return layerMean(mFactor, mCumulative, mLayers, a, b);
}

inline double DensityProfile::Line::across() const {
    return mAcross[0][std::size_t(mCell[0] & mMask)] * mAcross[1][std::size_t(mCell[1] & mMask)];
}

double DensityProfile::Line::mean(double s0, double s1) {
    if (!mFactor) return 1;
    // A non-finite s (no march passes one) takes the floor's layer, as a NaN height does in
    // meanFactor(level, z0, z1).
    if (!std::isfinite(s0) || !std::isfinite(s1)) return mFactor[0];
    if (s1 < s0) std::swap(s0, s1);
    if (!advanceTo(s0)) start(s0);
    // The walk's end: the whole segment, or its first kMaxAcrossTiles tiles across.
    const double end = std::min(s1, s0 + mLongest);
    if (!(end > s0)) return across() * heightMean(s0, s0);
    double sum = 0, s = s0, pxy = across();
    // At most (kMaxAcrossTiles + 2) tiles of column crossings; the bound only guards against rounding.
    const std::size_t maxSteps = std::size_t((kMaxAcrossTiles + 4) * double(mMask + 1)) + 8;
    for (std::size_t steps = 0; steps < maxSteps; ++steps) {
        const std::size_t k = nextAxis();
        if (!(mNext[k] < end)) break;
        const double t = std::max(mNext[k], s);
        sum += pxy * heightMean(s, t) * (t - s);
        s = t;
        cross(k);
        pxy = across();
    }
    if (end > s) sum += pxy * heightMean(s, end) * (end - s);
    mAt = end;
    return sum / (end - s0);
}

}  // namespace vtex::octree
