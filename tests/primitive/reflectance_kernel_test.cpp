// The fast micro-primitive reflectance (ReflectanceKernel, reflectanceFast) against the same
// method written out plainly in double precision, on ellipsoids from needles to discs, and
// against the paper's integration (reflectanceReference).
#include <vtex/primitive/reflectance_kernel.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>

using namespace vtex::primitive;

namespace {

constexpr double kPi = std::numbers::pi;

// The 16-point Fibonacci lattice through the closed-form SGGX VNDF sampler (Heitz et al. 2015,
// Listing 3) in the frame of Frisvad's basis around v, in double precision with a plain matrix
// congruence and std::pow: none of the kernel's precomputation, SIMD or Phong cut-off.
ReflectanceFactors plainVndfLattice(const Eigen::Matrix3d& s, const Eigen::Vector3d& light,
                                    const Eigen::Vector3d& view, double shininess, int samples) {
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
    const double golden = kPi * (3 - std::sqrt(5.0));
    double diffuse = 0, specular = 0;
    for (int i = 0; i < samples; ++i) {
        const double r = std::sqrt((i + 0.5) / samples);
        const double u = r * std::cos(golden * i), v = r * std::sin(golden * i);
        const Eigen::Vector3d n = (u * mk + v * mj + std::sqrt(1 - u * u - v * v) * mi).normalized();
        const double nl = n.dot(l);
        if (nl <= 0) continue;
        diffuse += nl;
        const double cosAlpha = 2 * nl * n.z() - l.z();
        if (cosAlpha > 0) specular += nl * std::pow(cosAlpha, shininess);
    }
    return {diffuse / (samples * kPi), specular * (shininess + 2) / (2 * kPi) / samples};
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
                const ReflectanceFactors want = plainVndfLattice(s, l, v, shininess, 16);
                const double specularScale = (shininess + 2) / (2 * kPi);
                const double dErr = std::abs(got.diffuse - want.diffuse) / (want.diffuse + 1e-3 / kPi);
                const double sErr = std::max(std::abs(got.specular - want.specular) - 1e-6 * specularScale, 0.0) /
                                    (want.specular + 1e-3 * specularScale);
                worst = std::max({worst, dErr, sErr});
                EXPECT_LE(dErr, 1e-5) << "n=" << shininess << " diffuse " << got.diffuse << " vs " << want.diffuse;
                EXPECT_LE(sErr, 1e-5) << "n=" << shininess << " specular " << got.specular << " vs " << want.specular;
                // Every lattice term is (N·l)⁺ ≤ 1 times a Phong factor ≤ 1: no facet reflects
                // more than one facing the light.
                EXPECT_GE(got.diffuse, 0);
                EXPECT_LE(got.diffuse, 1 / kPi);
                EXPECT_GE(got.specular, 0);
                EXPECT_LE(got.specular, specularScale);
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
