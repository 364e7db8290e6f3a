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
#include <utility>

namespace vtex::primitive {

/// The fast path. Since f(N)(N·v)⁺ / A(v) is the distribution of visible normals D_v (Heitz,
/// Dupuy, Crassin, Dachsbacher, "The SGGX microflake distribution", SIGGRAPH 2015, §4 and
/// Listing 3 for its closed-form sampling), R(l,v) = E_{N∼D_v}[(N·l)⁺ ρ(N,l,v)] exactly.
///
/// Diffuse: `samples` fixed points of D_v (a Fibonacci lattice on the unit disc mapped through
/// the closed-form VNDF sampler), so the result is deterministic and smooth in l and v.
///
/// Specular: those points alone miss a Phong lobe narrower than the spread of the normals (a
/// sphere at shininess 100: +155 %), and points of the lobe alone miss normals narrower than
/// the lobe (discs). The kernel combines both sets by multiple importance sampling (Veach's
/// balance heuristic): strategy A, the D_v lattice; strategy B, kLobeSamples mirror directions
/// drawn from the normalised Phong lobe around v, each giving the half vector N between l and
/// it, whose density over normals is (n+1)/2π cosⁿα · 4(N·l). Both densities are evaluated
/// on the pre-image sphere of the VNDF sampler's linear map m = C u (where D_v is a cosine
/// around the sampler's axis, Heitz et al. §4), so the weights need no eigen-decomposition:
/// the Jacobian from u to N is |det C| / |C u|³. B's directions depend on (l, v, shininess)
/// alone and are set up once per kernel. A needle much thinner than the lobe defeats both (its
/// normals lie on a circle that the lobe crosses on a short arc): when its axis ratio is below
/// 0.105 (n+1)^0.3 times the lobe's width 1/√(n+1) (where the two estimators' errors cross,
/// src/fibre_specular.h), the specular factor is instead the limit
/// of an ideal fibre of elliptic cross-section, an 8- or 16-node quadrature along that circle
/// (src/fibre_specular.h), skipped when the fibre's highlight cone misses v by more than the
/// Phong cut-off (then every term is below 1e-6 of the lobe's peak). From shininess 50, needles
/// from 0.15 to 4 lobe widths thick take a product rule over their band of normals instead, along
/// the circle and across it (src/band_specular.h): the lattice and lobe missed the product of
/// the band and a narrow lobe, and the fibre limit the band's tails. Errors against the paper's integration are measured
/// by bench/vtex_specular_estimators, per family of shapes and shininess (docs/micro-primitive.md).
///
/// Along one ray segment v is constant, and so is l for a directional light, while S changes
/// from voxel to voxel: the kernel keeps what depends on (l, v, shininess, samples) alone, so
/// that a call only projects S into the frame around v and sums the lattices. The cost per call
/// is measured by bench/render_shading_bench, the error against the reference by
/// bench/render_reflectance_error. A kernel built with `specular` false returns specular 0 and
/// skips strategy B and the fibre: texels without specular colour (the default) pay nothing for
/// them.
class ReflectanceKernel {
public:
    /// Mirror directions of strategy B (the lobe's points).
    static constexpr int kLobeSamples = 8;

    ReflectanceKernel(const Eigen::Vector3d& light, const Eigen::Vector3d& view, double shininess, int samples = 16,
                      bool specular = true);
    ReflectanceFactors operator()(const SggxMatrix& s) const;

private:
    struct Lattice;
    struct Clones;  ///< set-up and evaluation compiled for SSE2 and AVX2 (reflectance_kernel.cpp)
    ReflectanceFactors evaluate(const SggxMatrix& s) const;
    void setUpProjection(const Eigen::Vector3d& wk, const Eigen::Vector3d& wj, const Eigen::Vector3d& wi);
    void setUpLobe();
    std::pair<double, double> latticeSums(const Eigen::Vector3d& mk, const Eigen::Vector3d& mj, const Eigen::Vector3d& mi,
                                          double scale, double lobeRatio, bool wantSpecular) const;
    double lobeSum(double mkx, double mjx, double mjy, const Eigen::Vector3d& Mi, double detC) const;
    double power(double c) const;                   ///< cⁿ: by squaring for a whole n ≤ 1024
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
    bool mSpecular;
    /// (K_B / K_A) · 2(n+1): the ratio of B's density to A's at a lattice point is this times
    /// |det C| (N·l) cosⁿα / (w |C u|³), w the point's height on the disc's hemisphere.
    double mLobeRatio = 0;
    double mFibreGate = 0;  ///< the largest λ₁/λ₂ the fibre limit takes (src/fibre_specular.h)
    double mBandGate = 0;   ///< the largest λ₁/λ₂ the band rule takes (src/band_specular.h); 0: none
    /// Strategy B's half vectors in (wk, wj, wi) and their (N·l) cosⁿα; 0 for those facing
    /// away from v, whose normal is then v.
    alignas(16) std::array<float, kLobeSamples> mLobeX, mLobeY, mLobeZ, mLobeTerm;  // set by setUpLobe
    int mLobeCount = 0;  ///< how many face v
};

/// ReflectanceKernel(light, view, shininess, samples)(s), for a single evaluation.
ReflectanceFactors reflectanceFast(const SggxMatrix& s, const Eigen::Vector3d& light, const Eigen::Vector3d& view,
                                   double shininess, int samples = 16, bool specular = true);

}  // namespace vtex::primitive
