/// @file
/// @brief The SGGX matrix of a micro-primitive as its six unique entries: the one form in which
/// the sampler, the octree and the renderer hand S to each other's maths.
///
/// S = R diag(σ²) Rᵀ is symmetric positive semi-definite; the projected area of the primitive
/// along a unit direction ω is A(ω) = √(ωᵀSω) (Heitz, Dupuy, Crassin, Dachsbacher, "The SGGX
/// microflake distribution", SIGGRAPH 2015, §3; DESIGN.md, "The micro-primitive").
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace vtex::primitive {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// The six unique entries of a symmetric 3×3 matrix, in double precision. Default: the identity
/// (a sphere of unit mean projected area).
struct SggxMatrix {
    double xx = 1, yy = 1, zz = 1, xy = 0, xz = 0, yz = 0;

    /// The diagonal and upper triangle of `m` (symmetric: the lower triangle is not read).
    static SggxMatrix fromUpper(const Mat3& m) { return {m(0, 0), m(1, 1), m(2, 2), m(0, 1), m(0, 2), m(1, 2)}; }
    Mat3 matrix() const {
        Mat3 m;
        m << xx, xy, xz, xy, yy, yz, xz, yz, zz;
        return m;
    }

    /// ωᵀSω, written out on the six entries: it runs per voxel per ray step, and the explicit
    /// form is half the work of rotating ω into the primitive's frame.
    double quadratic(const Vec3& w) const {
        return xx * w.x() * w.x() + yy * w.y() * w.y() + zz * w.z() * w.z() +
               2 * (xy * w.x() * w.y() + xz * w.x() * w.z() + yz * w.y() * w.z());
    }
    /// pᵀSq.
    double bilinear(const Vec3& p, const Vec3& q) const {
        return xx * p.x() * q.x() + yy * p.y() * q.y() + zz * p.z() * q.z() + xy * (p.x() * q.y() + p.y() * q.x()) +
               xz * (p.x() * q.z() + p.z() * q.x()) + yz * (p.y() * q.z() + p.z() * q.y());
    }
    /// A(ω) = √(ωᵀSω) for a unit ω (either sign). S's eigenvalues are ≥ 0, but rounding can
    /// push ωᵀSω a few ulps below zero along a needle's axis: hence the max.
    double projectedArea(const Vec3& w) const { return std::sqrt(std::max(quadratic(w), 0.0)); }

    friend bool operator==(const SggxMatrix&, const SggxMatrix&) = default;
};

}  // namespace vtex::primitive
