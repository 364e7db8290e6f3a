// The micro-primitive of Neyret 1994 §3.1–3.3.2 and its SGGX parameterisation (Heitz et al.
// 2015, §4). See DESIGN.md, "The micro-primitive".
#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/quadrature.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace vtex::primitive {
namespace {

constexpr double kPi = std::numbers::pi;

bool isFinite(const Mat3& m) { return m.allFinite(); }

// Below this eccentricity measure (1 − shortest/longest) the elliptic-integral closed form of
// the surface area divides two vanishing quantities; the projected area A(ω) is then within
// 1% of constant and a small product Gauss rule integrates it to ~1e-14.
constexpr double kNearSphere = 1e-2;

// Surface area of the ellipsoid with semi-axes c ≤ b ≤ 1 (the longest scaled to 1).
double unitSurfaceArea(double c, double b) {
    if (1 - c < kNearSphere) {
        // Area = 4 Ā = (1/π) ∫ A(ω) dω = ∫ √(Σ (σᵢ/π)² ωᵢ²) dω, with σ/π = (b, c, cb) for the
        // semi-axes (c, b, 1). The integrand is even in each coordinate: integrate one octant.
        static const QuadratureRule rule = gaussLegendre(24);
        const std::array<double, 3> sigmaSquared = {b * b, c * c, c * c * b * b};
        double sum = 0;
        for (std::size_t i = 0; i < rule.nodes.size(); ++i) {
            const double z = 0.5 * (rule.nodes[i] + 1);  // cos θ on [0, 1]
            const double r = std::sqrt(std::max(0.0, 1 - z * z));
            for (std::size_t j = 0; j < rule.nodes.size(); ++j) {
                const double phi = 0.25 * kPi * (rule.nodes[j] + 1);  // [0, π/2]
                const double x = r * std::cos(phi), y = r * std::sin(phi);
                sum += rule.weights[i] * rule.weights[j] *
                       std::sqrt(sigmaSquared[0] * x * x + sigmaSquared[1] * y * y +
                                 sigmaSquared[2] * z * z);
            }
        }
        // dω = dz dφ; the maps from [-1, 1] have Jacobians ½ and π/4.
        return 8 * sum * 0.5 * (0.25 * kPi);
    }
    // Legendre's form: S = 2πc² + 2πab/sin φ · (E(φ,k) sin²φ + F(φ,k) cos²φ), a = 1,
    // cos φ = c/a, k² = a²(b² − c²) / (b²(a² − c²)). Both terms are positive: no cancellation.
    const double cosPhi = c;
    const double sinPhi = std::sqrt((1 - c) * (1 + c));
    const double phi = std::acos(cosPhi);
    const double k = std::sqrt(std::clamp((b - c) * (b + c) / (b * b * (1 - c) * (1 + c)), 0.0, 1.0));
    const double ellE = std::ellint_2(k, phi);
    const double ellF = std::ellint_1(k, phi);
    return 2 * kPi * c * c + 2 * kPi * b / sinPhi * (ellE * sinPhi * sinPhi + ellF * cosPhi * cosPhi);
}

// An orthonormal basis from σ-like quantities proportional to inverse semi-axes: the shared
// tail of fromS and fitNormals. `sigma` ≥ 0 with a positive maximum.
Ellipsoid fromBasisAndSigma(const Mat3& basis, Vec3 sigma) {
    // σᵢ = π aⱼ aₖ  ⇔  aᵢ = √(σ₁σ₂σ₃/π) / σᵢ. Work relative to the largest σ so that the
    // triple product neither overflows nor underflows: aᵢ = √s · √(σ̂₁σ̂₂σ̂₃/π) / σ̂ᵢ.
    const double largest = sigma.maxCoeff();
    const Vec3 unit = floorAxisRatios(sigma / largest);
    const double volumeTerm = std::sqrt(unit.prod() / kPi);
    const Vec3 semiAxes = std::sqrt(largest) * volumeTerm * unit.cwiseInverse();
    return Ellipsoid::fromAxes(basis, semiAxes);
}

}  // namespace

Vec3 floorAxisRatios(const Vec3& lengths) {
    return lengths.cwiseMax(kMinAxisRatio * lengths.maxCoeff());
}

Ellipsoid::Ellipsoid() : Ellipsoid(Mat3::Identity(), Vec3::Ones()) {}

Ellipsoid::Ellipsoid(const Mat3& basis, const Vec3& semiAxes) {
    const Vec3 floored = floorAxisRatios(semiAxes);
    std::array<int, 3> order = {0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int i, int j) { return floored[i] < floored[j]; });
    for (int k = 0; k < 3; ++k) {
        mBasis.col(k) = basis.col(order[k]);
        mSemiAxes[k] = floored[order[k]];
    }
    const Vec3& a = mSemiAxes;
    const double volumeProduct = a.prod();
    mDetM = volumeProduct * volumeProduct;
    mExactMeanArea = a[2] * a[2] * unitSurfaceArea(a[0] / a[2], a[1] / a[2]) / 4;
    cacheForms();
}

void Ellipsoid::cacheForms() {
    const auto unique = [](const Mat3& m) {
        return std::array<double, 6>{m(0, 0), m(1, 1), m(2, 2), m(0, 1), m(0, 2), m(1, 2)};
    };
    mS = SggxMatrix::fromUpper(S());
    mM = unique(M());
}

Ellipsoid Ellipsoid::fromAxes(const Mat3& basis, const Vec3& semiAxes) {
    const double largest = semiAxes.maxCoeff();
    if (!semiAxes.allFinite() || !(largest > 0) || semiAxes.minCoeff() < 0)
        throw std::invalid_argument("Ellipsoid::fromAxes: semi-axes must be finite, >= 0, max > 0");
    if (!isFinite(basis) || !(basis.transpose() * basis).isIdentity(1e-6))
        throw std::invalid_argument("Ellipsoid::fromAxes: basis must be orthonormal");
    return Ellipsoid(basis, semiAxes);
}

std::optional<Ellipsoid> Ellipsoid::fromM(const Mat3& M) {
    if (!isFinite(M)) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(M);
    const Vec3 lengthsSquared = solver.eigenvalues().cwiseMax(0.0);
    if (!(lengthsSquared.maxCoeff() > 0)) return std::nullopt;
    return Ellipsoid(solver.eigenvectors(), lengthsSquared.cwiseSqrt());
}

std::optional<Ellipsoid> Ellipsoid::fromQ(const Mat3& Q) {
    if (!isFinite(Q)) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(Q);
    // √qᵢ = 1/aᵢ: the floor on these inverse lengths caps an infinite axis (q = 0) at
    // 1/kMinAxisRatio times the shortest one.
    const Vec3 inverseLengths = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    if (!(inverseLengths.maxCoeff() > 0)) return std::nullopt;
    return Ellipsoid(solver.eigenvectors(), floorAxisRatios(inverseLengths).cwiseInverse());
}

std::optional<Ellipsoid> Ellipsoid::fromS(const Mat3& S) {
    if (!isFinite(S)) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(S);
    const Vec3 sigma = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    if (!(sigma.maxCoeff() > 0)) return std::nullopt;
    return fromBasisAndSigma(solver.eigenvectors(), sigma);
}

std::optional<Ellipsoid> Ellipsoid::fitNormals(std::span<const Vec3> normals,
                                               std::span<const double> weights) {
    if (normals.size() != weights.size())
        throw std::invalid_argument("Ellipsoid::fitNormals: one weight per normal");
    // Step 1: principal axes from the second moment E = Σ w n nᵀ (sign-free by construction).
    Mat3 secondMoment = Mat3::Zero();
    double totalWeight = 0;
    auto usable = [&](std::size_t i, Vec3& unit) {
        const double norm = normals[i].norm();
        if (!(weights[i] > 0) || !std::isfinite(weights[i]) || !(norm > 0) || !std::isfinite(norm))
            return false;
        unit = normals[i] / norm;
        return true;
    };
    Vec3 n;
    for (std::size_t i = 0; i < normals.size(); ++i) {
        if (!usable(i, n)) continue;
        secondMoment.noalias() += weights[i] * n * n.transpose();
        totalWeight += weights[i];
    }
    if (!(totalWeight > 0) || !std::isfinite(totalWeight)) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(secondMoment);
    const Mat3& axes = solver.eigenvectors();
    // Step 2: the mean projected area of the facets along each axis.
    Vec3 sigma = Vec3::Zero();
    for (std::size_t i = 0; i < normals.size(); ++i) {
        if (!usable(i, n)) continue;
        sigma += weights[i] * (axes.transpose() * n).cwiseAbs();
    }
    sigma /= totalWeight;
    if (!(sigma.maxCoeff() > 0)) return std::nullopt;
    return fromBasisAndSigma(axes, sigma);
}

Mat3 Ellipsoid::M() const {
    return mBasis * mSemiAxes.cwiseAbs2().asDiagonal() * mBasis.transpose();
}

Mat3 Ellipsoid::Q() const {
    return mBasis * mSemiAxes.cwiseAbs2().cwiseInverse().asDiagonal() * mBasis.transpose();
}

Mat3 Ellipsoid::S() const {
    const Vec3& a = mSemiAxes;
    const Vec3 sigmaSquared =
        Vec3(kPi * a[1] * a[2], kPi * a[0] * a[2], kPi * a[0] * a[1]).cwiseAbs2();
    return mBasis * sigmaSquared.asDiagonal() * mBasis.transpose();
}

double Ellipsoid::surfaceArea() const { return 4 * mExactMeanArea; }

double Ellipsoid::meanProjectedArea(Normalization normalization) const {
    if (normalization == Normalization::Exact) return mExactMeanArea;
    const Vec3& a = mSemiAxes;
    return kPi * (a[1] * a[2] + a[0] * a[2] + a[0] * a[1]) / 3;
}

Ellipsoid Ellipsoid::normalized(Normalization normalization) const {
    return scaled(1 / std::sqrt(meanProjectedArea(normalization)));
}

Ellipsoid Ellipsoid::scaled(double factor) const {
    Ellipsoid copy = *this;
    const double areaFactor = factor * factor;
    copy.mSemiAxes *= factor;
    copy.mDetM *= areaFactor * areaFactor * areaFactor;
    copy.mExactMeanArea *= areaFactor;
    for (double* s : {&copy.mS.xx, &copy.mS.yy, &copy.mS.zz, &copy.mS.xy, &copy.mS.xz, &copy.mS.yz})
        *s *= areaFactor * areaFactor;
    for (double& m : copy.mM) m *= areaFactor;
    return copy;
}

}  // namespace vtex::primitive
