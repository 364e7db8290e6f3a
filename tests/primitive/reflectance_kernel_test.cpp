// The fast micro-primitive reflectance (ReflectanceKernel, reflectanceFast) against the same
// method written out plainly in double precision, on ellipsoids from needles to discs, and
// against the paper's integration (reflectanceReference).
#include <vtex/primitive/reflectance_kernel.h>

#include "../../primitive/src/band_specular.h"
#include "../../primitive/src/fibre_specular.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace vtex::primitive;

namespace {

constexpr double kPi = std::numbers::pi;

// The fast path written out plainly in double precision, with a plain matrix congruence and
// std::pow: none of the kernel's precomputation, SIMD or Phong cut-off. Diffuse: the 16-point
// Fibonacci lattice through the closed-form SGGX VNDF sampler (Heitz et al. 2015, Listing 3) in
// the frame of Frisvad's basis around v. Specular: that lattice and the 8 mirror directions of
// the Phong lobe, combined by the balance heuristic with both densities taken over normals —
// D_v(N) = D(N)(N·v)/A(v) from the SGGX density, (n+1)/2π cosⁿα 4(N·l) for the lobe — where the
// kernel takes them over the sampler's pre-image sphere: the two must agree.
ReflectanceFactors plainFastPath(const Eigen::Matrix3d& s, const Eigen::Vector3d& light, const Eigen::Vector3d& view,
                                 double shininess, int samples) {
    const double sign = std::copysign(1.0, view.z());
    const double a = -1.0 / (sign + view.z());
    const double b = view.x() * view.y() * a;
    Eigen::Matrix3d basis;
    basis.row(0) = Eigen::Vector3d(1 + sign * view.x() * view.x() * a, sign * b, -sign * view.x());
    basis.row(1) = Eigen::Vector3d(b, sign + view.y() * view.y() * a, -view.y());
    basis.row(2) = view;
    const Eigen::Matrix3d t = basis * s * basis.transpose();
    const Eigen::Vector3d l = basis * light;
    const double sii = t(2, 2);
    const double blockDet = t(1, 1) * sii - t(1, 2) * t(1, 2);
    const Eigen::Vector3d mk(std::sqrt(std::abs(t.determinant()) / blockDet), 0, 0);
    const Eigen::Vector3d mj((t(0, 1) * sii - t(0, 2) * t(1, 2)) / std::sqrt(sii * blockDet), std::sqrt(blockDet / sii), 0);
    const Eigen::Vector3d mi = t.col(2) / std::sqrt(sii);
    const Eigen::Matrix3d tInv = t.inverse();
    const double area = std::sqrt(sii);  // A(v), v = (0, 0, 1) in this frame
    const int lobeCount = ReflectanceKernel::kLobeSamples;
    auto densityA = [&](const Eigen::Vector3d& n) {
        const double q = n.dot(tInv * n);
        return n.z() > 0 ? n.z() / (kPi * std::sqrt(t.determinant()) * q * q * area) : 0.0;
    };
    auto cosAlpha = [&](const Eigen::Vector3d& n) { return 2 * n.dot(l) * n.z() - l.z(); };
    auto densityB = [&](const Eigen::Vector3d& n) {
        const double c = cosAlpha(n);
        return c > 0 && n.dot(l) > 0 ? (shininess + 1) / (2 * kPi) * std::pow(c, shininess) * 4 * n.dot(l) : 0.0;
    };
    auto term = [&](const Eigen::Vector3d& n) {  // (N·l)(n+2)/2π cosⁿα times A's density
        const double c = cosAlpha(n);
        return c > 0 && n.dot(l) > 0 ? densityA(n) * n.dot(l) * (shininess + 2) / (2 * kPi) * std::pow(c, shininess) : 0.0;
    };
    auto weighted = [&](const Eigen::Vector3d& n) {
        const double f = term(n);
        return f > 0 ? f / (samples * densityA(n) + lobeCount * densityB(n)) : 0.0;
    };
    const double golden = kPi * (3 - std::sqrt(5.0));
    double diffuse = 0, specular = 0;
    for (int i = 0; i < samples; ++i) {
        const double r = std::sqrt((i + 0.5) / samples);
        const double u = r * std::cos(golden * i), v = r * std::sin(golden * i);
        const Eigen::Vector3d n = (u * mk + v * mj + std::sqrt(1 - u * u - v * v) * mi).normalized();
        if (n.dot(l) <= 0) continue;
        diffuse += n.dot(l);
        specular += weighted(n);
    }
    for (int k = 0; k < lobeCount; ++k) {
        const double c = std::pow((k + 0.5) / lobeCount, 1 / (shininess + 1));
        const double sn = std::sqrt(std::max(0.0, 1 - c * c));
        const Eigen::Vector3d r(sn * std::cos(golden * k), sn * std::sin(golden * k), c);
        if ((l + r).norm() < 1e-12) continue;
        specular += weighted((l + r).normalized());
    }
    return {diffuse / (samples * kPi), specular};
}

Eigen::Vector3d randomDirection(std::mt19937& rng) {
    std::normal_distribution<double> n;
    return Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
}

// S = R diag(σ²) Rᵀ for a random rotation: σ ratios from 1e-3 to 1e3, and explicitly needles
// (one σ 1e-3 of the others: small projected area along the fibre) and discs (two σ small).
std::vector<Eigen::Matrix3d> randomMatrices(std::mt19937& rng, int count) {
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> logSigma(-1.5, 1.5);
    std::vector<Eigen::Matrix3d> out;
    for (int k = 0; k < count; ++k) {
        Eigen::Vector3d sigma(std::pow(10.0, logSigma(rng)), std::pow(10.0, logSigma(rng)), std::pow(10.0, logSigma(rng)));
        if (k % 4 == 1) sigma = Eigen::Vector3d(1, 1, 1e-3);
        if (k % 4 == 2) sigma = Eigen::Vector3d(1, 1e-3, 1e-3);
        const Eigen::Matrix3d r = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
        out.push_back(r * sigma.cwiseAbs2().asDiagonal() * r.transpose());
    }
    return out;
}

SggxMatrix toSggx(const Eigen::Matrix3d& s) { return {s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(0, 2), s(1, 2)}; }

// The kernel's fibre gate as an axis ratio (src/fibre_specular.h): needles thinner than
// 0.105 (n+1)^0.3 times the lobe's width 1/√(n+1) take the fibre limit.
double fibreGateRatio(double shininess) { return std::sqrt(vtex::primitive::detail::kernelFibreEigenRatioGate(shininess)); }

}  // namespace

// One kernel per (l, v, shininess) applied to many S equals the method computed plainly per
// call (reflectanceFast is one kernel used once). Tolerance: the kernel's lattice sum runs in single
// precision, whose rounding is relative to the terms' scale (1/π, (n+2)/2π) rather than to
// their sum, which cancellation in N·l near grazing can make 1e3 times smaller; and it drops
// Phong terms below 1e-6 of the lobe's peak, whose sum is below 1e-6 of the specular scale.
// Measured: worst 5.4e-6 of (value + 1e-3 of the scale); bound 1e-5.
TEST(ReflectanceKernel, EqualsThePlainMethodOnNeedlesAndDiscs) {
    std::mt19937 rng(5);
    const auto matrices = randomMatrices(rng, 64);
    double worst = 0;
    for (double shininess : {0.0, 1.0, 7.5, 20.0, 100.3, 200.0}) {
        for (int pair = 0; pair < 12; ++pair) {
            const Eigen::Vector3d l = randomDirection(rng), v = randomDirection(rng);
            const ReflectanceKernel kernel(l, v, shininess);
            for (const Eigen::Matrix3d& s : matrices) {
                const ReflectanceFactors got = kernel(toSggx(s));
                const ReflectanceFactors want = plainFastPath(s, l, v, shininess, 16);
                // Needles thin against the lobe take the fibre limit instead (tested below,
                // FibreLimitAgreesWithThePapersIntegration): kept out with a factor 4 of margin
                // on the kernel's gate, whose eigenvalue estimates are close there.
                const Eigen::Vector3d lambda = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(s).eigenvalues();
                // So do thicker needles from shininess 50, the band rule's (src/band_specular.h,
                // BandRuleAgreesWithThePapersIntegration): its gate is tested on S's invariants as
                // the kernel tests it, with 1 % of margin for their rounding.
                const bool band = vtex::primitive::detail::takesFibreLimit(
                    s.trace(), vtex::primitive::detail::adjugate(s).trace(), s.determinant(),
                    1.01 * vtex::primitive::detail::bandEigenRatioGate(shininess));
                if (band || lambda(0) / lambda(1) < 4 * std::pow(fibreGateRatio(shininess), 2)) {
                    EXPECT_NEAR(got.diffuse, want.diffuse, 1e-5 * (want.diffuse + 1e-3 / kPi));
                    continue;
                }
                const double specularScale = (shininess + 2) / (2 * kPi);
                const double dErr = std::abs(got.diffuse - want.diffuse) / (want.diffuse + 1e-3 / kPi);
                const double sErr = std::max(std::abs(got.specular - want.specular) - 1e-6 * specularScale, 0.0) /
                                    (want.specular + 1e-3 * specularScale);
                worst = std::max({worst, dErr, sErr});
                EXPECT_LE(dErr, 1e-5) << "n=" << shininess << " diffuse " << got.diffuse << " vs " << want.diffuse;
                EXPECT_LE(sErr, 1e-5) << "n=" << shininess << " specular " << got.specular << " vs " << want.specular;
                // Every term is (N·l)⁺ ≤ 1 times a Phong factor ≤ 1 (times a balance weight ≤ 1
                // for the specular), over 16 lattice points; the specular adds the lobe's 8.
                EXPECT_GE(got.diffuse, 0);
                EXPECT_LE(got.diffuse, 1 / kPi);
                EXPECT_GE(got.specular, 0);
                EXPECT_LE(got.specular, specularScale * (16.0 + ReflectanceKernel::kLobeSamples) / 16);
            }
        }
    }
    RecordProperty("worst_relative_error", std::to_string(worst));
    std::cout << "kernel vs plain double: worst relative error " << worst << "\n";
}

// The fast reflectance against the paper's integration on random ellipsoids and directions.
TEST(ReflectanceKernel, IsCloseToTheReference) {
    std::mt19937 rng(21);
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> u(0.05, 1);
    double diffuseError = 0, diffuseScale = 0;
    const int trials = 150;
    for (int k = 0; k < trials; ++k) {
        const Eigen::Matrix3d r = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
        const Eigen::Vector3d sigma(u(rng), u(rng), u(rng));
        const Eigen::Matrix3d s = r * sigma.cwiseAbs2().asDiagonal() * r.transpose();
        const SggxMatrix m{s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(0, 2), s(1, 2)};
        const Eigen::Vector3d l = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
        const Eigen::Vector3d v = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
        const auto fast = reflectanceFast(m, l, v, 20);
        const auto ref = reflectanceReference(m, l, v, 20, 64);
        diffuseError += std::abs(fast.diffuse - ref.diffuse);
        diffuseScale += ref.diffuse;
        EXPECT_TRUE(std::isfinite(fast.diffuse) && std::isfinite(fast.specular));
    }
    // Mean absolute error relative to the mean diffuse factor.
    EXPECT_LT(diffuseError / diffuseScale, 0.05);
}

namespace {

// R diag(σ²) Rᵀ for a random rotation R (quaternion components from `n`), σ = `sigma`, or where
// that is zero a random one, (10^a, 10^b, 1) with a, b drawn by `logRatio`.
SggxMatrix randomEllipsoid(const Eigen::Vector3d& sigma, std::normal_distribution<double>& n,
                           std::uniform_real_distribution<double>& logRatio, std::mt19937& rng) {
    const Eigen::Matrix3d r = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
    const Eigen::Vector3d axes =
        sigma.isZero() ? Eigen::Vector3d(std::pow(10.0, logRatio(rng)), std::pow(10.0, logRatio(rng)), 1) : sigma;
    return toSggx(r * axes.cwiseAbs2().asDiagonal() * r.transpose());
}

// Mean |fast − paper| / mean paper of the specular factor over `count` random rotations and
// light/view pairs of the ellipsoid with σ = `sigma` (a random σ per case if sigma is zero:
// ratios 1 to 1e-3), the paper's integration at 96 cells per axis as the truth.
double specularErrorAgainstThePaper(const Eigen::Vector3d& sigma, double shininess, int count, std::mt19937& rng,
                                    int cells = 96) {
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> logRatio(-3, 0);
    double error = 0, scale = 0;
    for (int k = 0; k < count; ++k) {
        const SggxMatrix m = randomEllipsoid(sigma, n, logRatio, rng);
        const Eigen::Vector3d l = randomDirection(rng), v = randomDirection(rng);
        const double paper = reflectanceReference(m, l, v, shininess, cells).specular;
        error += std::abs(reflectanceFast(m, l, v, shininess).specular - paper);
        scale += paper;
    }
    return error / scale;
}

}  // namespace

// The specular factor of the fast path (lattice and lobe by multiple importance sampling, the
// fibre limit for thin needles) against the paper's integration, per family of shapes: the
// lattice alone was 23 % off on spheres at shininess 10 and 155 % at 100, 52 % on needles at
// 100 (bench/vtex_specular_estimators). Bounds: the measured error × 1.5, rounded up; the
// paper's method at 96 cells is itself within 1.5 % of an unbiased Monte Carlo estimate here.
TEST(ReflectanceKernel, SpecularIsCloseToThePapersIntegrationOnEveryFamily) {
    struct Family {
        const char* name;
        Eigen::Vector3d sigma;
        std::array<double, 3> bound;  // shininess 1, 10, 100
    };
    const Family families[] = {{"sphere", {1, 1, 1}, {0.03, 0.035, 0.06}},
                               {"needle 1e-3", {1, 1, 1e-3}, {0.015, 0.03, 0.04}},
                               {"disc 1e-3", {1e-3, 1e-3, 1}, {0.01, 0.01, 0.01}},
                               // At 100 this was 0.122 with the fibre gate fixed at 0.15 × the
                               // lobe's width; with the gate where the estimators' errors
                               // cross (src/fibre_specular.h), 0.029.
                               {"random 1…1e-3", {0, 0, 0}, {0.03, 0.05, 0.045}}};
    std::mt19937 rng(17);
    const double shininesses[] = {1, 10, 100};
    for (const Family& family : families)
        for (std::size_t i = 0; i < 3; ++i) {
            const double error = specularErrorAgainstThePaper(family.sigma, shininesses[i], 60, rng);
            std::cout << family.name << ", shininess " << shininesses[i] << ": " << error << "\n";
            EXPECT_LE(error, family.bound[i]) << family.name << ", shininess " << shininesses[i];
        }
}

// The fibre limit alone decides needles thinner than its gate (src/fibre_specular.h): on needles of
// axis ratio 1e-3 and 1e-2 it must agree with the paper's integration (which resolves their
// circle of normals at 96 cells) within 4 % (measured: at most 3.7 %, ratio 1e-2 at 100).
TEST(ReflectanceKernel, FibreLimitAgreesWithThePapersIntegration) {
    std::mt19937 rng(29);
    for (const double ratio : {1e-3, 1e-2})
        for (const double shininess : {1.0, 10.0, 100.0}) {
            const double error = specularErrorAgainstThePaper({1, 1, ratio}, shininess, 60, rng);
            std::cout << "needle " << ratio << ", shininess " << shininess << ": " << error << "\n";
            EXPECT_LE(error, 0.04) << "needle " << ratio << ", shininess " << shininess;
        }
}

// The gate itself: needles just inside it (axis ratio 0.95 × the gate), the thickest the fibre
// limit takes, against the paper's integration. The gate sits where the fibre limit's error and
// the lattice-and-lobe estimator's cross (src/fibre_specular.h), so both are worst here; from
// shininess 50 the band rule takes over at a thickness of 0.15 (src/band_specular.h), below the
// fibre's own gate. Measured 0.038, 0.039, 0.031 at shininess 1, 10, 100 (0.165 at 100 with the
// fibre's own gate, 0.40 thick): bounds those × 1.3, rounded up.
TEST(ReflectanceKernel, FibreLimitHoldsUpToItsGate) {
    std::mt19937 rng(31);
    const double shininesses[] = {1, 10, 100}, bounds[] = {0.05, 0.06, 0.05};
    for (std::size_t i = 0; i < 3; ++i) {
        const double ratio = 0.95 * fibreGateRatio(shininesses[i]);
        const double error = specularErrorAgainstThePaper({1, 1, ratio}, shininesses[i], 60, rng);
        std::cout << "needle " << ratio << ", shininess " << shininesses[i] << ": " << error << "\n";
        EXPECT_LE(error, bounds[i]) << "needle " << ratio << ", shininess " << shininesses[i];
    }
}

namespace {

struct FactorErrors {
    double mean;  ///< mean |fast − paper| / mean paper
    double p95;   ///< 95th percentile of |fast − paper| / mean paper
};

// The two figures of row 16's goal for one family: fast and paper per case.
FactorErrors relativeErrors(const std::vector<double>& fast, const std::vector<double>& paper) {
    const double count = double(paper.size());
    double scale = 0;
    for (const double p : paper) scale += p / count;
    std::vector<double> errors;
    double mean = 0;
    for (std::size_t k = 0; k < fast.size(); ++k) {
        errors.push_back(std::abs(fast[k] - paper[k]) / scale);
        mean += errors.back() / count;
    }
    std::sort(errors.begin(), errors.end());
    return {mean, errors[std::size_t(0.95 * (count - 1))]};
}

// The specular factor's errors against the paper's integration (96 cells per axis) on `count`
// ellipsoids R diag(σ²) Rᵀ, σ = sigma() per case, each lit at a highlight: v random, l its mirror
// about a normal N ∝ S^{1/2}u (u random; the map concentrates N where the ellipsoid's normals
// are, on a needle's band), so that the lobe's peak lies on the normals and the specular factor
// is large. (With l and v both random, the lobe misses a needle's band in most cases.)
template <class Sigma>
FactorErrors aimedFactorErrors(Sigma sigma, double shininess, int count, std::mt19937& rng) {
    std::normal_distribution<double> n;
    std::vector<double> fast, paper;
    for (int k = 0; k < count; ++k) {
        const Eigen::Matrix3d r = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
        const Eigen::Vector3d axes = sigma();
        const SggxMatrix m = toSggx(r * axes.cwiseAbs2().asDiagonal() * r.transpose());
        const Eigen::Vector3d normal = (r * axes.asDiagonal() * r.transpose() * randomDirection(rng)).normalized();
        Eigen::Vector3d v = randomDirection(rng);
        if (v.dot(normal) < 0) v = -v;
        const Eigen::Vector3d l = 2 * normal.dot(v) * normal - v;
        fast.push_back(reflectanceFast(m, l, v, shininess).specular);
        paper.push_back(reflectanceReference(m, l, v, shininess, 96).specular);
    }
    return relativeErrors(fast, paper);
}

}  // namespace

// Issue 15, row 16: the bush's voxels at shininess 1000 were 0.156 off (bench/vtex_specular_estimators),
// the error carried by one needle of axis ratios 0.10 (its thickness against its cross-section)
// and 0.21 (its cross-section's), 3.3 lobe widths thick: past the fibre limit's gate, where the
// lattice and lobe missed the product of its band of normals and the narrow lobe. The band rule
// (src/band_specular.h) takes it. Lit at its highlights, against the paper's integration (within
// 0.2 % of a converged band rule and of Monte Carlo there): the lattice and lobe measured 0.069
// mean and 0.232 at the 95th percentile, the band rule 0.022 and 0.072; bounds: the row's goal.
TEST(ReflectanceKernel, BandRuleAgreesWithThePapersIntegration) {
    std::mt19937 rng(41);
    const FactorErrors e = aimedFactorErrors([] { return Eigen::Vector3d(0.10 * 0.21, 0.21, 1); }, 1000, 60, rng);
    std::cout << "needle 0.10 / 0.21, shininess 1000: mean " << e.mean << ", 95th percentile " << e.p95 << "\n";
    EXPECT_LE(e.mean, 0.05);
    EXPECT_LE(e.p95, 0.15);
}

// The band rule across its window: needles 1, 2 and 3.5 lobe widths thick (axis ratio × √(n+1)),
// their cross-sections' axis ratios log-uniform in [0.01, 1] (down to the band's kBandFlattest),
// lit at their highlights, at shininess 100, 300 and 1000, against the paper's integration. The
// lattice and lobe measured up to 0.080 mean (thickness 1 at 1000) and 0.342 at the 95th
// percentile (2 at 1000), over the goal at 300 and 1000 (cross-sections from 0.03); the band rule
// at most 0.015 and 0.084 (1 at 300); bounds: the row's goal.
TEST(ReflectanceKernel, BandRuleHoldsAcrossItsWindow) {
    std::mt19937 rng(43);
    std::uniform_real_distribution<double> logCross(-2, 0);
    for (const double shininess : {100.0, 300.0, 1000.0})
        for (const double thickness : {1.0, 2.0, 3.5}) {
            const double ratio = thickness / std::sqrt(shininess + 1);
            const auto sigma = [&] {
                const double cross = std::pow(10.0, logCross(rng));
                return Eigen::Vector3d(ratio * cross, cross, 1);
            };
            const FactorErrors e = aimedFactorErrors(sigma, shininess, 60, rng);
            std::cout << "needle " << thickness << " lobe widths, shininess " << shininess << ": mean " << e.mean
                      << ", 95th percentile " << e.p95 << "\n";
            EXPECT_LE(e.mean, 0.05) << thickness << " lobe widths, shininess " << shininess;
            EXPECT_LE(e.p95, 0.15) << thickness << " lobe widths, shininess " << shininess;
        }
}

// The band rule takes needles only. Its window reaches λ₁/λ₂ = 16/(n+1) (0.31 at shininess 50),
// and the invariants' estimate of that ratio is 0.21 for a sphere: until the exact test
// (detail::bandTakes), spheres at shininess 50–79 took the band rule around an arbitrary axis,
// 0.25–0.46 mean off against Monte Carlo (`build/bench/vtex_specular_estimators 60 20000
// 40,49,50,51,60,64,65,70,80,90` with 082ff99's kernel; 0.03–0.05 at 40, 49, 80, 90; see
// docs/micro-primitive.md, "The band rule's gate, exact"). The gate: a sphere, a thick ellipsoid and a disc refused, needles 1 and 3.9 lobe
// widths thick taken, at 50 and 79. Then spheres and random shapes at 50, 60 and 70 against the
// paper's integration: spheres 0.040–0.047 (0.31–0.35 with the invariants' test alone), random
// shapes 0.011–0.015 (0.011–0.016); bounds: the row's goal.
TEST(ReflectanceKernel, BandRuleTakesOnlyNeedles) {
    namespace d = vtex::primitive::detail;
    const auto diagonal = [](double a, double b, double c) { return Eigen::Vector3d(a, b, c).asDiagonal().toDenseMatrix(); };
    for (const double n : {50.0, 79.0}) {
        const double gate = d::bandEigenRatioGate(n);
        EXPECT_FALSE(d::bandTakes(diagonal(1, 1, 1), gate)) << n;
        EXPECT_FALSE(d::bandTakes(diagonal(0.5, 1, 1), gate)) << n;
        EXPECT_FALSE(d::bandTakes(diagonal(1e-6, 1e-6, 1), gate)) << n;  // a disc: λ₁ = λ₂
        // A disc whose normals spread unevenly (λ₁/λ₂ = 0.15, in the window at 50–79, but a
        // cross-section of 0.001): one such shape, 25 % off through the band rule at 60, was two
        // thirds of the random family's mean error there in `vtex_specular_estimators 300 20000
        // 50,60,70` with kBandFlattest 0 (0.061; 0.027 with it).
        EXPECT_FALSE(d::bandTakes(diagonal(1.5e-7, 1e-6, 1), gate)) << n;
        for (const double thickness : {1.0, 3.9}) {
            const double ratio2 = thickness * thickness / (n + 1);  // λ₁/λ₂
            EXPECT_TRUE(d::bandTakes(diagonal(ratio2 * 0.3, 0.3, 1), gate)) << n << " " << thickness;
            // The invariants' test passes what the exact one does (its ratio is a lower bound).
            const Eigen::Matrix3d s = diagonal(ratio2 * 0.3, 0.3, 1);
            const double trAdj = s(1, 1) * s(2, 2) + s(0, 0) * s(2, 2) + s(0, 0) * s(1, 1);
            EXPECT_TRUE(d::takesFibreLimit(s.trace(), trAdj, s.determinant(), gate)) << n << " " << thickness;
        }
    }
    std::mt19937 rng(53);
    for (const double shininess : {50.0, 60.0, 70.0}) {
        const double sphere = specularErrorAgainstThePaper({1, 1, 1}, shininess, 60, rng);
        const double random = specularErrorAgainstThePaper({0, 0, 0}, shininess, 60, rng);
        std::cout << "shininess " << shininess << ": sphere " << sphere << ", random " << random << "\n";
        EXPECT_LE(sphere, 0.05) << shininess;
        EXPECT_LE(random, 0.05) << shininess;
    }
}

// Round needles between the band rule's lower edge (0.15 lobe widths) and the fibre gate under
// random l and v: the lobe meets the band's tails off its circle, which the fibre limit, a line,
// has not (src/band_specular.h, kBandThinnest). The paper's integration at 192 cells per axis
// (the kernel's errors against it within 0.5 % of those against 384 cells). The fibre limit
// measured 0.045, 0.169 (0.2 and 0.4 lobe widths) at shininess 100, 0.029, 0.087 at 300, 0.058,
// 0.133, 0.293 (0.2, 0.4, 0.8) at 1000; the band rule at most 0.017; bounds: the row's goal.
TEST(ReflectanceKernel, BandRuleTakesThickFibresUnderAnyLight) {
    std::mt19937 rng(47);
    for (const double shininess : {100.0, 300.0, 1000.0})
        for (const double thickness : {0.2, 0.4, 0.8}) {
            if (thickness * thickness / (shininess + 1) > vtex::primitive::detail::fibreEigenRatioGate(shininess)) continue;
            const double ratio = thickness / std::sqrt(shininess + 1);
            const double error = specularErrorAgainstThePaper({1, 1, ratio}, shininess, 60, rng, 192);
            std::cout << "round needle " << thickness << " lobe widths, shininess " << shininess << ": " << error << "\n";
            EXPECT_LE(error, 0.05) << thickness << " lobe widths, shininess " << shininess;
        }
}

// Issue 15, row 16, the diffuse half: the fast path's diffuse factor (the 16-point D_v lattice)
// against the paper's integration at 64 cells per axis (within 1 % from 32; within 0.002 of an
// unbiased Monte Carlo estimate at 96, bench/vtex_specular_estimators), per family, random l and v,
// 200 cases each. Measured here: mean / 95th percentile of |error| over the family's mean, sphere
// 0.033 / 0.076, needle 0.042 / 0.093, disc 0.000 / 0.001, random 0.021 / 0.089 (1000 cases in the
// bench: 0.034 / 0.082, 0.042 / 0.100, 0.001 / 0.001, 0.022 / 0.089). Bounds: the row's goal.
TEST(ReflectanceKernel, DiffuseMeetsItsGoalOnEveryFamily) {
    const std::pair<const char*, Eigen::Vector3d> families[] = {
        {"sphere", {1, 1, 1}}, {"needle 1e-3", {1, 1, 1e-3}}, {"disc 1e-3", {1e-3, 1e-3, 1}}, {"random 1…1e-4", {0, 0, 0}}};
    std::mt19937 rng(23);
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> logRatio(-4, 0);
    for (const auto& [name, sigma] : families) {
        const int count = 200;
        std::vector<double> fast, paper;
        for (int k = 0; k < count; ++k) {
            const SggxMatrix m = randomEllipsoid(sigma, n, logRatio, rng);
            const Eigen::Vector3d l = randomDirection(rng), v = randomDirection(rng);
            fast.push_back(reflectanceFast(m, l, v, 20).diffuse);
            paper.push_back(reflectanceReference(m, l, v, 20, 64).diffuse);
        }
        const FactorErrors e = relativeErrors(fast, paper);
        std::cout << name << ": diffuse mean " << e.mean << ", 95th percentile " << e.p95 << "\n";
        EXPECT_LE(e.mean, 0.05) << name;
        EXPECT_LE(e.p95, 0.15) << name;
    }
}
