/// @file
/// @brief The micro-primitive: an ellipsoid that summarises a voxel's distribution of normals.
///
/// F. Neyret, "Un modèle général et multiéchelle de textures volumiques", AFIG 1994, §3
/// (English: Graphics Interface 1995); its SGGX reading follows Heitz, Dupuy, Crassin and
/// Dachsbacher, "The SGGX microflake distribution", SIGGRAPH 2015. DESIGN.md, "The
/// micro-primitive", is the contract.
///
/// The ellipsoid {x : xᵀQx ≤ 1}, M = Q⁻¹ = R diag(a²) Rᵀ, has no position: it only reflects
/// light and blocks it. Everything computed from it is invariant under negating any axis of R.
/// Needles and discs are ordinary shapes: every constructor passes the semi-axes (or the
/// quantities proportional to their inverses) through floorAxisRatios(), the one place where
/// the ratio of shortest to longest axis is kept at or above kMinAxisRatio, so every function
/// below stays finite.
#pragma once

#include <vtex/primitive/sggx.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <span>

namespace vtex::primitive {

/// The smallest ratio of shortest to longest semi-axis that an Ellipsoid keeps. A flat leaf
/// (ratio 0) becomes a disc 1e-4 thick, a hair a needle 1e4 times as long as it is wide. At
/// this ratio f(N) peaks at 1e8 times its mean and A(ω) still has 4 significant digits along
/// the short axis, so nothing overflows in double or in the float storage of the octree.
inline constexpr double kMinAxisRatio = 1e-4;

/// Raises every component of `lengths` (non-negative, finite) to at least kMinAxisRatio times
/// the largest; the one place where shapes are kept away from degeneracy. Constructors apply
/// it to the semi-axes, or to σ (fromS) and √q (fromQ), which are proportional to the
/// inverse semi-axes, so the resulting axis ratio is floored at kMinAxisRatio in every case.
Vec3 floorAxisRatios(const Vec3& lengths);

/// The semi-axes of the ellipsoid whose projected areas along its axes are `sigma` (σᵢ = π aⱼaₖ;
/// ≥ 0 with a positive maximum), after the ratio floor: what fromS and fitNormals build from
/// their σ, and what a stored voxel's σ stands for.
Vec3 semiAxesFromSigma(const Vec3& sigma);

/// How an ellipsoid is scaled to unit mean apparent area Ā (DESIGN.md, "Normalisation").
enum class Normalization {
    Exact,     ///< Ā = surface area / 4 (Cauchy), the mean of A(ω) over all directions
    ThreeAxis  ///< the paper's stand-in: mean of A along the three axes, π(a₂a₃+a₁a₃+a₁a₂)/3
};

/// An ellipsoid's axes as Ellipsoid's constructors leave them (sorted, floored) and its exact
/// mean apparent area, without the forms an Ellipsoid caches for evaluating it: all that storing
/// it takes (packing.h), for a caller that makes millions and evaluates none (the octree build).
struct EllipsoidShape {
    Mat3 basis;            ///< the axes as columns, sorted by increasing semi-axis
    Vec3 semiAxes;         ///< a₁ ≤ a₂ ≤ a₃ along them
    double exactMeanArea;  ///< surface area / 4
    /// Scaled to unit exact mean area with Ellipsoid::normalized(Exact)'s arithmetic, to the bit.
    EllipsoidShape normalized() const;
};

class Ellipsoid {
public:
    /// A sphere of radius 1.
    Ellipsoid();

    /// From an orthonormal basis (columns are the axes, any handedness) and the semi-axis
    /// lengths along them. Precondition: the largest semi-axis is positive and finite and the
    /// others are non-negative (std::invalid_argument otherwise).
    static Ellipsoid fromAxes(const Mat3& basis, const Vec3& semiAxes);
    /// From M = Q⁻¹ = R diag(a²) Rᵀ. Empty if M is not finite or has no positive eigenvalue.
    static std::optional<Ellipsoid> fromM(const Mat3& M);
    /// From the quadratic form Q. A zero eigenvalue (an infinite axis) is capped by the ratio
    /// floor relative to the shortest axis. Empty if Q is not finite or has no positive
    /// eigenvalue.
    static std::optional<Ellipsoid> fromQ(const Mat3& Q);
    /// From the SGGX matrix S = π² adj(M) = π² det(M) Q, so that A(ω) = √(ωᵀSω). Eigenvalues
    /// (1,1,0) give a needle, (1,0,0) a disc. Empty if S is not finite or has no positive
    /// eigenvalue.
    static std::optional<Ellipsoid> fromS(const Mat3& S);
    /// The shapes fromS(S) and fromM(M) are built from, without building the Ellipsoid (its
    /// cached forms); empty where those are.
    static std::optional<EllipsoidShape> shapeFromS(const Mat3& S);
    static std::optional<EllipsoidShape> shapeFromM(const Mat3& M);
    /// shapeFromS of each of `S`, the same bits, the exact mean areas computed four at a time
    /// where the processor has AVX2: Carlson's integrals are a chain of square roots and
    /// divisions whose latency one shape waits out and four share (the octree build's filter
    /// makes one shape per parent).
    static void shapesFromS(std::span<const Mat3> S, std::span<std::optional<EllipsoidShape>> shapes);
    /// The design's two-step fit to a weighted set of surface normals (sign ignored): axes
    /// from the eigenvectors of E = Σ wₜ nₜnₜᵀ, then σₖ = Σ wₜ|ωₖ·nₜ| / Σ wₜ along each, and
    /// S = R diag(σₖ²) Rᵀ. Exact for the normals of one ellipsoid, a disc and a fibre; its
    /// projected area along ωₖ is the mean projected area of the input facets (per unit
    /// weight). Zero, non-finite and zero-weight normals are skipped; empty if none is left.
    static std::optional<Ellipsoid> fitNormals(std::span<const Vec3> normals,
                                               std::span<const double> weights);

    /// The axes as columns of an orthonormal matrix, sorted by increasing semi-axis.
    const Mat3& basis() const { return mBasis; }
    /// The semi-axes a₁ ≤ a₂ ≤ a₃ along basis() columns (after the ratio floor).
    const Vec3& semiAxes() const { return mSemiAxes; }
    /// Its axes and exact mean apparent area, what storing it takes (packing.h).
    EllipsoidShape shape() const { return {mBasis, mSemiAxes, mExactMeanArea}; }

    Mat3 M() const;  ///< Q⁻¹ = R diag(a²) Rᵀ
    Mat3 Q() const;  ///< R diag(a⁻²) Rᵀ
    Mat3 S() const;  ///< π² det(M) Q = R diag(σ²) Rᵀ, σᵢ = π aⱼaₖ

    /// f(N) = det(M) / (NᵀMN)², area per steradian of normal N (unit vector; either sign).
    /// ∫ f dN over the sphere is surfaceArea().
    double normalDistribution(const Vec3& normal) const {
        const double x = normal.x(), y = normal.y(), z = normal.z();
        const double nMn = mM[0] * x * x + mM[1] * y * y + mM[2] * z * z +
                           2 * (mM[3] * x * y + mM[4] * x * z + mM[5] * y * z);
        return mDetM / (nMn * nMn);
    }

    /// A(ω) = π √(det M · ωᵀ M⁻¹ ω) = √(ωᵀSω): the area of the shadow cast along the unit
    /// direction ω (either sign); equals ½ ∫ |ω·N| f(N) dN.
    double projectedArea(const Vec3& direction) const { return mS.projectedArea(direction); }
    /// S's six unique entries (the SGGX form every stage shares).
    const SggxMatrix& sggx() const { return mS; }

    /// Surface area, stable over the whole range of shapes (elliptic integrals where they
    /// keep their digits, sphere quadrature of A(ω) near a sphere, where their closed form
    /// is 0/0).
    double surfaceArea() const;
    /// Ā = surfaceArea()/4 (Exact) or the paper's three-axis mean (ThreeAxis).
    double meanProjectedArea(Normalization normalization = Normalization::Exact) const;

    /// A copy scaled so that meanProjectedArea(normalization) is 1.
    Ellipsoid normalized(Normalization normalization = Normalization::Exact) const;
    /// Â(ω) = A(ω)/Ā: the anisotropic factor of the extinction τρÂ(ω); its mean over
    /// directions is 1 with the Exact normalisation.
    double normalizedProjectedArea(const Vec3& direction,
                                   Normalization normalization = Normalization::Exact) const {
        return projectedArea(direction) / meanProjectedArea(normalization);
    }
    /// f(N)/Ā (Exact): integrates to 4 over the sphere whatever the size.
    double normalizedNormalDistribution(const Vec3& normal) const {
        return normalDistribution(normal) / mExactMeanArea;
    }

    /// Adds `weight`·f(N)/Ā (normalizedNormalDistribution, to rounding) to `sums[i]` for each
    /// direction N = (x[i], y[i], z[i]), in a loop the compiler vectorises (the filter error
    /// evaluates eight children on 512 directions per sampled node). `start`: sets `sums[i]` to
    /// it instead (the first term of a sum, which then needs no zeroing).
    void accumulateNormalizedNormalDistribution(std::span<const double> x, std::span<const double> y,
                                                std::span<const double> z, double weight,
                                                std::span<double> sums, bool start = false) const;

    /// A copy with every length multiplied by `factor` (> 0): areas scale by factor².
    Ellipsoid scaled(double factor) const;

private:
    Ellipsoid(const Mat3& basis, const Vec3& semiAxes);
    explicit Ellipsoid(const EllipsoidShape& shape);
    /// Sorts and floors the axes, and computes the exact mean area: every constructor's shape.
    static EllipsoidShape shapeOf(const Mat3& basis, const Vec3& semiAxes);
    /// shapeOf without the exact mean area (NaN), and shapeFromS without it, for shapesFromS.
    static EllipsoidShape axesOf(const Mat3& basis, const Vec3& semiAxes);
    static std::optional<EllipsoidShape> axesFromS(const Mat3& S);

    void cacheForms();

    Mat3 mBasis;
    Vec3 mSemiAxes;
    // S = R diag(σ²) Rᵀ, σᵢ = π aⱼaₖ, and the unique entries (xx, yy, zz, xy, xz, yz) of
    // M = R diag(a²) Rᵀ, for the two functions above.
    SggxMatrix mS;
    std::array<double, 6> mM;
    double mDetM;        // (a₁a₂a₃)²
    double mExactMeanArea;  // surfaceArea()/4, computed once: it costs elliptic integrals
};

}  // namespace vtex::primitive
