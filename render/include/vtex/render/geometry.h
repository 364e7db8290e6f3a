/// @file
/// @brief Exact ray tests against bilinear patches, and the trilinear shell of a texel cell.
///
/// DESIGN.md, "Base mesh and mapping". A base face is the bilinear patch
/// P(u,v) = bilerp(P00, P10, P01, P11); a texel cell over it is the trilinear map
/// X(u,v,w) = bilerp_uv(Pij + (w − w0)·H·Nij), (u,v,w) ∈ [0,1]³, with w0 = 0 for a texel placed
/// on the face and w0 = 1 for one placed under it. The cell is bounded by six bilinear patches
/// (w = 0 bottom, w = 1 top, u = 0, u = 1, v = 0, v = 1); rays are intersected with them
/// exactly (Reshetov's ray–bilinear-patch test, "Cool Patches", Ray Tracing Gems ch. 8, as in
/// pbrt-v4's `IntersectBilinearPatch`, Pharr, Jakob and Humphreys, "Physically Based Rendering",
/// 4th ed., §6.6), in double precision.
///
/// Degenerate input is normal here: a triangle is a quad with two equal corners, a shell can be
/// 1e-6 or 1e3 times as high as its face is wide, a face can be twisted. Every function stays
/// finite and reports "no hit" or an empty optional where the answer is undefined.
#pragma once

#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

namespace vtex::render {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

/// One intersection of a ray with a bilinear patch: ray parameter t (world units when the
/// direction is unit) and the patch parameters (u, v) ∈ [0,1]².
struct PatchHit {
    double t;
    double u;
    double v;
};

/// All intersections (0, 1 or 2) of the ray o + t·d with the bilinear patch whose corners are
/// p00 (u=0,v=0), p10 (u=1,v=0), p01 (u=0,v=1), p11 (u=1,v=1), for t in (tMin, tMax).
/// Returns the number of hits written to `hits`, nearest first.
int intersectBilinearPatchAll(const Vec3& o, const Vec3& d, const Vec3& p00, const Vec3& p10,
                              const Vec3& p01, const Vec3& p11, double tMin, double tMax,
                              std::array<PatchHit, 2>& hits);

/// The nearest intersection in (tMin, tMax), if any.
std::optional<PatchHit> intersectBilinearPatch(const Vec3& o, const Vec3& d, const Vec3& p00,
                                               const Vec3& p10, const Vec3& p01, const Vec3& p11,
                                               double tMin, double tMax);

/// The trilinear cell X(u,v,w) of one base face (world units). Corner index i + 2j stands for
/// (u = i, v = j): corners[0] = P00, [1] = P10, [2] = P01, [3] = P11.
class TrilinearCell {
public:
    /// The point cell at the origin.
    TrilinearCell() {
        mCorners.fill(Vec3::Zero());
    }
    /// `normals` need not be unit (they are used as given); `height` is H in world units;
    /// `under` puts the shell below the face (X(u,v,1) is the face itself).
    TrilinearCell(const std::array<Vec3, 4>& positions, const std::array<Vec3, 4>& normals,
                  double height, bool under);

    /// X(r), r = (u, v, w) in cell coordinates (any value: the map extends polynomially).
    Vec3 map(const Vec3& r) const;
    /// ∂X/∂(u,v,w) as columns.
    Mat3 jacobian(const Vec3& r) const;
    /// The world corners of the cell: index i + 2j + 4k for (u=i, v=j, w=k).
    const std::array<Vec3, 8>& corners() const { return mCorners; }
    /// A length scale of the cell: the largest distance between two of its corners (computed on
    /// each call).
    double size() const;

    /// The four corners of face `face` (0: w=0, 1: w=1, 2: u=0, 3: u=1, 4: v=0, 5: v=1) in the
    /// order p00, p10, p01, p11 of its own parameters (a, b): (u,v) on w-faces, (v,w) on
    /// u-faces, (u,w) on v-faces.
    std::array<Vec3, 4> faceCorners(int face) const;
    /// Cell coordinates of the point (a, b) of face `face`.
    static Vec3 faceToCell(int face, double a, double b);
    /// (p10 − p00) × (p01 − p11) of face `face`'s corners: the u² coefficient vector of the ray
    /// test against it.
    Vec3 faceTwist(int face) const;

    /// Inverts the map: the cell coordinates r with X(r) = x, by Newton's method with the
    /// analytic Jacobian started at `guess`, then (if that fails) from a 3×3×3 grid of starts
    /// with a damped step. Succeeds when |X(r) − x| ≤ `tolerance` · size() and r lies within
    /// `slack` of [0,1]³; empty otherwise (a clear failure: x outside the cell, or a cell so
    /// folded that no start converges).
    std::optional<Vec3> inverse(const Vec3& x, const Vec3& guess = Vec3(0.5, 0.5, 0.5),
                                double tolerance = 1e-7, double slack = 1e-3) const;

    /// Whether the map is affine (every mixed term exactly zero: a parallelepiped, as a flat
    /// face under a shell along its constant normal makes), and then its Jacobian.
    bool affine() const { return mAffine; }
    const Mat3& affineJacobian() const { return mJ; }

private:
    std::array<Vec3, 8> mCorners;
    // Decided once by the constructor (jacobian and the ray test ask for every ray and sample):
    // the affine test, and whether every difference jacobian() interpolates equals its edge's,
    // so that jacobian(r) is mJ bit for bit at every finite r.
    bool mAffine = true, mConstantJacobian = true;
    Mat3 mJ = Mat3::Zero();
};

/// An interval [tIn, tOut] of a ray inside a cell, with where it enters and leaves.
struct CellSpan {
    double tIn = 0, tOut = 0;
    int faceIn = -1;   ///< face crossed on entry; −1 when the ray starts inside the cell
    int faceOut = -1;  ///< face crossed on exit
    Vec3 rIn{0, 0, 0}, rOut{0, 0, 0};  ///< cell coordinates of the two ends (rIn unknown when faceIn = −1)
};

/// The spans of the ray o + t·d (t > 0) inside the cell, in increasing t, found from the
/// crossings with its six faces: a crossing enters when d points along the gradient of the
/// face's coordinate (∇k = row k of J⁻¹) into the cell, and leaves otherwise; tangent crossings
/// and crossings where the cell is degenerate (det J = 0) are ignored. Returns the number of
/// spans written (at most spans.size()).
int cellSpans(const TrilinearCell& cell, const Vec3& o, const Vec3& d, std::array<CellSpan, 4>& spans);

}  // namespace vtex::render
