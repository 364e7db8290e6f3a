// Exact ray tests against bilinear patches and trilinear cells (see geometry.h).
//
// The patch test follows pbrt-v4's IntersectBilinearPatch (Pharr, Jakob, Humphreys, "Physically
// Based Rendering", 4th ed., §6.6): the ray meets the u-isoline segment between lerp(u, p00, p10)
// and lerp(u, p01, p11) where a quadratic in u vanishes; v and t follow from two 3×3
// determinants. It is run in double precision and returns both roots, because the cell test needs
// every crossing, not only the nearest.
#include <vtex/render/geometry.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtex::render {
namespace {

// Shared edges of adjacent patches must not leak rays through the crack that rounding opens
// between them: accept parameters this far outside [0,1] and clamp them back.
constexpr double kEdgeSlack = 1e-9;

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
    r0 = q / a;
    r1 = c / q;
    if (r0 > r1) std::swap(r0, r1);
    return 2;
}

double det3(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

}  // namespace

int intersectBilinearPatchAll(const Vec3& o, const Vec3& d, const Vec3& p00, const Vec3& p10,
                              const Vec3& p01, const Vec3& p11, double tMin, double tMax,
                              std::array<PatchHit, 2>& hits) {
    // Quadratic coefficients for the distance from the ray to the u-isolines.
    const double a = (p10 - p00).cross(p01 - p11).dot(d);
    const double c = (p00 - o).cross(d).dot(p01 - p00);
    const double b = (p10 - o).cross(d).dot(p11 - p10) - (a + c);
    double us[2];
    const int roots = solveQuadratic(a, b, c, us[0], us[1]);
    int count = 0;
    for (int i = 0; i < roots; ++i) {
        if (i == 1 && us[1] == us[0]) break;
        double u = us[i];
        if (!(u >= -kEdgeSlack && u <= 1 + kEdgeSlack)) continue;
        u = std::clamp(u, 0.0, 1.0);
        // v and t from the closest points of the ray and the isoline segment.
        const Vec3 uo = p00 + u * (p10 - p00);
        const Vec3 ud = p01 + u * (p11 - p01) - uo;
        const Vec3 deltao = uo - o;
        const Vec3 perp = d.cross(ud);
        const double p2 = perp.squaredNorm();
        if (!(p2 > 0)) continue;  // collapsed isoline (a triangle's apex) or ray along it
        const double v1 = det3(deltao, d, perp);
        const double t1 = det3(deltao, ud, perp);
        const double v = v1 / p2;
        const double t = t1 / p2;
        if (!(v >= -kEdgeSlack && v <= 1 + kEdgeSlack)) continue;
        if (!(t > tMin && t < tMax) || !std::isfinite(t)) continue;
        hits[count++] = PatchHit{t, u, std::clamp(v, 0.0, 1.0)};
    }
    if (count == 2 && hits[1].t < hits[0].t) std::swap(hits[0], hits[1]);
    return count;
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
    for (int i = 0; i < 8; ++i)
        for (int j = i + 1; j < 8; ++j) mSize = std::max(mSize, (mCorners[i] - mCorners[j]).norm());
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
    const auto& c = mCorners;
    switch (face) {
        case 0: return {c[0], c[1], c[2], c[3]};  // w = 0, (a,b) = (u,v)
        case 1: return {c[4], c[5], c[6], c[7]};  // w = 1
        case 2: return {c[0], c[2], c[4], c[6]};  // u = 0, (a,b) = (v,w)
        case 3: return {c[1], c[3], c[5], c[7]};  // u = 1
        case 4: return {c[0], c[1], c[4], c[5]};  // v = 0, (a,b) = (u,w)
        default: return {c[2], c[3], c[6], c[7]};  // v = 1
    }
}

Vec3 TrilinearCell::faceToCell(int face, double a, double b) {
    switch (face) {
        case 0: return {a, b, 0};
        case 1: return {a, b, 1};
        case 2: return {0, a, b};
        case 3: return {1, a, b};
        case 4: return {a, 0, b};
        default: return {a, 1, b};
    }
}

std::optional<Vec3> TrilinearCell::inverse(const Vec3& x, const Vec3& guess, double tolerance,
                                           double slack) const {
    const double target = tolerance * std::max(mSize, std::numeric_limits<double>::min());
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
    const auto accept = [&](const Vec3& r, double err) {
        return err <= target && (r.array() >= -slack).all() && (r.array() <= 1 + slack).all();
    };
    auto [r, err] = newton(guess, false);
    if (accept(r, err)) return r.cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones());
    // Safe fallback: damped Newton from a grid of starts; keep the first that converges inside.
    for (int k = 0; k < 27; ++k) {
        const Vec3 start((k % 3 + 0.5) / 3, (k / 3 % 3 + 0.5) / 3, (k / 9 + 0.5) / 3);
        auto [rk, ek] = newton(start, true);
        if (accept(rk, ek)) return rk.cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones());
    }
    return std::nullopt;
}

int cellSpans(const TrilinearCell& cell, const Vec3& o, const Vec3& d, std::array<CellSpan, 4>& spans) {
    struct Crossing {
        double t;
        int face;
        bool entry;
        Vec3 r;
    };
    std::array<Crossing, 12> crossings;
    int n = 0;
    for (int face = 0; face < 6; ++face) {
        const auto p = cell.faceCorners(face);
        std::array<PatchHit, 2> hits;
        const int count = intersectBilinearPatchAll(o, d, p[0], p[1], p[2], p[3], 0.0,
                                                    std::numeric_limits<double>::infinity(), hits);
        const int axis = face / 2;                // 0: w, 1: u, 2: v
        const int coord = axis == 0 ? 2 : axis - 1;  // index of the face's coordinate in (u,v,w)
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

}  // namespace vtex::render
