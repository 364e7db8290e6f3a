// Exact ray tests against bilinear patches and trilinear cells (see geometry.h).
//
// The patch test is Reshetov's (A. Reshetov, "Cool Patches: A Geometric Approach to Ray/Bilinear
// Patch Intersections", Ray Tracing Gems, ch. 8, 2019), the one pbrt-v4's IntersectBilinearPatch
// also follows: the ray meets the u-isoline segment between lerp(u, p00, p10) and
// lerp(u, p01, p11) where a quadratic in u vanishes; v and t follow from one more cross product.
// It is run in double precision and returns both roots, because the cell test needs every
// crossing, not only the nearest. Its inputs are split so that a cell's six faces share the work
// that depends on their eight corners only (corners relative to the origin and their cross
// products with d) and on the cell alone (the twist vectors, precomputed per cell).
#include <vtex/render/geometry.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtex::render {
namespace {

// The cell's map when it is affine (every mixed term of the trilinear map exactly zero: a
// parallelepiped, as a flat face under a shell along its constant normal makes), as its origin
// corner and Jacobian; false otherwise.
bool affineMap(const std::array<Vec3, 8>& c, Mat3& j) {
    // X = c0 + u·a + v·b + w·e + uv·(c3 − c1 − c2 + c0) + uw·(…) + vw·(…) + uvw·(…)
    const bool affine = (c[3] - c[1] - c[2] + c[0]).isZero(0) && (c[5] - c[1] - c[4] + c[0]).isZero(0) &&
                        (c[6] - c[2] - c[4] + c[0]).isZero(0) && (c[7] - c[3] - c[5] + c[1]).isZero(0);
    if (!affine) return false;
    j.col(0) = c[1] - c[0];
    j.col(1) = c[2] - c[0];
    j.col(2) = c[4] - c[0];
    return true;
}

// Shared edges of adjacent patches must not leak rays through the crack that rounding opens
// between them: accept parameters this far outside [0,1] and clamp them back.
constexpr double kEdgeSlack = 1e-9;

// Corners p00, p10, p01, p11 of each cell face, as indices i + 2j + 4k of the cell's corners;
// see TrilinearCell::faceCorners for the faces' parameters.
constexpr int kFaceCorners[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 2, 4, 6},
                                    {1, 3, 5, 7}, {0, 1, 4, 5}, {2, 3, 6, 7}};

// (p10 − p00) × (p01 − p11) of face `face` (TrilinearCell::faceTwist), inlined into cellSpans.
[[gnu::always_inline]] inline Vec3 twistOf(const std::array<Vec3, 8>& c, int face) {
    const auto& k = kFaceCorners[std::size_t(face)];
    return (c[k[1]] - c[k[0]]).cross(c[k[2]] - c[k[3]]);
}

// The index in (u, v, w) of the coordinate each face holds fixed.
constexpr int kFaceCoordinate[6] = {2, 2, 0, 0, 1, 1};

// Roots of a t² + b t + c in increasing order, by the cancellation-free form
// q = −(b + sign(b)√Δ)/2, roots q/a and c/q.
int solveQuadratic(double a, double b, double c, double& r0, double& r1) {
    if (a == 0) {
        if (b == 0) return 0;
        r0 = r1 = -c / b;
        return 1;
    }
    const double discriminant = std::fma(b, b, -4 * a * c);
    if (discriminant < 0) return 0;
    const double root = std::sqrt(discriminant);
    const double q = -0.5 * (b + std::copysign(root, b));
    if (q == 0) {  // b = 0 and c = 0: the double root 0
        r0 = r1 = 0;
        return 1;
    }
    // min and max rather than a conditional swap: the order is unpredictable, and they compile
    // to branch-free instructions.
    const double x0 = q / a, x1 = c / q;
    r0 = std::min(x0, x1);
    r1 = std::max(x0, x1);
    return 2;
}

// The patch (p00, p10, p01, p11) seen from the ray o + t·d: q00 = p00 − o, the cross products
// (p00 − o) × d and (p10 − o) × d, the edges e10 = p10 − p00, e00 = p01 − p00, e11 = p11 − p10, and
// the twist (p10 − p00) × (p01 − p11), the u² coefficient of the quadratic (zero when the patch
// is a parallelogram).
struct PatchView {
    const Vec3& q00;
    const Vec3& q00xd;
    const Vec3& q10xd;
    Vec3 e10, e00, e11;
    const Vec3& twist;
};

// Inlined into cellSpans' loop over the faces, where the shared corner terms stay in registers
// (vtex_geometry_bench: ~10 % fewer instructions per cell).
[[gnu::always_inline]] inline int intersectPatch(const PatchView& p, const Vec3& d, double tMin,
                                                 double tMax, std::array<PatchHit, 2>& hits) {
    // The ray meets the line through the u-isoline where det(q(u), d, e(u)) = 0, q(u) the
    // isoline's start and e(u) its direction: a quadratic a u² + b u + c.
    const double a = p.twist.dot(d);
    const double c = p.q00xd.dot(p.e00);
    const double b = p.q10xd.dot(p.e11) - (a + c);
    // No root in the accepted u range when the quadratic has one sign at both ends of it and
    // does not turn back within it: on the forest benchmark half the faces of the cells a ray
    // is offered end here, before the square root and the divisions. The conditions are
    // combined with & and | into a single branch: the outcome is a coin toss per face, and one
    // mispredicted branch is cheaper than several.
    const double f0 = c - kEdgeSlack * b, slope1 = 2 * a + b, f1 = a + b + c + kEdgeSlack * slope1;
    const bool positive = (f0 > 0) & (f1 > 0) & !((a > 0) & (b < 0) & (slope1 > 0));
    const bool negative = (f0 < 0) & (f1 < 0) & !((a < 0) & (b > 0) & (slope1 < 0));
    if (positive | negative) return 0;
    double us[2];
    const int roots = solveQuadratic(a, b, c, us[0], us[1]);
    int count = 0;
    for (int i = 0; i < roots; ++i) {
        if (i == 1 && us[1] == us[0]) break;
        double u = us[i];
        if (!(u >= -kEdgeSlack && u <= 1 + kEdgeSlack)) continue;
        u = std::clamp(u, 0.0, 1.0);
        // v and t from the closest points of the ray and the isoline segment, start − o = qa and
        // direction eb (built from o-relative corners and edges, which keeps them accurate far
        // from the world origin).
        const Vec3 qa = p.q00 + u * p.e10;
        const Vec3 eb = p.e00 + u * (p.e11 - p.e00);
        const Vec3 perp = d.cross(eb);
        const double p2 = perp.squaredNorm();
        if (!(p2 > 0)) continue;  // collapsed isoline (a triangle's apex) or ray along it
        const Vec3 n = perp.cross(qa);
        // v = v1 / p2 is range-checked before the division: about half the roots fail here.
        const double v1 = n.dot(d);
        if (!(v1 >= -kEdgeSlack * p2 && v1 <= (1 + kEdgeSlack) * p2)) continue;
        const double t = n.dot(eb) / p2;
        if (!(t > tMin && t < tMax) || !std::isfinite(t)) continue;
        hits[count++] = PatchHit{t, u, std::clamp(v1 / p2, 0.0, 1.0)};
    }
    if (count == 2 && hits[1].t < hits[0].t) std::swap(hits[0], hits[1]);
    return count;
}

}  // namespace

int intersectBilinearPatchAll(const Vec3& o, const Vec3& d, const Vec3& p00, const Vec3& p10,
                              const Vec3& p01, const Vec3& p11, double tMin, double tMax,
                              std::array<PatchHit, 2>& hits) {
    const Vec3 q00 = p00 - o;
    const Vec3 q00xd = q00.cross(d), q10xd = (p10 - o).cross(d);
    const Vec3 twist = (p10 - p00).cross(p01 - p11);
    return intersectPatch(PatchView{q00, q00xd, q10xd, p10 - p00, p01 - p00, p11 - p10, twist}, d,
                          tMin, tMax, hits);
}

std::optional<PatchHit> intersectBilinearPatch(const Vec3& o, const Vec3& d, const Vec3& p00,
                                               const Vec3& p10, const Vec3& p01, const Vec3& p11,
                                               double tMin, double tMax) {
    std::array<PatchHit, 2> hits;
    if (intersectBilinearPatchAll(o, d, p00, p10, p01, p11, tMin, tMax, hits) == 0) return std::nullopt;
    return hits[0];
}

TrilinearCell::TrilinearCell(const std::array<Vec3, 4>& positions, const std::array<Vec3, 4>& normals,
                             double height, bool under) {
    const double w0 = under ? -1.0 : 0.0;
    for (int i = 0; i < 4; ++i) {
        mCorners[i] = positions[i] + w0 * height * normals[i];
        mCorners[i + 4] = positions[i] + (w0 + 1) * height * normals[i];
    }
    const auto& c = mCorners;
    mAffine = affineMap(c, mJ);
    const Vec3 du = c[1] - c[0], dv = c[2] - c[0], dw = c[4] - c[0];
    mConstantJacobian = mAffine && du == c[3] - c[2] && du == c[5] - c[4] && du == c[7] - c[6] && dv == c[3] - c[1] &&
                        dv == c[6] - c[4] && dv == c[7] - c[5] && dw == c[5] - c[1] && dw == c[6] - c[2] && dw == c[7] - c[3];
}

Vec3 TrilinearCell::faceTwist(int face) const { return twistOf(mCorners, face); }

double TrilinearCell::size() const {
    // Computed when asked, not kept: a large mesh's cells are rebuilt for every ray that meets
    // them (prim_table.h), and most of those never ask. The largest squared distance, then one root
    // (the same as the largest root: it is monotonic and correctly rounded).
    double size2 = 0;
    for (int i = 0; i < 8; ++i)
        for (int j = i + 1; j < 8; ++j) size2 = std::max(size2, (mCorners[i] - mCorners[j]).squaredNorm());
    return std::sqrt(size2);
}

Vec3 TrilinearCell::map(const Vec3& r) const {
    const double u = r.x(), v = r.y(), w = r.z();
    const auto bilerp = [&](int base) {
        const Vec3 a = mCorners[base] + u * (mCorners[base + 1] - mCorners[base]);
        const Vec3 b = mCorners[base + 2] + u * (mCorners[base + 3] - mCorners[base + 2]);
        return Vec3(a + v * (b - a));
    };
    const Vec3 bottom = bilerp(0);
    return bottom + w * (bilerp(4) - bottom);
}

Mat3 TrilinearCell::jacobian(const Vec3& r) const {
    // Each lerp below between equal differences returns the difference itself (a + s·0 = a).
    if (mConstantJacobian && r.allFinite()) return mJ;
    const double u = r.x(), v = r.y(), w = r.z();
    const auto& c = mCorners;
    const auto lerp = [](const Vec3& a, const Vec3& b, double s) { return Vec3(a + s * (b - a)); };
    // ∂/∂u: differences along u, interpolated in v then w; likewise for v and w.
    const Vec3 du = lerp(lerp(c[1] - c[0], c[3] - c[2], v), lerp(c[5] - c[4], c[7] - c[6], v), w);
    const Vec3 dv = lerp(lerp(c[2] - c[0], c[3] - c[1], u), lerp(c[6] - c[4], c[7] - c[5], u), w);
    const Vec3 dw = lerp(lerp(c[4] - c[0], c[5] - c[1], u), lerp(c[6] - c[2], c[7] - c[3], u), v);
    Mat3 j;
    j.col(0) = du;
    j.col(1) = dv;
    j.col(2) = dw;
    return j;
}

std::array<Vec3, 4> TrilinearCell::faceCorners(int face) const {
    const auto& k = kFaceCorners[face];
    return {mCorners[k[0]], mCorners[k[1]], mCorners[k[2]], mCorners[k[3]]};
}

Vec3 TrilinearCell::faceToCell(int face, double a, double b) {
    // A table, not a switch: cellSpans calls this for every crossing, and the jump on the face
    // index is unpredictable.
    static constexpr int kAxes[6][3] = {{0, 1, 2}, {0, 1, 2}, {1, 2, 0},
                                        {1, 2, 0}, {0, 2, 1}, {0, 2, 1}};
    const auto& axes = kAxes[face];
    Vec3 r;
    r[axes[0]] = a;
    r[axes[1]] = b;
    r[axes[2]] = face % 2;
    return r;
}

std::optional<Vec3> TrilinearCell::inverse(const Vec3& x, const Vec3& guess, double tolerance,
                                           double slack) const {
    const auto accept = [&](const Vec3& r, double err, double target) {
        return err <= target && (r.array() >= -slack).all() && (r.array() <= 1 + slack).all();
    };
    // An affine cell (a parallelepiped: a flat face under a shell along its constant normal) is
    // inverted by one linear solve, exact up to rounding. Its residual is held to the same
    // tolerance, first against the diagonal |X(1,1,1) − X(0,0,0)| ≤ size() (a cheaper bound, so
    // that passing it passes the test with size()); a near-singular cell falls through to Newton.
    if (mAffine) {
        const Vec3 r = mJ.inverse() * (x - mCorners[0]);
        if (r.allFinite()) {
            const double err = (map(r) - x).norm();
            if (accept(r, err, tolerance * (mCorners[7] - mCorners[0]).norm()) ||
                accept(r, err, tolerance * std::max(size(), std::numeric_limits<double>::min())))
                return r.cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones());
        }
    }
    const double target = tolerance * std::max(size(), std::numeric_limits<double>::min());
    // Newton from one start; damped (the step is halved until the residual decreases) so that a
    // start in a fold does not jump out of the cell and diverge.
    const auto newton = [&](Vec3 r, bool damped) -> std::pair<Vec3, double> {
        Vec3 f = map(r) - x;
        double err = f.norm();
        for (int iteration = 0; iteration < 40 && err > target; ++iteration) {
            const Mat3 j = jacobian(r);
            const Eigen::FullPivLU<Mat3> lu(j);
            if (!lu.isInvertible()) break;
            const Vec3 step = lu.solve(f);
            if (!step.allFinite()) break;
            double scale = 1;
            Vec3 next = r - step;
            Vec3 fNext = map(next) - x;
            if (damped) {
                while (fNext.norm() >= err && scale > 1e-4) {
                    scale *= 0.5;
                    next = r - scale * step;
                    fNext = map(next) - x;
                }
                if (fNext.norm() >= err) break;
            }
            // Keep the iterate in a box around the cell: outside, the cubic map can have
            // spurious roots far away.
            r = next.cwiseMax(Vec3::Constant(-1.0)).cwiseMin(Vec3::Constant(2.0));
            f = map(r) - x;
            err = f.norm();
        }
        return {r, err};
    };
    auto [r, err] = newton(guess, false);
    if (accept(r, err, target)) return r.cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones());
    // Safe fallback: damped Newton from a grid of starts; keep the first that converges inside.
    for (int k = 0; k < 27; ++k) {
        const Vec3 start((k % 3 + 0.5) / 3, (k / 3 % 3 + 0.5) / 3, (k / 9 + 0.5) / 3);
        auto [rk, ek] = newton(start, true);
        if (accept(rk, ek, target)) return rk.cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones());
    }
    return std::nullopt;
}

namespace {

// cellSpans for an affine cell: the slab test in cell coordinates, a fourth of the six patch
// tests' instructions (callgrind on the bush field's middle view: 470 per cell, 1 770 before). The same spans up to rounding:
// entry and exit are where the ray crosses the planes u, v, w = 0, 1, the coordinate crossed set
// exactly; a ray that only grazes the cell (an empty or one-point interval) has no span, as a
// tangent crossing has none in the general test.
int affineSpans(const Vec3& origin, const Mat3& j, const Vec3& o, const Vec3& d, std::array<CellSpan, 4>& spans) {
    const double det = j.determinant();
    if (!(det != 0) || !std::isfinite(det)) return 0;
    const Mat3 inverse = j.inverse();
    Vec3 ro = inverse * (o - origin);
    const Vec3 rd = inverse * d;
    // An origin on a face within rounding (a floor point's shadow ray starts on the floor) is on
    // it: a ray from there into the cell starts inside it, as the patch tests find (their
    // crossing at t = 0 is not past the origin); without this, the inverse's rounding put some
    // floor points a hair below the floor, which then blocked their light.
    for (int a = 0; a < 3; ++a) {
        if (std::abs(ro[a]) < 1e-12) ro[a] = 0;
        else if (std::abs(ro[a] - 1) < 1e-12) ro[a] = 1;
    }
    // Face numbering of TrilinearCell: 0/1 w = 0/1, 2/3 u = 0/1, 4/5 v = 0/1.
    constexpr int kFaceOf[3] = {2, 4, 0};
    double tIn = -std::numeric_limits<double>::infinity(), tOut = std::numeric_limits<double>::infinity();
    int faceIn = -1, faceOut = -1;
    for (int a = 0; a < 3; ++a) {
        if (rd[a] == 0) {
            if (!(ro[a] > 0 && ro[a] < 1)) return 0;  // parallel to and outside (or on) the slab
            continue;
        }
        const double t0 = -ro[a] / rd[a], t1 = (1 - ro[a]) / rd[a];
        const bool up = rd[a] > 0;
        const double enter = up ? t0 : t1, leave = up ? t1 : t0;
        if (enter > tIn) {
            tIn = enter;
            faceIn = kFaceOf[a] + (up ? 0 : 1);
        }
        if (leave < tOut) {
            tOut = leave;
            faceOut = kFaceOf[a] + (up ? 1 : 0);
        }
    }
    // A ray from a point on the boundary leaving at once has the span [0, 0], as the patch tests
    // find its exit a rounding error past 0.
    if (!(tOut > tIn) || !(tOut >= 0)) return 0;
    const auto at = [&](double t, int face) {
        Vec3 r = (ro + t * rd).cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones());
        const int axis = face < 2 ? 2 : face < 4 ? 0 : 1;
        r[axis] = face % 2;
        return r;
    };
    CellSpan s;
    if (tIn > 0) {
        s.tIn = tIn;
        s.faceIn = faceIn;
        s.rIn = at(tIn, faceIn);
    }
    s.tOut = tOut;
    s.faceOut = faceOut;
    s.rOut = at(tOut, faceOut);
    spans[0] = s;
    return 1;
}

// The crossings of the six faces' patch tests, sorted, paired into spans.
int generalSpans(const TrilinearCell& cell, const Vec3& o, const Vec3& d, std::array<CellSpan, 4>& spans) {
    struct Crossing {
        double t;
        int face;
        bool entry;
        Vec3 r;
    };
    std::array<Crossing, 12> crossings;
    int n = 0;
    // The faces' p00 and p10 corners are cell corners 0 to 5; each face reuses their offsets from
    // o and cross products with d.
    const auto& corner = cell.corners();
    std::array<Vec3, 6> q, qxd;
    for (int i = 0; i < 6; ++i) {
        q[i] = corner[i] - o;
        qxd[i] = q[i].cross(d);
    }
    for (int face = 0; face < 6; ++face) {
        const auto& k = kFaceCorners[face];
        const Vec3 twist = twistOf(corner, face);
        const PatchView view{q[k[0]], qxd[k[0]], qxd[k[1]], corner[k[1]] - corner[k[0]],
                             corner[k[2]] - corner[k[0]], corner[k[3]] - corner[k[1]], twist};
        std::array<PatchHit, 2> hits;
        const int count =
            intersectPatch(view, d, 0.0, std::numeric_limits<double>::infinity(), hits);
        const int coord = kFaceCoordinate[face];
        for (int h = 0; h < count; ++h) {
            const Vec3 r = TrilinearCell::faceToCell(face, hits[h].u, hits[h].v);
            const Mat3 j = cell.jacobian(r);
            // Row `coord` of J⁻¹ is the cofactor column over det J: the world gradient of the
            // coordinate. Its sign against d says whether the ray enters or leaves.
            const Vec3 cofactor = j.col((coord + 1) % 3).cross(j.col((coord + 2) % 3));
            const double det = cofactor.dot(j.col(coord));
            const double along = cofactor.dot(d);
            if (det == 0 || along == 0 || !std::isfinite(det) || !std::isfinite(along)) continue;
            const bool increasing = (along > 0) == (det > 0);
            const bool atZero = (face % 2) == 0;
            crossings[n++] = Crossing{hits[h].t, face, increasing == atZero, r};
        }
    }
    std::sort(crossings.begin(), crossings.begin() + n,
              [](const Crossing& a, const Crossing& b) { return a.t < b.t; });
    int count = 0;
    bool inside = false;
    CellSpan current;
    for (int i = 0; i < n && count < int(spans.size()); ++i) {
        const Crossing& c = crossings[i];
        if (!inside) {
            if (c.entry) {
                current = CellSpan{};
                current.tIn = c.t;
                current.faceIn = c.face;
                current.rIn = c.r;
                inside = true;
            } else if (i == 0) {
                // The first crossing leaves: the origin is inside the cell.
                CellSpan s;
                s.tIn = 0;
                s.faceIn = -1;
                s.tOut = c.t;
                s.faceOut = c.face;
                s.rOut = c.r;
                spans[count++] = s;
            }
            // Otherwise a stray exit (the same edge crossed on two faces): ignore it.
        } else if (!c.entry) {
            current.tOut = c.t;
            current.faceOut = c.face;
            current.rOut = c.r;
            spans[count++] = current;
            inside = false;
        }
        // A second entry while inside is the same edge crossed on two faces: ignore it.
    }
    return count;
}

}  // namespace

int cellSpans(const TrilinearCell& cell, const Vec3& o, const Vec3& d, std::array<CellSpan, 4>& spans) {
    if (cell.affine()) return affineSpans(cell.corners()[0], cell.affineJacobian(), o, d, spans);
    return generalSpans(cell, o, d, spans);
}

}  // namespace vtex::render
