// Filtering of micro-primitives, Neyret 1994 §3.3.2 ("the mean ellipsoid is the one whose
// inverse quadratic form is the mean of the inverse quadratic forms", weighted by density),
// and the SGGX alternative (Heitz et al. 2015, §5: linear filtering of S).
#include <vtex/octree/filtering.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>

namespace vtex::octree {
namespace {

void checkSizes(std::size_t children, std::size_t weights) {
    if (children != weights)
        throw std::invalid_argument("filtering: one weight per child ellipsoid");
}

bool usableWeight(double w) { return w > 0 && std::isfinite(w); }

// own[p] ← (own[p] − mixture[p]/totalWeight)², for filterError: also compiled for AVX2 and
// AVX-512 and chosen at load time, as the sums before it are (Ellipsoid's
// accumulateNormalizedNormalDistribution): a division per direction, eight lanes at a time
// where the processor has them. A difference and a square: nothing an FMA instruction could
// contract, so every version gives the same bits.
#if defined(__x86_64__) && defined(__has_attribute)
#if __has_attribute(target_clones) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
#endif
void squaredDifferences(double* own, const double* mixture, double totalWeight, std::size_t n) {
    for (std::size_t p = 0; p < n; ++p) {
        const double difference = own[p] - mixture[p] / totalWeight;
        own[p] = difference * difference;
    }
}

}  // namespace

std::optional<Ellipsoid> filterEllipsoids(std::span<const Ellipsoid> children,
                                          std::span<const double> weights, FilterRule rule) {
    checkSizes(children.size(), weights.size());
    // Each child enters with unit mean apparent area, so its weight is its density alone.
    std::vector<Mat3> forms(children.size(), Mat3::Zero());
    for (std::size_t i = 0; i < children.size(); ++i)
        if (usableWeight(weights[i]))
            forms[i] = rule == FilterRule::Neyret ? children[i].normalized(Normalization::ThreeAxis).M()
                                                  : children[i].normalized(Normalization::Exact).S();
    return filterForms(forms, weights, rule);
}

namespace {

// The weighted mean of the forms both rules average; empty for no positive weight.
std::optional<Mat3> meanForm(std::span<const Mat3> forms, std::span<const double> weights) {
    checkSizes(forms.size(), weights.size());
    Mat3 sum = Mat3::Zero();
    double totalWeight = 0;
    for (std::size_t i = 0; i < forms.size(); ++i) {
        if (!usableWeight(weights[i])) continue;
        sum += weights[i] * forms[i];
        totalWeight += weights[i];
    }
    if (!(totalWeight > 0)) return std::nullopt;
    sum /= totalWeight;
    return sum;
}

}  // namespace

std::optional<Ellipsoid> filterForms(std::span<const Mat3> forms, std::span<const double> weights,
                                     FilterRule rule) {
    const auto mean = meanForm(forms, weights);
    if (!mean) return std::nullopt;
    const auto result = rule == FilterRule::Neyret ? Ellipsoid::fromM(*mean) : Ellipsoid::fromS(*mean);
    if (!result) return std::nullopt;
    return result->normalized(Normalization::Exact);
}

std::optional<primitive::PackedPrimitive> filterFormsPacked(std::span<const Mat3> forms,
                                                            std::span<const double> weights, FilterRule rule) {
    // filterForms's steps on the shape alone: normalised as it normalises, then packed as
    // packEllipsoid packs (which normalises again, as it does for the Ellipsoid).
    const auto mean = meanForm(forms, weights);
    if (!mean) return std::nullopt;
    const auto shape = rule == FilterRule::Neyret ? Ellipsoid::shapeFromM(*mean) : Ellipsoid::shapeFromS(*mean);
    if (!shape) return std::nullopt;
    return primitive::pack(shape->normalized());
}

std::optional<Mat3> meanFilterForm(std::span<const Mat3> forms, std::span<const double> weights) {
    return meanForm(forms, weights);
}

void packSggxMeans(std::span<const Mat3> means, std::span<std::optional<primitive::PackedPrimitive>> out) {
    if (means.size() != out.size()) throw std::invalid_argument("packSggxMeans: one primitive per mean");
    thread_local std::vector<std::optional<primitive::EllipsoidShape>> shapes;  // reused: called per range of parents
    shapes.resize(means.size());
    Ellipsoid::shapesFromS(means, shapes);
    for (std::size_t i = 0; i < means.size(); ++i)
        out[i] = shapes[i] ? std::optional(primitive::pack(shapes[i]->normalized())) : std::nullopt;
}

std::optional<Mat3> storedFilterForm(const VoxelData& voxel, FilterRule rule) {
    const Vec3 sigma(voxel.sigma[0], voxel.sigma[1], voxel.sigma[2]);
    if (voxel.isEmpty() || !(sigma.maxCoeff() > 0)) return std::nullopt;
    // A stored primitive is normalised (Exact) before its σ is rounded to float, so its S is
    // the normalised one to float precision: no elliptic integral, no eigensolver (R and σ are
    // its eigen-form already). ThreeAxis: Ā₃ = π(a₂a₃ + a₁a₃ + a₁a₂)/3 of the same semi-axes.
    if (rule == FilterRule::Sggx) return unpackS(voxel).matrix();
    const Vec3 a = primitive::semiAxesFromSigma(sigma);
    const double threeAxisArea = std::numbers::pi * (a[1] * a[2] + a[0] * a[2] + a[0] * a[1]) / 3;
    const Mat3 R = unpackRotation(voxel);
    return R * (a.cwiseAbs2() / threeAxisArea).asDiagonal() * R.transpose();
}

std::span<const Vec3> sphericalPointSet(std::size_t count) {
    if (count == 0) throw std::invalid_argument("sphericalPointSet: count must be positive");
    static std::mutex mutex;
    static std::map<std::size_t, std::unique_ptr<std::vector<Vec3>>> cache;
    std::lock_guard lock(mutex);
    auto& points = cache[count];
    if (!points) {
        // Spherical Fibonacci lattice: equal-area bands in z, golden-angle steps in φ.
        points = std::make_unique<std::vector<Vec3>>(count);
        const double goldenAngle = std::numbers::pi * (3 - std::sqrt(5.0));
        for (std::size_t i = 0; i < count; ++i) {
            const double z = 1 - (2.0 * i + 1) / double(count);
            const double r = std::sqrt(std::max(0.0, 1 - z * z));
            const double phi = goldenAngle * double(i);
            (*points)[i] = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        }
    }
    return *points;
}

double filterError(const Ellipsoid& result, std::span<const Ellipsoid> children,
                   std::span<const double> weights, std::span<const Vec3> points) {
    checkSizes(children.size(), weights.size());
    double totalWeight = 0;
    for (double w : weights)
        if (usableWeight(w)) totalWeight += w;
    if (!(totalWeight > 0) || points.empty()) return 0;
    // The directions as three arrays, the mixture and the result's f̂ accumulated child by
    // child over all of them (vectorised), then the squared differences summed in order.
    const std::size_t n = points.size();
    thread_local std::vector<double> buffer;  // one per thread, reused: this runs per sampled node
    buffer.resize(5 * n);
    const std::span<double> all(buffer);
    const auto mixture = all.subspan(3 * n, n), own = all.subspan(4 * n, n);
    // The default set's arrays are made once (its points live as long as the process): copying
    // them on every call was a quarter of this function's own instructions in the octree build.
    static const std::span<const Vec3> defaultPoints = sphericalPointSet();
    static const std::vector<double> defaultArrays = [] {
        const std::size_t count = defaultPoints.size();
        std::vector<double> arrays(3 * count);
        for (std::size_t p = 0; p < count; ++p) {
            arrays[p] = defaultPoints[p].x();
            arrays[count + p] = defaultPoints[p].y();
            arrays[2 * count + p] = defaultPoints[p].z();
        }
        return arrays;
    }();
    std::span<const double> arrays(defaultArrays);
    if (points.data() != defaultPoints.data() || n != defaultPoints.size()) {
        for (std::size_t p = 0; p < n; ++p) {
            all[p] = points[p].x();
            all[n + p] = points[p].y();
            all[2 * n + p] = points[p].z();
        }
        arrays = all.subspan(0, 3 * n);
    }
    const auto x = arrays.subspan(0, n), y = arrays.subspan(n, n), z = arrays.subspan(2 * n, n);
    // The first usable child sets the mixture's sums (there is one: totalWeight > 0), and the
    // result sets its own: 0 + v is v bit for bit, so the sums are those of a zeroed start.
    bool first = true;
    for (std::size_t i = 0; i < children.size(); ++i)
        if (usableWeight(weights[i])) {
            children[i].accumulateNormalizedNormalDistribution(x, y, z, weights[i], mixture, first);
            first = false;
        }
    result.accumulateNormalizedNormalDistribution(x, y, z, 1.0, own, true);
    // The squared differences first, in a loop the compiler vectorises (a division each), then
    // summed in order, as the single loop summed them.
    squaredDifferences(own.data(), mixture.data(), totalWeight, n);
    double squaredSum = 0;
    for (std::size_t p = 0; p < n; ++p) squaredSum += own[p];
    return std::sqrt(squaredSum * 4 * std::numbers::pi / double(n));
}

double fitError(const Ellipsoid& fit, std::span<const Vec3> normals, std::span<const double> weights,
                std::span<const Vec3> points) {
    checkSizes(normals.size(), weights.size());
    double totalWeight = 0;
    for (std::size_t i = 0; i < normals.size(); ++i)
        if (usableWeight(weights[i]) && normals[i].allFinite()) totalWeight += weights[i];
    if (!(totalWeight > 0)) return 0;
    double errorSquared = 0, dataSquared = 0;
    for (const Vec3& p : points) {
        double facets = 0;
        for (std::size_t i = 0; i < normals.size(); ++i) {
            const double norm = normals[i].norm();
            if (usableWeight(weights[i]) && norm > 0 && std::isfinite(norm))
                facets += weights[i] * std::abs(p.dot(normals[i])) / norm;
        }
        facets /= totalWeight;
        const double difference = fit.projectedArea(p) - facets;
        errorSquared += difference * difference;
        dataSquared += facets * facets;
    }
    return dataSquared > 0 ? std::sqrt(errorSquared / dataSquared) : 0;
}

}  // namespace vtex::octree
