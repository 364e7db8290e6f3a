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
#include <utility>

namespace vtex::primitive {
namespace {

constexpr double kPi = std::numbers::pi;

bool isFinite(const Mat3& m) { return m.allFinite(); }

// Below this eccentricity measure (1 − shortest/longest) the elliptic-integral closed form of
// the surface area divides two vanishing quantities; the projected area A(ω) is then within
// 1% of constant and a small product Gauss rule integrates it to ~1e-14.
constexpr double kNearSphere = 1e-2;

// Carlson's R_F(x, y, 1) and R_D(x, y, 1) (B. C. Carlson, "Numerical computation of real or
// complex elliptic integrals", Numer. Algorithms 10, 1995, §2): both by the same duplication
// x ← (x + λ)/4, λ = √x√y + √x√z + √y√z, so one loop serves both, run until both criteria
// hold, then each one's Taylor series about its mean. The truncation errors are
// below double's epsilon at the tolerances (ε/8)^(1/6) and ε^(1/6) (§2.2); one duplication
// costs three square roots, a third of what std::ellint_1 and std::ellint_2 spend together.
std::pair<double, double> carlsonRfRd(double x, double y) {
    constexpr double kToleranceF = 0.0024, kToleranceD = 0.0014;  // ε^(1/6), (ε/8)^(1/6), ε = 2⁻⁵²
    const auto deviation = [](double mu, double a, double b, double c) {
        return std::max({std::abs(mu - a), std::abs(mu - b), std::abs(mu - c)}) / mu;
    };
    double z = 1, sum = 0, power = 1;
    for (int iteration = 0; iteration < 100; ++iteration) {
        if (deviation((x + y + z) / 3, x, y, z) < kToleranceF &&
            deviation((x + y + 3 * z) / 5, x, y, z) < kToleranceD)
            break;
        const double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z);
        const double lambda = sx * (sy + sz) + sy * sz;
        sum += power / (sz * (z + lambda));
        power *= 0.25;
        x = 0.25 * (x + lambda);
        y = 0.25 * (y + lambda);
        z = 0.25 * (z + lambda);
    }
    // R_F: deviations about μ = (x + y + z)/3, series 1 − E₂/10 + E₃/14 + E₂²/24 − 3E₂E₃/44.
    const double muF = (x + y + z) / 3;
    const double fx = (muF - x) / muF, fy = (muF - y) / muF, fz = -(fx + fy);
    const double f2 = fx * fy - fz * fz, f3 = fx * fy * fz;
    const double rf = (1 + (f2 / 24 - 0.1 - 3 * f3 / 44) * f2 + f3 / 14) / std::sqrt(muF);
    // R_D: deviations about μ = (x + y + 3z)/5, Carlson's series to fifth order,
    // 1 − 3E₂/14 + E₃/6 + 9E₂²/88 − 3E₄/22 − 9E₂E₃/52 + 3E₅/26, in the deviations' products.
    const double muD = (x + y + 3 * z) / 5;
    const double dx = (muD - x) / muD, dy = (muD - y) / muD, dz = (muD - z) / muD;
    const double ea = dx * dy, eb = dz * dz, ec = ea - eb, ed = ea - 6 * eb, ee = ed + ec + ec;
    const double series = 1 + ed * (-3.0 / 14 + 9.0 / 88 * ed - 9.0 / 52 * dz * ee) +
                          dz * (ee / 6 + dz * (-9.0 / 22 * ec + dz * 3.0 / 26 * ea));
    const double rd = 3 * sum + power * series / (muD * std::sqrt(muD));
    return {rf, rd};
}

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
    // Legendre's form S = 2πc² + 2πab/sin φ · (E(φ,k) sin²φ + F(φ,k) cos²φ), a = 1,
    // cos φ = c, k² = (b² − c²)/(b²(1 − c²)), written with Carlson's symmetric integrals
    // (F = sin φ R_F, E = sin φ R_F − k² sin³φ R_D / 3, all at (c², 1 − k² sin²φ, 1)):
    // S = 2πc² + 2πb (R_F − k² sin⁴φ R_D / 3), with 1 − k² sin²φ = c²/b² and
    // k² sin⁴φ = (1 − c²/b²)(1 − c²). Both terms are positive: no cancellation.
    const double y = (c / b) * (c / b);
    const auto [rf, rd] = carlsonRfRd(c * c, y);
    return 2 * kPi * c * c + 2 * kPi * b * (rf - (1 - y) * (1 - c) * (1 + c) * rd / 3);
}

// An orthonormal basis from σ-like quantities proportional to inverse semi-axes: the shared
// tail of fromS and fitNormals. `sigma` ≥ 0 with a positive maximum.
Ellipsoid fromBasisAndSigma(const Mat3& basis, Vec3 sigma) {
    return Ellipsoid::fromAxes(basis, semiAxesFromSigma(sigma));
}

// The loop of accumulateNormalizedNormalDistribution: out[i] += scale / (NᵀMN)² for the
// directions N = (x[i], y[i], z[i]), M's unique entries in `m` (out[i] = … when `start`, which
// spares the caller zeroing the sums first: that zeroing was a tenth of a 256³ bush build's
// instructions). The octree build's filter error runs it on 512 directions for every child of
// every sampled node, a third of a 256³ bush build's instructions (callgrind), so it is also
// compiled for AVX2 and AVX-512, chosen at load time where the processor has them: four or eight
// lanes per division instead of SSE2's two (on this project's AMD EPYC, 512 directions in 190 ns
// with AVX-512 against 370 with AVX2). Every lane rounds as the scalar expression does, in the
// same order: "avx2" enables no FMA instruction to contract it into, and "avx512f" does, so this
// file is compiled with -ffp-contract=off (primitive/CMakeLists.txt). Every version gives the same
// sums bit for bit.
#if defined(__x86_64__) && defined(__has_attribute)
#if __has_attribute(target_clones) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
#endif
void accumulateNormalDistribution(const std::array<double, 6>& m, double scale, const double* px,
                                  const double* py, const double* pz, std::size_t n, bool start, double* out) {
    const double m0 = m[0], m1 = m[1], m2 = m[2], m3 = m[3], m4 = m[4], m5 = m[5];
    const auto value = [&](std::size_t i) {
        const double a = px[i], b = py[i], c = pz[i];
        const double nMn = m0 * a * a + m1 * b * b + m2 * c * c + 2 * (m3 * a * b + m4 * a * c + m5 * b * c);
        return scale / (nMn * nMn);
    };
    if (start)
        for (std::size_t i = 0; i < n; ++i) out[i] = value(i);
    else
        for (std::size_t i = 0; i < n; ++i) out[i] += value(i);
}

}  // namespace

Vec3 semiAxesFromSigma(const Vec3& sigma) {
    // σᵢ = π aⱼ aₖ  ⇔  aᵢ = √(σ₁σ₂σ₃/π) / σᵢ. Work relative to the largest σ so that the
    // triple product neither overflows nor underflows: aᵢ = √s · √(σ̂₁σ̂₂σ̂₃/π) / σ̂ᵢ.
    const double largest = sigma.maxCoeff();
    const Vec3 unit = floorAxisRatios(sigma / largest);
    const double volumeTerm = std::sqrt(unit.prod() / kPi);
    return std::sqrt(largest) * volumeTerm * unit.cwiseInverse();
}

Vec3 floorAxisRatios(const Vec3& lengths) {
    return lengths.cwiseMax(kMinAxisRatio * lengths.maxCoeff());
}

Ellipsoid::Ellipsoid() : Ellipsoid(Mat3::Identity(), Vec3::Ones()) {}

EllipsoidShape Ellipsoid::shapeOf(const Mat3& basis, const Vec3& semiAxes) {
    const Vec3 floored = floorAxisRatios(semiAxes);
    std::array<int, 3> order = {0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int i, int j) { return floored[i] < floored[j]; });
    EllipsoidShape shape;
    for (int k = 0; k < 3; ++k) {
        shape.basis.col(k) = basis.col(order[k]);
        shape.semiAxes[k] = floored[order[k]];
    }
    const Vec3& a = shape.semiAxes;
    shape.exactMeanArea = a[2] * a[2] * unitSurfaceArea(a[0] / a[2], a[1] / a[2]) / 4;
    return shape;
}

Ellipsoid::Ellipsoid(const Mat3& basis, const Vec3& semiAxes) : Ellipsoid(shapeOf(basis, semiAxes)) {}

Ellipsoid::Ellipsoid(const EllipsoidShape& shape) {
    mBasis = shape.basis;
    mSemiAxes = shape.semiAxes;
    mExactMeanArea = shape.exactMeanArea;
    const double volumeProduct = mSemiAxes.prod();
    mDetM = volumeProduct * volumeProduct;
    cacheForms();
}

EllipsoidShape EllipsoidShape::normalized() const {
    // Ellipsoid::scaled(1 / √Ā) on the fields a shape has, in the same order of operations.
    const double factor = 1 / std::sqrt(exactMeanArea);
    const double areaFactor = factor * factor;
    EllipsoidShape copy = *this;
    copy.semiAxes *= factor;
    copy.exactMeanArea *= areaFactor;
    return copy;
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
    const auto shape = shapeFromM(M);
    if (!shape) return std::nullopt;
    return Ellipsoid(*shape);
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
    const auto shape = shapeFromS(S);
    if (!shape) return std::nullopt;
    return Ellipsoid(*shape);
}

std::optional<EllipsoidShape> Ellipsoid::shapeFromS(const Mat3& S) {
    // An eigensolver's basis is orthonormal and semiAxesFromSigma's axes finite and
    // non-negative, so fromAxes's checks have nothing to refuse here.
    if (!isFinite(S)) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(S);
    const Vec3 sigma = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    if (!(sigma.maxCoeff() > 0)) return std::nullopt;
    return shapeOf(solver.eigenvectors(), semiAxesFromSigma(sigma));
}

std::optional<EllipsoidShape> Ellipsoid::shapeFromM(const Mat3& M) {
    if (!isFinite(M)) return std::nullopt;
    const Eigen::SelfAdjointEigenSolver<Mat3> solver(M);
    const Vec3 lengthsSquared = solver.eigenvalues().cwiseMax(0.0);
    if (!(lengthsSquared.maxCoeff() > 0)) return std::nullopt;
    return shapeOf(solver.eigenvectors(), lengthsSquared.cwiseSqrt());
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

void Ellipsoid::accumulateNormalizedNormalDistribution(std::span<const double> x, std::span<const double> y,
                                                       std::span<const double> z, double weight,
                                                       std::span<double> sums, bool start) const {
    const std::size_t n = sums.size();
    if (x.size() != n || y.size() != n || z.size() != n)
        throw std::invalid_argument("accumulateNormalizedNormalDistribution: one sum per direction");
    const double scale = weight * (mDetM / mExactMeanArea);  // one division per direction, not two
    accumulateNormalDistribution(mM, scale, x.data(), y.data(), z.data(), n, start, sums.data());
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
