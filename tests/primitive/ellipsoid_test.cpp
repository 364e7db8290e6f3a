// The micro-primitive's maths (DESIGN.md, "The micro-primitive"), each checked against an
// independent computation: quadrature of the normal distribution against the closed-form
// area and projected area, the SGGX formulas against Neyret's quadratic form, fits against
// the shapes their normals came from (the fits' projected-area error: tests/octree/fit_test.cpp).
#include "shapes.h"

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/quadrature.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <numbers>

namespace vtex::primitive {
namespace {

using test::integrateOverSurface;
using test::integrateSphere;
using test::parametricSurfaceArea;
using test::randomDirection;
using test::randomRotation;
using test::sampleSurfaceNormals;
using test::standardShapes;

constexpr double kPi = std::numbers::pi;

TEST(Quadrature, GaussLegendreIntegratesPolynomialsExactly) {
    const QuadratureRule rule = gaussLegendre(7);
    for (int degree = 0; degree <= 13; ++degree) {
        double sum = 0;
        for (std::size_t i = 0; i < rule.nodes.size(); ++i)
            sum += rule.weights[i] * std::pow(rule.nodes[i], degree);
        const double exact = degree % 2 ? 0.0 : 2.0 / (degree + 1);
        EXPECT_NEAR(sum, exact, 1e-14) << "x^" << degree;
    }
}

TEST(Ellipsoid, SurfaceAreaMatchesParametricQuadratureOverTheWholeRangeOfShapes) {
    // Near a sphere the closed form is 0/0, near a disc or needle it meets the ratio floor.
    const std::vector<Vec3> axes = {
        {1, 1, 1},       {1, 1, 1 - 1e-12}, {1, 1 - 1e-7, 1 - 2e-7}, {1, 0.999, 0.995},
        {1, 0.98, 0.97}, {1, 0.5, 0.2},     {1, 1, 1e-2},            {1, 1, 1e-4},
        {1, 1e-2, 1e-2}, {1, 1e-4, 1e-4},   {1, 0.3, 1e-4},          {1e3, 2e2, 7},
        {2e-5, 1e-5, 3e-6}};
    for (const Vec3& a : axes) {
        const Ellipsoid e = Ellipsoid::fromAxes(Mat3::Identity(), a);
        const double reference = parametricSurfaceArea(e.semiAxes());
        EXPECT_NEAR(e.surfaceArea() / reference, 1.0, 1e-9) << a.transpose();
    }
    EXPECT_NEAR(Ellipsoid().surfaceArea(), 4 * kPi, 1e-12);
}

TEST(Ellipsoid, SurfaceAreaAgreesWithLegendresFormThroughTheStandardLibrary) {
    // The area is Carlson's R_F and R_D from one shared duplication loop; Legendre's form
    // through std::ellint_1/ellint_2 (libstdc++'s own Carlson loops, one per integral) is an
    // independent evaluation (itself ~1e-12 off in double: φ = acos c and sin φ are rounded
    // before the integrals): within 3e-12 wherever the closed form is used (1 − c ≥ 1e-2).
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> unit(0, 1);
    for (int i = 0; i < 2000; ++i) {
        const double c0 = std::pow(10.0, -4 * unit(rng)) * 0.99;
        const Ellipsoid e = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(c0, c0 + (1 - c0) * unit(rng), 1));
        const double c = e.semiAxes()[0], b = e.semiAxes()[1];  // after the ratio floor
        const double sinPhi = std::sqrt((1 - c) * (1 + c));
        const double phi = std::acos(c);
        const double k = std::sqrt(std::clamp((b - c) * (b + c) / (b * b * (1 - c) * (1 + c)), 0.0, 1.0));
        const double legendre = 2 * kPi * c * c + 2 * kPi * b / sinPhi *
                                (std::ellint_2(k, phi) * sinPhi * sinPhi + std::ellint_1(k, phi) * c * c);
        ASSERT_NEAR(e.surfaceArea() / legendre, 1.0, 3e-12) << "c " << c << " b " << b;
    }
}

TEST(Ellipsoid, NormalDistributionIntegratesToTheSurfaceArea) {
    // A plain grid over the sphere of normals, about a fixed axis: it knows nothing of the
    // ellipsoid's frame. 1200 rings resolve the peak of the 100:1 disc (width ~0.01 rad).
    for (const auto& [name, e] : standardShapes()) {
        const double integral =
            integrateSphere([&](const Vec3& n) { return e.normalDistribution(n); }, 1200);
        const double area = parametricSurfaceArea(e.semiAxes());
        EXPECT_NEAR(integral / area, 1.0, 1e-3) << name;
    }
}

TEST(Ellipsoid, ProjectedAreaClosedFormEqualsHalfTheIntegralOfAbsCosineTimesF) {
    std::mt19937 rng(7);
    for (const auto& [name, e] : standardShapes()) {
        for (int k = 0; k < 100; ++k) {
            const Vec3 w = randomDirection(rng);
            const double integral =
                0.5 * integrateOverSurface(e, [&](const Vec3& n) { return std::abs(w.dot(n)); }, 160);
            EXPECT_NEAR(e.projectedArea(w) / integral, 1.0, 1e-3) << name << " ω=" << w.transpose();
        }
    }
}

TEST(Ellipsoid, MeanProjectedAreaIsAQuarterOfTheSurfaceArea) {
    // Cauchy's formula, with the area from the parametric integral.
    for (const auto& [name, e] : standardShapes()) {
        const double mean =
            integrateSphere([&](const Vec3& w) { return e.projectedArea(w); }, 400) / (4 * kPi);
        EXPECT_NEAR(mean / (parametricSurfaceArea(e.semiAxes()) / 4), 1.0, 1e-4) << name;
        EXPECT_NEAR(e.meanProjectedArea(Normalization::Exact) / mean, 1.0, 1e-4) << name;
    }
}

TEST(Ellipsoid, NormalisedProjectedAreaAveragesToOne) {
    for (const auto& [name, e] : standardShapes()) {
        const Ellipsoid unit = e.normalized();
        const double mean = integrateSphere([&](const Vec3& w) { return unit.normalizedProjectedArea(w); },
                                            400) / (4 * kPi);
        EXPECT_NEAR(mean, 1.0, 1e-4) << name;
        EXPECT_NEAR(unit.meanProjectedArea(), 1.0, 1e-12) << name;
        // The paper's stand-in is exact for a sphere only.
        EXPECT_NEAR(e.normalized(Normalization::ThreeAxis).meanProjectedArea(Normalization::ThreeAxis),
                    1.0, 1e-12);
    }
    const Ellipsoid sphere = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(2, 2, 2));
    EXPECT_NEAR(sphere.meanProjectedArea(Normalization::ThreeAxis), sphere.meanProjectedArea(), 1e-12);
}

TEST(Ellipsoid, NegatingAnyAxisChangesNothing) {
    std::mt19937 rng(11);
    for (const auto& [name, e] : standardShapes()) {
        for (int axis = 0; axis < 3; ++axis) {
            Mat3 flipped = e.basis();
            flipped.col(axis) *= -1;
            const Ellipsoid f = Ellipsoid::fromAxes(flipped, e.semiAxes());
            EXPECT_TRUE(f.M().isApprox(e.M(), 1e-12)) << name;
            EXPECT_TRUE(f.S().isApprox(e.S(), 1e-12)) << name;
            for (int k = 0; k < 20; ++k) {
                const Vec3 w = randomDirection(rng);
                EXPECT_DOUBLE_EQ(f.projectedArea(w), e.projectedArea(w));
                EXPECT_NEAR(f.normalDistribution(w), e.normalDistribution(w),
                            1e-12 * e.normalDistribution(w));
                // Either sign of the direction: the primitive has no front.
                EXPECT_DOUBLE_EQ(e.projectedArea(-w), e.projectedArea(w));
                EXPECT_DOUBLE_EQ(e.normalDistribution(-w), e.normalDistribution(w));
            }
        }
    }
}

TEST(Ellipsoid, SggxFormulasFromSEqualNeyretsFromQ) {
    // Heitz et al.: projected area √(ωᵀSω) and D(m) = 1/(π √|S| (mᵀS⁻¹m)²), computed here from
    // the matrix S alone, against Neyret's A(ω) = π√(det M ωᵀQω) and f(N) = det M/(NᵀMN)².
    std::mt19937 rng(3);
    for (const auto& [name, e] : standardShapes()) {
        const Mat3 S = e.S();
        const Mat3 Sinv = S.inverse();
        const Mat3 M = e.M();
        const Mat3 Q = e.Q();
        const double detM = M.determinant();
        EXPECT_TRUE(S.isApprox(kPi * kPi * detM * Q, 1e-9)) << name;
        for (int k = 0; k < 50; ++k) {
            const Vec3 w = randomDirection(rng);
            const double sggxArea = std::sqrt(w.dot(S * w));
            const double neyretArea = kPi * std::sqrt(detM * w.dot(Q * w));
            EXPECT_NEAR(sggxArea / neyretArea, 1.0, 1e-9) << name;
            EXPECT_NEAR(e.projectedArea(w) / neyretArea, 1.0, 1e-9) << name;
            const double mSm = w.dot(Sinv * w);
            const double sggxD = 1 / (kPi * std::sqrt(S.determinant()) * mSm * mSm);
            const double neyretF = detM / std::pow(w.dot(M * w), 2);
            EXPECT_NEAR(sggxD / neyretF, 1.0, 1e-9) << name;
            EXPECT_NEAR(e.normalDistribution(w) / neyretF, 1.0, 1e-9) << name;
        }
    }
}

TEST(Ellipsoid, EveryConstructionRoundTrips) {
    for (const auto& [name, e] : standardShapes()) {
        for (const auto& back : {Ellipsoid::fromM(e.M()), Ellipsoid::fromQ(e.Q()), Ellipsoid::fromS(e.S())}) {
            ASSERT_TRUE(back.has_value()) << name;
            EXPECT_TRUE(back->M().isApprox(e.M(), 1e-9)) << name;
            EXPECT_TRUE(back->semiAxes().isApprox(e.semiAxes(), 1e-9)) << name;
        }
    }
}

TEST(Ellipsoid, SemiAxesFollowFromSigmaAsTheDesignStates) {
    // aᵢ = √(σⱼσₖ/(π σᵢ)) for S = R diag(σ²) Rᵀ.
    const Vec3 sigma(0.7, 1.9, 3.1);
    const auto e = Ellipsoid::fromS(Mat3(sigma.cwiseAbs2().asDiagonal()));
    ASSERT_TRUE(e);
    Vec3 expected(std::sqrt(sigma[1] * sigma[2] / (kPi * sigma[0])),
                  std::sqrt(sigma[0] * sigma[2] / (kPi * sigma[1])),
                  std::sqrt(sigma[0] * sigma[1] / (kPi * sigma[2])));
    std::sort(expected.data(), expected.data() + 3);
    EXPECT_TRUE(e->semiAxes().isApprox(expected, 1e-12)) << e->semiAxes().transpose();
}

TEST(Ellipsoid, TheRawSecondMomentIsNotProportionalToS) {
    // The design's counter-example: semi-axes (1, 0.5, 0.2). The second moment's normalised
    // diagonal is (0.074, 0.244, 1) while σ² ∝ (0.04, 0.16, 1): the two-step fit must not
    // stop at E.
    const Ellipsoid e = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(1, 0.5, 0.2));
    std::vector<Vec3> normals;
    std::vector<double> areas;
    sampleSurfaceNormals(e, 200, normals, areas);
    Mat3 E = Mat3::Zero();
    for (std::size_t i = 0; i < normals.size(); ++i) E += areas[i] * normals[i] * normals[i].transpose();
    Vec3 moment = E.diagonal() / E.diagonal().maxCoeff();
    EXPECT_NEAR(moment[0], 0.074, 1e-3);
    EXPECT_NEAR(moment[1], 0.244, 1e-3);
    const auto fit = Ellipsoid::fitNormals(normals, areas);
    const Vec3 sigmaSquared = fit->S().diagonal() / fit->S().diagonal().maxCoeff();
    EXPECT_NEAR(sigmaSquared[0], 0.04, 1e-3);
    EXPECT_NEAR(sigmaSquared[1], 0.16, 1e-3);
}

TEST(Ellipsoid, FitIgnoresUnusableNormalsAndReportsNothingToFit) {
    const std::vector<Vec3> normals = {Vec3::Zero(), Vec3(NAN, 0, 0), Vec3(0, 0, 1)};
    const std::vector<double> zeroWeights = {1, 1, 0};
    EXPECT_FALSE(Ellipsoid::fitNormals(normals, zeroWeights));
    EXPECT_FALSE(Ellipsoid::fitNormals({}, {}));
    EXPECT_FALSE(Ellipsoid::fromM(Mat3::Zero()));
    EXPECT_FALSE(Ellipsoid::fromS(Mat3::Constant(NAN)));
    EXPECT_FALSE(Ellipsoid::fromQ(-Mat3::Identity()));
}

void expectFiniteNonNegative(const Ellipsoid& e, const std::string& name) {
    std::mt19937 rng(13);
    std::vector<Vec3> directions = {e.basis().col(0), e.basis().col(1), e.basis().col(2),
                                    (e.basis().col(0) + e.basis().col(2)).normalized()};
    for (int k = 0; k < 50; ++k) directions.push_back(randomDirection(rng));
    for (const Vec3& w : directions) {
        for (double value : {e.projectedArea(w), e.normalDistribution(w), e.normalizedProjectedArea(w),
                             e.normalizedNormalDistribution(w),
                             e.normalizedProjectedArea(w, Normalization::ThreeAxis)}) {
            EXPECT_TRUE(std::isfinite(value)) << name;
            EXPECT_GE(value, 0) << name;
        }
        EXPECT_GT(e.normalized().projectedArea(w), 0) << name;
    }
    EXPECT_TRUE(std::isfinite(e.surfaceArea()) && e.surfaceArea() > 0) << name;
    EXPECT_TRUE(e.M().allFinite() && e.Q().allFinite() && e.S().allFinite()) << name;
}

TEST(Ellipsoid, ExtremeShapesStayFinite) {
    std::mt19937 rng(17);
    for (double ratio : {1e-8, 1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6, 1e8}) {
        const Mat3 R = randomRotation(rng);
        for (const Vec3& a : {Vec3(1, 1, ratio), Vec3(1, ratio, ratio), Vec3(1, std::sqrt(ratio), ratio)}) {
            const Ellipsoid e = Ellipsoid::fromAxes(R, a);
            expectFiniteNonNegative(e, "ratio " + std::to_string(ratio));
            EXPECT_GE(e.semiAxes()[0] / e.semiAxes()[2], kMinAxisRatio * (1 - 1e-12));
        }
    }
    // Exactly degenerate S: a needle (1,1,0) and a disc (1,0,0).
    const auto needle = Ellipsoid::fromS(Vec3(1, 1, 0).asDiagonal().toDenseMatrix());
    const auto disc = Ellipsoid::fromS(Vec3(1, 0, 0).asDiagonal().toDenseMatrix());
    ASSERT_TRUE(needle && disc);
    expectFiniteNonNegative(*needle, "S needle");
    expectFiniteNonNegative(*disc, "S disc");
    EXPECT_NEAR(std::abs(needle->basis().col(2).z()), 1.0, 1e-12) << "needle along z";
    EXPECT_NEAR(std::abs(disc->basis().col(0).x()), 1.0, 1e-12) << "disc facing x";
    // A flat Q (an infinite axis) and absolute scales far from 1.
    const auto infinite = Ellipsoid::fromQ(Vec3(1, 1, 0).asDiagonal().toDenseMatrix());
    ASSERT_TRUE(infinite);
    expectFiniteNonNegative(*infinite, "Q with an infinite axis");
    expectFiniteNonNegative(Ellipsoid::fromAxes(Mat3::Identity(), Vec3(1e30, 1e30, 1e29)), "huge");
    expectFiniteNonNegative(Ellipsoid::fromAxes(Mat3::Identity(), Vec3(1e-30, 2e-30, 3e-30)), "tiny");
}

}  // namespace
}  // namespace vtex::primitive
