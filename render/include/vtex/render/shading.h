/// @file
/// @brief How a voxel's micro-primitive reflects light: the paper's reference integration and a
/// fast quadrature over SGGX visible normals.
///
/// Both return R(l, v) = kd·diffuse + ks·specular of octree/reflectance.h: the radiance the
/// ellipsoid sends toward v, averaged over its visible apparent area, per unit irradiance from
/// l, for the energy-normalised Phong BRDF of its micro-surfaces. The ellipsoid is given as its
/// SGGX matrix S (VoxelData::s, any scale), l and v are unit vectors in the same (reference)
/// frame, pointing away from the primitive.
#pragma once

#include <vtex/octree/reflectance.h>

#include <Eigen/Core>

#include <array>

namespace vtex::octree {
struct VoxelData;
}

namespace vtex::render {

/// The six unique entries of an SGGX matrix S (symmetric, positive semi-definite).
struct SggxMatrix {
    double xx = 1, yy = 1, zz = 1, xy = 0, xz = 0, yz = 0;
    /// ωᵀSω.
    double quadratic(const Eigen::Vector3d& w) const {
        return xx * w.x() * w.x() + yy * w.y() * w.y() + zz * w.z() * w.z() +
               2 * (xy * w.x() * w.y() + xz * w.x() * w.z() + yz * w.y() * w.z());
    }
    /// pᵀSq.
    double bilinear(const Eigen::Vector3d& p, const Eigen::Vector3d& q) const {
        return xx * p.x() * q.x() + yy * p.y() * q.y() + zz * p.z() * q.z() + xy * (p.x() * q.y() + p.y() * q.x()) +
               xz * (p.x() * q.z() + p.z() * q.x()) + yz * (p.y() * q.z() + p.z() * q.y());
    }
};

/// The normalised S a voxel stores (octree/voxel.h: S = R diag(σ²) Rᵀ, R a unit quaternion).
SggxMatrix voxelS(const octree::VoxelData& voxel);

/// The paper's method (Neyret 1994 §3.2): octree::phongReflectanceApparentEllipse on the
/// ellipsoid of S, `samplesPerAxis` grid cells per axis of the apparent ellipse.
octree::ReflectanceFactors reflectanceReference(const SggxMatrix& s, const Eigen::Vector3d& light,
                                                const Eigen::Vector3d& view, double shininess,
                                                int samplesPerAxis = 24);

/// The fast path. Since f(N)(N·v)⁺ / A(v) is the distribution of visible normals D_v (Heitz,
/// Dupuy, Crassin, Dachsbacher, "The SGGX microflake distribution", SIGGRAPH 2015, §4 and
/// Listing 3 for its closed-form sampling), R(l,v) = E_{N∼D_v}[(N·l)⁺ ρ(N,l,v)] exactly; it is
/// estimated with `samples` fixed points (a Fibonacci lattice on the unit disc mapped through
/// the closed-form VNDF sampler), so the result is deterministic and smooth in l and v.
///
/// Along one ray segment v is constant, and so is l for a directional light, while S changes
/// from voxel to voxel: the kernel keeps what depends on (l, v, shininess, samples) alone, so
/// that a call only projects S into the frame around v and sums the lattice. The cost per call
/// is measured by bench/render_shading_bench, the error against the reference by
/// bench/render_reflectance_error.
class ReflectanceKernel {
public:
    ReflectanceKernel(const Eigen::Vector3d& light, const Eigen::Vector3d& view, double shininess, int samples = 16);
    octree::ReflectanceFactors operator()(const SggxMatrix& s) const;

private:
    struct Lattice;
    const Lattice* mLattice;
    /// S in the orthonormal basis (wk, wj, wi = view) as a linear map of S's six entries
    /// (xx, yy, zz, xy, xz, yz) to (kk, jj, ii, kj, ki, ji): row e holds the six outputs'
    /// coefficients of entry e.
    alignas(16) std::array<double, 36> mProjection;
    Eigen::Vector3f mLight;  ///< light in (wk, wj, wi)
    double mShininess;
    int mWholePower;  ///< the shininess when it is a whole number in [0, 1024], else −1
    float mCosCutoff;
    double mDiffuseScale, mSpecularScale;
};

/// ReflectanceKernel(light, view, shininess, samples)(s), for a single evaluation.
octree::ReflectanceFactors reflectanceFast(const SggxMatrix& s, const Eigen::Vector3d& light,
                                           const Eigen::Vector3d& view, double shininess, int samples = 16);

}  // namespace vtex::render
