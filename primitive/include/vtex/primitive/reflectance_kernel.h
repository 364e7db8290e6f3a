/// @file
/// @brief The fast reflectance of a micro-primitive: a quadrature over SGGX visible normals.
///
/// It returns R(l, v) = kd·diffuse + ks·specular of reflectance.h: the radiance the ellipsoid
/// sends toward v, averaged over its visible apparent area, per unit irradiance from l, for the
/// energy-normalised Phong BRDF of its micro-surfaces. The ellipsoid is given as its SGGX matrix
/// S (any scale); l and v are unit vectors in the same (reference) frame, pointing away from the
/// primitive. reflectanceReference (reflectance.h) is the paper's method on the same input.
#pragma once

#include <vtex/primitive/reflectance.h>
#include <vtex/primitive/sggx.h>

#include <Eigen/Core>

#include <array>

namespace vtex::primitive {

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
    ReflectanceFactors operator()(const SggxMatrix& s) const;

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
ReflectanceFactors reflectanceFast(const SggxMatrix& s, const Eigen::Vector3d& light, const Eigen::Vector3d& view,
                                   double shininess, int samples = 16);

}  // namespace vtex::primitive
