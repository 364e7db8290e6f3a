// The stored form of the primitive (quaternion and σ) and the one way back to S, and the SGGX
// type's forms against Eigen's matrix products.
#include "shapes.h"

#include <vtex/primitive/packing.h>
#include <vtex/primitive/sggx.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

namespace vtex::primitive {
namespace {

using test::randomDirection;
using test::randomRotation;
using test::standardShapes;

TEST(Packing, KeepsDiscsAndNeedles) {
    const Mat3 R = Eigen::Quaterniond(0.3, -0.2, 0.8, 0.1).normalized().toRotationMatrix();
    for (const Vec3& axes : {Vec3(1e-5, 1, 1), Vec3(1, 1, 1e5), Vec3(0.3, 1.0, 2.5)}) {
        const Ellipsoid e = Ellipsoid::fromAxes(R, axes).normalized();
        const PackedPrimitive p = pack(e);
        const auto back = unpackEllipsoid(p.rotation, p.sigma);
        ASSERT_TRUE(back);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(back->semiAxes()[k] / e.semiAxes()[k], 1.0, 1e-4) << axes.transpose();
        // S itself, including the eigenvalues 1e-8 below the largest that 6 floats would lose.
        const Mat3 R2 = back->basis().transpose() * e.basis();  // the same axes, up to sign/order
        const Vec3& a = e.semiAxes();
        auto distinct = [](double x, double y) { return std::abs(x - y) > 1e-9 * std::max(x, y); };
        for (int k = 0; k < 3; ++k)
            if ((k == 0 || distinct(a[k], a[k - 1])) && (k == 2 || distinct(a[k], a[k + 1]))) {
                EXPECT_GT(std::abs(R2(k, k)), 0.9999) << axes.transpose();
            }
        EXPECT_LT((unpackS(p.rotation, p.sigma).matrix() - e.S()).norm(), 1e-6 * e.S().norm());
    }
}

// A stored quaternion is unit only to float precision, and a file's to the 1e-3 its reader
// accepts: S must not scale with |q|² (as a rotation matrix written for unit q would make it).
TEST(Packing, UnpackedSDoesNotDependOnTheQuaternionsNorm) {
    for (const auto& [name, e] : standardShapes()) {
        const PackedPrimitive p = pack(e);
        const SggxMatrix unit = unpackS(p.rotation, p.sigma);
        for (const float scale : {0.999f, 1.0009f, 3.0f}) {
            std::array<float, 4> q = p.rotation;
            for (float& c : q) c *= scale;
            const SggxMatrix scaled = unpackS(q, p.sigma);
            EXPECT_LT((scaled.matrix() - unit.matrix()).norm(), 1e-6 * unit.matrix().norm()) << name << " " << scale;
        }
        // Unit mean apparent area, whatever the size packed: the mean of √(ωᵀSω) is 1.
        EXPECT_NEAR(Ellipsoid::fromS(unit.matrix())->meanProjectedArea(), 1.0, 1e-5) << name;
    }
    const SggxMatrix zero = unpackS({0, 0, 0, 0}, {1, 1, 1});
    EXPECT_EQ(zero, (SggxMatrix{0, 0, 0, 0, 0, 0}));
    EXPECT_EQ(unpackS(kIsotropic.rotation, kIsotropic.sigma), SggxMatrix{});
}

TEST(Packing, QuaternionIsUnitWithANonNegativeW) {
    for (const auto& [name, e] : standardShapes()) {
        const PackedPrimitive p = pack(e);
        double norm = 0;
        for (float c : p.rotation) norm += double(c) * c;
        EXPECT_NEAR(std::sqrt(norm), 1.0, 1e-6) << name;
        EXPECT_GE(p.rotation[3], 0.0f) << name;
    }
}

// The six-entry forms against the full matrix: ωᵀSω, pᵀSq, and A(ω) = √(ωᵀSω) as the
// ellipsoid computes it from its semi-axes' π aⱼaₖ (the same S).
TEST(Sggx, FormsEqualTheMatrixProducts) {
    std::mt19937 rng(4);
    for (const auto& [name, e] : standardShapes()) {
        const SggxMatrix s = e.sggx();
        const Mat3 m = e.S();
        EXPECT_EQ(SggxMatrix::fromUpper(m), s) << name;
        EXPECT_TRUE(s.matrix().isApprox(m, 1e-12)) << name;
        for (int k = 0; k < 20; ++k) {
            const Vec3 w = randomDirection(rng), q = randomDirection(rng);
            const double scale = m.norm();
            EXPECT_NEAR(s.quadratic(w), w.dot(m * w), 1e-12 * scale) << name;
            EXPECT_NEAR(s.bilinear(w, q), w.dot(m * q), 1e-12 * scale) << name;
            EXPECT_NEAR(s.bilinear(w, q), s.bilinear(q, w), 1e-12 * scale) << name;
            EXPECT_EQ(s.projectedArea(w), e.projectedArea(w)) << name;
            EXPECT_GE(s.projectedArea(w), 0.0) << name;
        }
    }
    // A needle's axis: ωᵀSω is 0 up to rounding, which may fall below zero; A stays a number.
    const Mat3 R = randomRotation(rng);
    const SggxMatrix needle = SggxMatrix::fromUpper(R * Vec3(1, 1, 0).asDiagonal() * R.transpose());
    EXPECT_NEAR(needle.projectedArea(R.col(2)), 0.0, 1e-7);
    EXPECT_FALSE(std::isnan(needle.projectedArea(R.col(2))));
}

}  // namespace
}  // namespace vtex::primitive
