// The Phong reflectance of one primitive (Neyret 1994 §3.2) by the paper's apparent-ellipse
// sampling and by quadrature over the normals: they agree with each other, with the closed
// form for a Lambertian sphere, and with energy conservation.
#include "shapes.h"

#include <vtex/primitive/reflectance.h>

#include <gtest/gtest.h>

#include <numbers>

namespace vtex::primitive {
namespace {

using test::integrateSphere;
using test::randomDirection;
using test::randomRotation;

constexpr double kPi = std::numbers::pi;

// The phase function of a Lambertian sphere of albedo 1, as the radiance averaged over its
// apparent disc per unit irradiance: (2 / 3π²) (sin g + (π − g) cos g), g the phase angle.
double lambertianSpherePhase(const Vec3& light, const Vec3& view) {
    const double g = std::acos(std::clamp(light.dot(view), -1.0, 1.0));
    return 2 / (3 * kPi * kPi) * (std::sin(g) + (kPi - g) * std::cos(g));
}

TEST(Reflectance, BothMethodsMatchTheLambertianSpherePhaseFunction) {
    std::mt19937 rng(31);
    const Ellipsoid sphere = Ellipsoid::fromAxes(randomRotation(rng), Vec3(2, 2, 2));
    for (int k = 0; k < 40; ++k) {
        const Vec3 l = randomDirection(rng), v = randomDirection(rng);
        const double expected = lambertianSpherePhase(l, v);
        EXPECT_NEAR(phongReflectanceApparentEllipse(sphere, l, v, 10, 256).diffuse, expected, 1e-3);
        EXPECT_NEAR(phongReflectanceNormalQuadrature(sphere, l, v, 10, 256).diffuse, expected, 1e-3);
    }
}

// Random shapes with axis ratios up to 1:20, random lights and views, shininess 1 to 50.
// Agreement: |a − b| ≤ 2e-3 + 2% of the value for both terms, with the paper's method at 256
// cells per axis (~25,700 facets) and the quadrature at 256 rings (131,072 normals).
TEST(Reflectance, ApparentEllipseSamplingAgreesWithQuadratureOverNormals) {
    std::mt19937 rng(37);
    std::uniform_real_distribution<double> axis(0.05, 1.0), shininess(1, 50);
    for (int k = 0; k < 60; ++k) {
        const Ellipsoid e =
            Ellipsoid::fromAxes(randomRotation(rng), Vec3(axis(rng), axis(rng), axis(rng)));
        const Vec3 l = randomDirection(rng), v = randomDirection(rng);
        const double n = shininess(rng);
        const auto a = phongReflectanceApparentEllipse(e, l, v, n, 256);
        const auto b = phongReflectanceNormalQuadrature(e, l, v, n, 256);
        EXPECT_NEAR(a.diffuse, b.diffuse, 2e-3 + 0.02 * b.diffuse) << "case " << k;
        EXPECT_NEAR(a.specular, b.specular, 2e-3 + 0.02 * b.specular) << "case " << k << " n=" << n;
    }
}

TEST(Reflectance, AlbedoOneReflectsAllTheInterceptedEnergyAndNoMore) {
    // Σ over view directions of R(l, v) · A(v) is the power scattered; A(l) the power
    // intercepted. A convex Lambertian primitive of albedo 1 absorbs nothing (equality); the
    // energy-normalised Phong lobe never reflects more than it receives (kd + ks = 1).
    std::mt19937 rng(41);
    for (int k = 0; k < 4; ++k) {
        const Ellipsoid e = Ellipsoid::fromAxes(randomRotation(rng), Vec3(0.2 + k * 0.25, 1, 0.6));
        const Vec3 l = randomDirection(rng);
        const double intercepted = e.projectedArea(l);
        const double diffusePower = integrateSphere(
            [&](const Vec3& v) { return phongReflectanceNormalQuadrature(e, l, v, 0, 48).diffuse * e.projectedArea(v); },
            32);
        EXPECT_NEAR(diffusePower / intercepted, 1.0, 1e-2);
        const double mixedPower = integrateSphere(
            [&](const Vec3& v) {
                const auto r = phongReflectanceNormalQuadrature(e, l, v, 8, 48);
                return (0.5 * r.diffuse + 0.5 * r.specular) * e.projectedArea(v);
            },
            32);
        EXPECT_LE(mixedPower / intercepted, 1.0 + 1e-2);
        EXPECT_GT(mixedPower / intercepted, 0.5);
    }
}

TEST(Reflectance, DiffuseRadianceNeverExceedsThatOfAFacetFacingTheLight) {
    std::mt19937 rng(43);
    std::uniform_real_distribution<double> axis(1e-3, 1.0);
    for (int k = 0; k < 200; ++k) {
        const Ellipsoid e = Ellipsoid::fromAxes(randomRotation(rng), Vec3(axis(rng), axis(rng), axis(rng)));
        const Vec3 l = randomDirection(rng), v = randomDirection(rng);
        const auto r = phongReflectanceApparentEllipse(e, l, v, 20, 32);
        EXPECT_LE(r.diffuse, 1 / kPi + 1e-12);
        EXPECT_GE(r.diffuse, 0);
        EXPECT_GE(r.specular, 0);
    }
}

TEST(Reflectance, ADiscLitOnOneFaceAndSeenFromTheOtherIsBlack) {
    const Ellipsoid disc = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(1, 1, 1e-4));
    const Vec3 light = Vec3(0.3, 0.1, 1).normalized();
    const Vec3 same = Vec3(-0.2, 0.4, 1).normalized();
    const Vec3 other = Vec3(-0.2, 0.4, -1).normalized();
    for (auto method : {&phongReflectanceApparentEllipse, &phongReflectanceNormalQuadrature}) {
        const auto lit = method(disc, light, same, 10, 128);
        const auto behind = method(disc, light, other, 10, 128);
        // Seen from the lit side a thin disc is a flat facet: R = cos θ_l / π.
        EXPECT_NEAR(lit.diffuse, light.z() / kPi, 1e-3);
        EXPECT_LT(behind.diffuse, 1e-3 * lit.diffuse);
        EXPECT_LT(behind.specular, 1e-3 * std::max(lit.specular, 1e-3));
    }
}

TEST(Reflectance, GrazingAndAxialDirectionsOnNeedlesAndDiscsStayFinite) {
    std::mt19937 rng(47);
    const Mat3 R = randomRotation(rng);
    const std::vector<Ellipsoid> shapes = {
        Ellipsoid::fromAxes(R, Vec3(1, 1, 0)), Ellipsoid::fromAxes(R, Vec3(1, 0, 0)),
        Ellipsoid::fromAxes(R, Vec3(1, 1e-9, 1e-9)), *Ellipsoid::fromS(Vec3(1, 0, 0).asDiagonal().toDenseMatrix()),
        *Ellipsoid::fromS(Vec3(1, 1, 0).asDiagonal().toDenseMatrix())};
    for (const Ellipsoid& e : shapes) {
        std::vector<Vec3> directions;
        for (int c = 0; c < 3; ++c) {
            directions.push_back(e.basis().col(c));
            directions.push_back(-e.basis().col(c));
        }
        directions.push_back((e.basis().col(0) + e.basis().col(1)).normalized());
        for (const Vec3& l : directions) {
            for (const Vec3& v : directions) {
                for (double n : {0.0, 1.0, 1e4}) {
                    for (const auto& r : {phongReflectanceApparentEllipse(e, l, v, n, 16),
                                          phongReflectanceNormalQuadrature(e, l, v, n, 16)}) {
                        EXPECT_TRUE(std::isfinite(r.diffuse) && r.diffuse >= 0);
                        EXPECT_TRUE(std::isfinite(r.specular) && r.specular >= 0);
                    }
                }
            }
        }
    }
}

}  // namespace
}  // namespace vtex::primitive
