// The two-step fit of a primitive to surface normals (Ellipsoid::fitNormals) against the shapes
// the normals came from, and the octree's measure of a fit (fitError) on those same normals: 0
// for the facets of one ellipsoid, a disc and a fibre.
#include "../primitive/shapes.h"

#include <vtex/octree/filtering.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace vtex::octree {
namespace {

using primitive::kMinAxisRatio;
using primitive::test::randomRotation;
using primitive::test::sampleSurfaceNormals;
using primitive::test::standardShapes;

constexpr double kPi = std::numbers::pi;

TEST(EllipsoidFit, TwoStepFitRecoversAnEllipsoidFromItsSurfaceNormals) {
    std::mt19937 rng(5);
    for (const auto& [name, e] : standardShapes()) {
        std::vector<Vec3> normals;
        std::vector<double> areas;
        sampleSurfaceNormals(e, 200, normals, areas);
        const auto fit = Ellipsoid::fitNormals(normals, areas);
        ASSERT_TRUE(fit) << name;
        EXPECT_TRUE(fit->normalized().M().isApprox(e.normalized().M(), 2e-3))
            << name << "\nfit axes " << fit->semiAxes().transpose() << "\ntrue axes "
            << e.semiAxes().transpose();
        EXPECT_LT(fitError(*fit, normals, areas), 1e-3) << name;
    }
}

TEST(EllipsoidFit, TwoStepFitRecoversADiscAndAFibre) {
    std::mt19937 rng(6);
    const Mat3 R = randomRotation(rng);
    // A flat square: every facet has the normal R·z (either sign).
    std::vector<Vec3> normals = {R.col(2), -R.col(2), R.col(2)};
    std::vector<double> areas = {0.5, 0.25, 0.25};
    auto disc = Ellipsoid::fitNormals(normals, areas);
    ASSERT_TRUE(disc);
    EXPECT_NEAR(std::abs(disc->basis().col(0).dot(R.col(2))), 1.0, 1e-12) << "short axis = normal";
    EXPECT_NEAR(disc->semiAxes()[0] / disc->semiAxes()[2], kMinAxisRatio, 1e-12);
    EXPECT_NEAR(disc->semiAxes()[1], disc->semiAxes()[2], 1e-12);
    EXPECT_LT(fitError(*disc, normals, areas), 1e-3);

    // The side of a cylinder along R·x: normals all around the axis, equal areas.
    normals.clear();
    areas.clear();
    for (int k = 0; k < 360; ++k) {
        const double t = 2 * kPi * k / 360;
        normals.push_back(std::cos(t) * R.col(1) + std::sin(t) * R.col(2));
        areas.push_back(1.0);
    }
    auto fibre = Ellipsoid::fitNormals(normals, areas);
    ASSERT_TRUE(fibre);
    EXPECT_NEAR(std::abs(fibre->basis().col(2).dot(R.col(0))), 1.0, 1e-9) << "long axis = cylinder axis";
    EXPECT_NEAR(fibre->semiAxes()[0] / fibre->semiAxes()[2], kMinAxisRatio, 1e-9);
    EXPECT_NEAR(fibre->semiAxes()[0], fibre->semiAxes()[1], 1e-9);
    EXPECT_LT(fitError(*fibre, normals, areas), 1e-3);
}

}  // namespace
}  // namespace vtex::octree
