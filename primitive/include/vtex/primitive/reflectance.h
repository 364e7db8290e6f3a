/// @file
/// @brief The Phong reflectance of one micro-primitive (Neyret 1994 §3.2), by two methods.
///
/// The radiance the ellipsoid sends toward the viewer, averaged over its visible apparent
/// area, per unit irradiance from a light: R(l, v) = ∫_{N·v>0, N·l>0} f(N) (N·v)(N·l)
/// ρ(N, l, v) dN / A(v), with the energy-normalised Phong BRDF of DESIGN.md, "Radiometry":
/// ρ = kd/π + ks (n+2)/(2π) cosⁿα, α the angle between v and the mirror direction of l about
/// N. The ellipsoid is convex, so a facet is visible iff N·v > 0 and lit iff N·l > 0: a disc
/// lit on one face and seen from the other is black. R is linear in kd and ks, so both
/// methods return the two factors and the caller multiplies its colours in. The fast method the
/// renderer uses by default is in reflectance_kernel.h.
#pragma once

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/sggx.h>

namespace vtex::primitive {

/// R(l, v) = kd · diffuse + ks · specular.
struct ReflectanceFactors {
    double diffuse = 0;   ///< ∫ (N·v)(N·l)/π f dN / A(v)
    double specular = 0;  ///< ∫ (N·v)(N·l)(n+2)/(2π) cosⁿα f dN / A(v)
};

/// The paper's method: sample the apparent ellipse of the primitive seen along v on a regular
/// grid of its bounding rectangle (from the 2×2 quadratic form of the silhouette, in the
/// ellipse's own axes), half of it only: each sample's ray gives the visible point and, by the
/// central symmetry of the ellipsoid, the visible point of the opposite sample. `samplesPerAxis`
/// (≥ 2) grid cells along each axis of the rectangle. `light` and `view` are unit vectors
/// pointing away from the primitive.
ReflectanceFactors phongReflectanceApparentEllipse(const Ellipsoid& ellipsoid, const Vec3& light,
                                                   const Vec3& view, double shininess,
                                                   int samplesPerAxis = 64);

/// An independent method: quadrature over normals weighted by f(N). The sphere of directions
/// u is integrated with a Gauss–Legendre × uniform product rule through the Gauss map
/// N(u) ∝ L⁻ᵀu (L = R diag(a)), where f(N) dN = det(L)|L⁻ᵀu| du: this flattens the peaks f has
/// for discs and needles. `rings` Gauss–Legendre nodes in cos θ (≥ 2), 2·rings in φ.
ReflectanceFactors phongReflectanceNormalQuadrature(const Ellipsoid& ellipsoid, const Vec3& light,
                                                    const Vec3& view, double shininess,
                                                    int rings = 128);

/// The paper's method on the ellipsoid of an SGGX matrix S (any scale; Ellipsoid::fromS):
/// phongReflectanceApparentEllipse with `samplesPerAxis` grid cells per axis of the apparent
/// ellipse; zero factors for an S with no positive eigenvalue. The renderer's --shading reference.
ReflectanceFactors reflectanceReference(const SggxMatrix& s, const Vec3& light, const Vec3& view, double shininess,
                                        int samplesPerAxis = 24);

}  // namespace vtex::primitive
