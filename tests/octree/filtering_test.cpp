// Filtering rules of DESIGN.md, "Octree: filtering and compression": conservative where they
// must be (copies, opposite bases), and different in the documented ways on crossed discs and
// crossed fibres, with the filter error measuring the difference.
#include "../primitive/shapes.h"

#include <vtex/octree/filtering.h>

#include <gtest/gtest.h>

#include <numbers>

namespace vtex::octree {
namespace {

using primitive::test::randomDirection;
using primitive::test::randomRotation;
using primitive::test::standardShapes;

const FilterRule kRules[] = {FilterRule::Neyret, FilterRule::Sggx};

std::string ruleName(FilterRule rule) { return rule == FilterRule::Neyret ? "neyret" : "sggx"; }

TEST(Filtering, CopiesOfOneEllipsoidWithAnyWeightsGiveItBack) {
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> weight(0.01, 10);
    for (const auto& [name, e] : standardShapes()) {
        for (FilterRule rule : kRules) {
            // Copies at different sizes: each child is normalised before it is averaged.
            const std::vector<Ellipsoid> children = {e, e.scaled(3.0), e.scaled(0.1)};
            const std::vector<double> weights = {weight(rng), weight(rng), weight(rng)};
            const auto result = filterEllipsoids(children, weights, rule);
            ASSERT_TRUE(result) << name;
            EXPECT_TRUE(result->M().isApprox(e.normalized().M(), 1e-6)) << name << " " << ruleName(rule);
            EXPECT_LT(filterError(*result, children, weights), 1e-6 * 2 / std::sqrt(std::numbers::pi))
                << name;
        }
    }
}

TEST(Filtering, AnEllipsoidAndItsOppositeBasisFilterToItself) {
    for (const auto& [name, e] : standardShapes()) {
        const Ellipsoid opposite = Ellipsoid::fromAxes(-e.basis(), e.semiAxes());
        for (FilterRule rule : kRules) {
            const std::vector<Ellipsoid> children = {e, opposite};
            const std::vector<double> weights = {1, 1};
            const auto result = filterEllipsoids(children, weights, rule);
            ASSERT_TRUE(result);
            EXPECT_TRUE(result->M().isApprox(e.normalized().M(), 1e-6)) << name << " " << ruleName(rule);
        }
    }
}

TEST(Filtering, ZeroWeightChildrenAreIgnoredAndNoWeightGivesNothing) {
    const Ellipsoid needle = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(10, 1, 1));
    const Ellipsoid disc = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(1, 10, 10));
    const std::vector<Ellipsoid> children = {needle, disc};
    for (FilterRule rule : kRules) {
        const auto result = filterEllipsoids(children, std::vector<double>{2, 0}, rule);
        ASSERT_TRUE(result);
        EXPECT_TRUE(result->M().isApprox(needle.normalized().M(), 1e-9));
        EXPECT_FALSE(filterEllipsoids(children, std::vector<double>{0, 0}, rule));
    }
}

Ellipsoid needleAlong(const Vec3& axis) {
    Mat3 basis;
    basis.col(2) = axis;
    basis.col(0) = axis.unitOrthogonal();
    basis.col(1) = axis.cross(basis.col(0));
    return Ellipsoid::fromAxes(basis, Vec3(1e-4, 1e-4, 1));
}

Ellipsoid discFacing(const Vec3& normal) {
    Mat3 basis;
    basis.col(0) = normal;
    basis.col(1) = normal.unitOrthogonal();
    basis.col(2) = normal.cross(basis.col(1));
    return Ellipsoid::fromAxes(basis, Vec3(1e-4, 1, 1));
}

// The mean projected area of a weighted set of normalised children along ω: what the filtered
// primitive should block.
double mixtureArea(const std::vector<Ellipsoid>& children, const Vec3& w) {
    double sum = 0;
    for (const auto& c : children) sum += c.normalized().projectedArea(w);
    return sum / children.size();
}

TEST(Filtering, TwoOrthogonalNeedlesFilterToAShapeSymmetricAboutTheThirdAxis) {
    std::mt19937 rng(2);
    const Mat3 R = randomRotation(rng);
    const std::vector<Ellipsoid> children = {needleAlong(R.col(0)), needleAlong(R.col(1))};
    for (FilterRule rule : kRules) {
        const auto result = filterEllipsoids(children, std::vector<double>{1, 1}, rule);
        ASSERT_TRUE(result);
        for (int k = 0; k < 16; ++k) {
            const double angle = 2 * std::numbers::pi * k / 16;
            const Vec3 inPlane = std::cos(angle) * R.col(0) + std::sin(angle) * R.col(1);
            EXPECT_NEAR(result->projectedArea(inPlane), result->projectedArea(R.col(0)), 1e-9)
                << ruleName(rule);
        }
    }
}

// Filter errors measured on the default 512-point set (the tests print them):
//   crossed discs:  neyret 1.21, sggx 0.667
//   crossed fibres: neyret 0.849, sggx 1.24
// Neither rule wins both: on fibres the paper's disc puts its normals at the two great
// circles' crossing points, which the fibres' NDFs share, while SGGX spreads them.
TEST(Filtering, CrossedDiscsNeyretInventsAreaAlongTheCommonLineSggxOverestimatesAlongTheNormals) {
    std::mt19937 rng(4);
    const Mat3 R = randomRotation(rng);
    const std::vector<Ellipsoid> children = {discFacing(R.col(0)), discFacing(R.col(1))};
    const std::vector<double> weights = {1, 1};
    const Vec3 commonLine = R.col(2);
    const auto neyret = filterEllipsoids(children, weights, FilterRule::Neyret);
    const auto sggx = filterEllipsoids(children, weights, FilterRule::Sggx);
    ASSERT_TRUE(neyret && sggx);

    // The mixture blocks nothing along the common line (both discs are edge-on).
    EXPECT_LT(mixtureArea(children, commonLine), 1e-3);
    EXPECT_GT(neyret->projectedArea(commonLine), 0.3) << "the paper's rule invents normals";
    EXPECT_LT(sggx->projectedArea(commonLine), 1e-3) << "SGGX keeps zero-area directions at zero";

    // The raw mean of the normalised S blocks √2 times the mixture along each disc's normal
    // (Jensen's inequality); the filtered primitive is that S renormalised to unit mean area,
    // a needle of mean area √2·π/4, so the overestimate it carries into Â is 4/π.
    const Mat3 meanS = 0.5 * (children[0].normalized().S() + children[1].normalized().S());
    const Vec3 normal = R.col(0);
    EXPECT_NEAR(std::sqrt(normal.dot(meanS * normal)) / mixtureArea(children, normal), std::sqrt(2.0), 1e-3);
    EXPECT_TRUE(sggx->S().isApprox(meanS / std::pow(std::sqrt(2.0) * std::numbers::pi / 4, 2), 1e-3));
    EXPECT_NEAR(sggx->projectedArea(normal) / mixtureArea(children, normal), 4 / std::numbers::pi, 1e-3);

    const double neyretError = filterError(*neyret, children, weights);
    const double sggxError = filterError(*sggx, children, weights);
    std::cout << "crossed discs filter error: neyret " << neyretError << ", sggx " << sggxError << "\n";
    EXPECT_NEAR(neyretError, 1.21, 0.01);
    EXPECT_NEAR(sggxError, 0.667, 0.01);
}

TEST(Filtering, CrossedFibresNeyretCollapsesToADiscSggxKeepsAreaInTheirPlane) {
    std::mt19937 rng(8);
    const Mat3 R = randomRotation(rng);
    const std::vector<Ellipsoid> children = {needleAlong(R.col(0)), needleAlong(R.col(1))};
    const std::vector<double> weights = {1, 1};
    const auto neyret = filterEllipsoids(children, weights, FilterRule::Neyret);
    const auto sggx = filterEllipsoids(children, weights, FilterRule::Sggx);
    ASSERT_TRUE(neyret && sggx);
    // Neyret: the mean of the two needles' M is a disc in their plane.
    EXPECT_NEAR(std::abs(neyret->basis().col(0).dot(R.col(2))), 1.0, 1e-9);
    EXPECT_LT(neyret->semiAxes()[0] / neyret->semiAxes()[2], 1e-3) << "a disc";
    // Seen along the diagonal of their plane each fibre shows its side; the disc shows its edge.
    const Vec3 diagonal = (R.col(0) + R.col(1)).normalized();
    const double mixtureInPlane = mixtureArea(children, diagonal);
    EXPECT_LT(neyret->projectedArea(diagonal), 0.1 * mixtureInPlane);
    EXPECT_GT(sggx->projectedArea(diagonal), 0.5 * mixtureInPlane);

    const double neyretError = filterError(*neyret, children, weights);
    const double sggxError = filterError(*sggx, children, weights);
    std::cout << "crossed fibres filter error: neyret " << neyretError << ", sggx " << sggxError << "\n";
    EXPECT_NEAR(neyretError, 0.849, 0.01);
    EXPECT_NEAR(sggxError, 1.24, 0.01);
}

// The octree build reads each child through storedFilterForm (no Ellipsoid, no elliptic
// integral) where filterEllipsoids rebuilds it: packed children of every standard shape, at
// random sizes and orientations, give the same parent within float rounding of the stored σ.
TEST(Filtering, StoredFormsGiveTheParentTheEllipsoidsGive) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> weight(0.01, 10), logScale(-3, 3);
    std::vector<Ellipsoid> shapes;
    for (const auto& [name, e] : standardShapes()) shapes.push_back(e);
    std::uniform_int_distribution<std::size_t> pick(0, shapes.size() - 1), count(1, 8);
    for (int trial = 0; trial < 400; ++trial) {
        std::vector<VoxelData> voxels(count(rng));
        std::vector<Ellipsoid> children;
        std::vector<Mat3> formsN, formsS;
        std::vector<double> weights;
        for (VoxelData& v : voxels) {
            const Ellipsoid e = Ellipsoid::fromAxes(randomRotation(rng) * shapes[pick(rng)].basis(),
                                                    shapes[pick(rng)].semiAxes() * std::exp(logScale(rng)));
            v.density = float(weight(rng));
            packEllipsoid(e, v);
            const auto unpacked = unpackEllipsoid(v);
            ASSERT_TRUE(unpacked);
            // What storedFilterForm takes as exact: the stored primitive has unit mean area.
            ASSERT_NEAR(unpacked->meanProjectedArea(), 1.0, 1e-6);
            children.push_back(*unpacked);
            formsN.push_back(*storedFilterForm(v, FilterRule::Neyret));
            formsS.push_back(*storedFilterForm(v, FilterRule::Sggx));
            weights.push_back(v.density);
        }
        for (FilterRule rule : kRules) {
            const auto reference = filterEllipsoids(children, weights, rule);
            const auto stored = filterForms(rule == FilterRule::Neyret ? formsN : formsS, weights, rule);
            ASSERT_TRUE(reference && stored);
            EXPECT_TRUE(stored->S().isApprox(reference->S(), 1e-6)) << ruleName(rule) << " trial " << trial;
        }
    }
    VoxelData empty;
    EXPECT_FALSE(storedFilterForm(empty, FilterRule::Sggx));
}

TEST(Filtering, SphericalPointSetIsUnitAndBalanced) {
    const auto points = sphericalPointSet(512);
    ASSERT_EQ(points.size(), 512u);
    Vec3 centroid = Vec3::Zero();
    Mat3 moment = Mat3::Zero();
    for (const Vec3& p : points) {
        EXPECT_NEAR(p.norm(), 1.0, 1e-12);
        centroid += p;
        moment += p * p.transpose();
    }
    EXPECT_LT((centroid / 512).norm(), 1e-2);
    EXPECT_TRUE((moment / 512).isApprox(Mat3::Identity() / 3, 1e-2));
    EXPECT_EQ(sphericalPointSet(512).data(), points.data()) << "cached, not rebuilt";
}

TEST(Filtering, FilterErrorOfASphereAgainstADiscIsTheirNdfDistance) {
    // Golden value: normalised NDFs f̂ = f/Ā are 1/π for the sphere; for a disc they
    // concentrate at ±n. The L2 distance squared is ‖f̂_s‖² + ‖f̂_d‖² − 2⟨f̂_s, f̂_d⟩, and
    // ⟨f̂_s, f̂_d⟩ = (1/π)·4 whatever the disc, ‖f̂_s‖² = 4/π.
    const Ellipsoid sphere;
    const Ellipsoid disc = Ellipsoid::fromAxes(Mat3::Identity(), Vec3(0.3, 1, 1));
    const std::vector<Ellipsoid> children = {disc};
    const std::vector<double> weights = {1};
    const auto points = sphericalPointSet(1 << 16);
    double discNormSquared = 0;
    for (const Vec3& p : points) discNormSquared += std::pow(disc.normalizedNormalDistribution(p), 2);
    discNormSquared *= 4 * std::numbers::pi / points.size();
    const double expected = std::sqrt(discNormSquared + 4 / std::numbers::pi - 8 / std::numbers::pi);
    EXPECT_NEAR(filterError(sphere, children, weights, points), expected, 1e-3);
}

}  // namespace
}  // namespace vtex::octree
