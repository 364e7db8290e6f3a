// Filtering of micro-primitives, Neyret 1994 §3.3.2 ("the mean ellipsoid is the one whose
// inverse quadratic form is the mean of the inverse quadratic forms", weighted by density),
// and the SGGX alternative (Heitz et al. 2015, §5: linear filtering of S).
#include <vtex/octree/filtering.h>

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

}  // namespace

std::optional<Ellipsoid> filterEllipsoids(std::span<const Ellipsoid> children,
                                          std::span<const double> weights, FilterRule rule) {
    checkSizes(children.size(), weights.size());
    Mat3 sum = Mat3::Zero();
    double totalWeight = 0;
    for (std::size_t i = 0; i < children.size(); ++i) {
        if (!usableWeight(weights[i])) continue;
        // Each child enters with unit mean apparent area, so its weight is its density alone.
        if (rule == FilterRule::Neyret)
            sum += weights[i] * children[i].normalized(Normalization::ThreeAxis).M();
        else
            sum += weights[i] * children[i].normalized(Normalization::Exact).S();
        totalWeight += weights[i];
    }
    if (!(totalWeight > 0)) return std::nullopt;
    sum /= totalWeight;
    const auto result = rule == FilterRule::Neyret ? Ellipsoid::fromM(sum) : Ellipsoid::fromS(sum);
    if (!result) return std::nullopt;
    return result->normalized(Normalization::Exact);
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
    double squaredSum = 0;
    for (const Vec3& p : points) {
        double mixture = 0;
        for (std::size_t i = 0; i < children.size(); ++i)
            if (usableWeight(weights[i]))
                mixture += weights[i] * children[i].normalizedNormalDistribution(p);
        const double difference = result.normalizedNormalDistribution(p) - mixture / totalWeight;
        squaredSum += difference * difference;
    }
    return std::sqrt(squaredSum * 4 * std::numbers::pi / double(points.size()));
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
