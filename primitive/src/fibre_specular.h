// The specular factor of a thin needle in the limit of an ideal fibre (reflectance_kernel.h).
// A needle's normals lie on the great circle orthogonal to its axis t; in the limit of an ideal
// fibre of elliptic cross-section (the 2×2 block S₂ of S orthogonal to t), the visible normals
// are distributed along the circle's angle φ as ρ(N)(N·v)⁺ / W with ρ(N) = 1/(√det S₂
// (NᵀS₂⁻¹N)^{3/2}) the cross-section's radius of curvature and W = 2√(vᵀS₂v) its width seen
// from v (for a round fibre: (N·v)⁺ / (2|v⊥|)). The integral over φ runs on the arc where N
// faces both l and v, by an 8-node Gauss–Legendre rule through a wrapped-Cauchy map centred
// on the lobe's peak with its width; a flat cross-section adds a second rule centred on its
// flattest side (ρ's peak) with S₂'s axis ratio, the two combined by the power heuristic, each
// integrating the part of the integrand it resolves.
//
// The map of a rule is φ = c + 2 atan(γ tan s), s Gauss–Legendre on [s₀, s₁]: near c it is
// the tangent map φ ≈ c + 2γ tan s (a Cauchy density of scale 2γ), and it makes a node's
// direction a rational function of sin s and cos s — (cos Δ, sin Δ) = (C² − γ²S², 2γSC) /
// (C² + γ²S²) — so that a node costs two short polynomials and no libm call (the tangent map
// took a tan, a sin and a cos per node), and the nodes run four at a time in single precision
// (its rounding, ~1e-7 of the terms, is far below the rule's own error). A needle whose
// highlight cone misses v (Kajiya and Kay's cone, below the Phong cut-off) is skipped outright.
#pragma once

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <initializer_list>
#include <optional>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace vtex::primitive::detail {

/// The gate of fibreSpecular: the fibre limit takes a needle when its axis ratio √(λ₁/λ₂) times
/// √(n+1) (its thickness in units of the lobe's width) is below kFibreGate (n+1)^kFibreGateGrowth.
/// The limit's error grows with that thickness, and the lattice-and-lobe estimator's shrinks;
/// the gate sits where the two cross on needles against the paper's integration: from a thickness
/// of about an eighth at shininess 1 to about half at 300 (a throw-away scan; docs/micro-primitive.md).
/// ReflectanceKernel.FibreLimitHoldsUpToItsGate bounds the error at the gate's edge. (A fixed 0.15
/// left thicker needles to the lattice and lobe, well off at shininess 100 and more.)
inline constexpr double kFibreGate = 0.105;
inline constexpr double kFibreGateGrowth = 0.3;
/// The gate as the largest λ₁/λ₂ the fibre limit takes at shininess n.
inline double fibreEigenRatioGate(double n) {
    const double thickness = kFibreGate * std::pow(n + 1, kFibreGateGrowth);
    return thickness * thickness / (n + 1);
}
/// The lobe rule's Cauchy scale in units of the lobe's standard deviation along the circle:
/// wider than the Gaussian it stands for, since 8 nodes resolve the lobe's tails poorly;
/// chosen on needles against the paper's integration, whose agreement
/// ReflectanceKernel.FibreLimitAgreesWithThePapersIntegration bounds.
inline constexpr double kLobeSpread = 1.4;
/// Below this axis ratio of the cross-section, a second rule follows its flattest side.
inline constexpr double kFlatSection = 0.5;

inline constexpr std::size_t kFibreNodes = 8;
using FibreLanes = std::array<float, kFibreNodes>;

/// atan2(y, x) for x ≥ 0 (the right half-plane, where both callers' angles lie) by Abramowitz and
/// Stegun's 4.4.49 (|error| ≤ 2e-8 on [0, 1]), in place of libm's atan2, which was the
/// costliest call of a fibre's set-up once its nodes took none.
inline double atanRightHalf(double y, double x) {
    const double ay = std::abs(y), big = std::max({ay, x, 1e-300});
    const double a = std::min(ay, x) / big, a2 = a * a;
    const double p = a * (1 + a2 * (-0.3333314528 + a2 * (0.1999355085 + a2 * (-0.1420889944 + a2 * (0.1065626393 +
                     a2 * (-0.0752896400 + a2 * (0.0429096138 + a2 * (-0.0161657367 + a2 * 0.0028662257))))))));
    return std::copysign(ay > x ? std::numbers::pi / 2 - p : p, y);
}

/// One rule on the circle of normals, in the 2-D frame (a, b) of the cross-section.
struct FibreRule {
    double cx = 1, cy = 0;  ///< the centre c, a unit vector
    double gamma = 1;       ///< half the Cauchy scale at c (tan(Δ/2) = γ tan s)
    double s0 = 0, s1 = 0;  ///< the arc's ends in s
    /// s of the direction e (unit) on the arc: atan(tan(Δ/2)/γ), tan(Δ/2) = (c×e)/(1 + c·e).
    double sOf(double ex, double ey) const { return atanRightHalf(cx * ey - cy * ex, gamma * (1 + cx * ex + cy * ey)); }
    /// The rule's density over φ at the unit direction (nx, ny): ds/dφ / (s₁ − s₀).
    float density(float nx, float ny) const {
        const float k = 1 + float(cx) * nx + float(cy) * ny, s = float(cx) * ny - float(cy) * nx, g = float(gamma);
        return g * k / ((g * g * k * k + s * s) * float(s1 - s0));
    }
};

/// The integrand along the circle: S₂ = [[saa, sab], [sab, sbb]] in (a, b), and v, l there.
struct FibreIntegrand {
    double saa, sbb, sab, det;  ///< det = det S₂
    double vx, vy, lx, ly, lv;  ///< v and l in (a, b); lv = l·v in 3-D
    double width;               ///< W = 2√(vᵀS₂v)
};

inline constexpr FibreLanes kFibreNodeS{-0.9602898564975363f, -0.7966664774136267f, -0.5255324099163290f,
                                        -0.1834346424956498f, 0.1834346424956498f,  0.5255324099163290f,
                                        0.7966664774136267f,  0.9602898564975363f};
inline constexpr FibreLanes kFibreWeights{0.1012285362903763f, 0.2223810344533745f, 0.3137066458778873f,
                                          0.3626837833783620f, 0.3626837833783620f, 0.3137066458778873f,
                                          0.2223810344533745f, 0.1012285362903763f};

#if defined(__SSE2__)
/// The rule's nodes four at a time (SSE2, part of every x86-64): per node the product of
/// jacobian, power-heuristic weight (with `other`) and ρ (N·v)(N·l) into `term`, and cos α
/// into `cosAlpha`; both 0 where N faces away from l or v or α ≥ 90°.
inline void fibreNodes(const FibreRule& rule, const FibreRule* other, const FibreIntegrand& f, FibreLanes& term,
                       FibreLanes& cosAlpha) {
    const auto set = [](double x) { return _mm_set1_ps(float(x)); };
    const auto poly = [](__m128 x2, std::initializer_list<float> c) {  // Horner in x², highest first
        __m128 r = _mm_set1_ps(*c.begin());
        for (auto it = c.begin() + 1; it != c.end(); ++it) r = _mm_add_ps(_mm_mul_ps(r, x2), _mm_set1_ps(*it));
        return r;
    };
    const __m128 mid = set(0.5 * (rule.s0 + rule.s1)), half = set(0.5 * (rule.s1 - rule.s0)), g = set(rule.gamma);
    const __m128 cx = set(rule.cx), cy = set(rule.cy), vx = set(f.vx), lx = set(f.lx), ly = set(f.ly), lv = set(f.lv);
    const __m128 saa = set(f.saa), sbb = set(f.sbb), sab2 = set(2 * f.sab), det = set(f.det);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1), two = _mm_set1_ps(2);
    for (std::size_t k = 0; k < kFibreNodes; k += 4) {
        const __m128 s = _mm_add_ps(mid, _mm_mul_ps(half, _mm_loadu_ps(&kFibreNodeS[k]))), x2 = _mm_mul_ps(s, s);
        // sin and cos on [−π/2, π/2]: Taylor to s¹¹ and s¹², truncation below 6e-8.
        const __m128 sn = _mm_mul_ps(s, poly(x2, {-1.f / 39916800, 1.f / 362880, -1.f / 5040, 1.f / 120, -1.f / 6, 1}));
        const __m128 cs = poly(x2, {1.f / 479001600, -1.f / 3628800, 1.f / 40320, -1.f / 720, 1.f / 24, -0.5f, 1});
        const __m128 gs = _mm_mul_ps(g, sn), c2 = _mm_mul_ps(cs, cs), g2 = _mm_mul_ps(gs, gs);
        const __m128 d = _mm_div_ps(one, _mm_add_ps(c2, g2));
        const __m128 cosD = _mm_mul_ps(_mm_sub_ps(c2, g2), d), sinD = _mm_mul_ps(_mm_mul_ps(two, _mm_mul_ps(gs, cs)), d);
        const __m128 x = _mm_sub_ps(_mm_mul_ps(cx, cosD), _mm_mul_ps(cy, sinD));
        const __m128 y = _mm_add_ps(_mm_mul_ps(cy, cosD), _mm_mul_ps(cx, sinD));
        const __m128 nv = _mm_mul_ps(x, vx), nl = _mm_add_ps(_mm_mul_ps(x, lx), _mm_mul_ps(y, ly));
        const __m128 c = _mm_sub_ps(_mm_mul_ps(two, _mm_mul_ps(nl, nv)), lv);
        const __m128 lit = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(nv, zero), _mm_cmpgt_ps(nl, zero)), _mm_cmpgt_ps(c, zero));
        // ρ = det S₂ / q^{3/2}, q = det S₂ · NᵀS₂⁻¹N = sbb x² − 2 sab xy + saa y².
        const __m128 q = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(_mm_mul_ps(sbb, x), _mm_mul_ps(sab2, y)), x),
                                    _mm_mul_ps(_mm_mul_ps(saa, y), y));
        const __m128 rho = _mm_div_ps(det, _mm_mul_ps(q, _mm_sqrt_ps(_mm_max_ps(q, _mm_set1_ps(1e-30f)))));
        // dφ/ds = 2γ / (C² + γ²S²).
        const __m128 jacobian = _mm_mul_ps(_mm_mul_ps(half, _mm_loadu_ps(&kFibreWeights[k])), _mm_mul_ps(two, _mm_mul_ps(g, d)));
        __m128 t = _mm_mul_ps(_mm_mul_ps(jacobian, rho), _mm_mul_ps(nv, nl));
        if (other) {
            // The power heuristic: own² / (own² + other²), each rule's density over φ.
            const auto density = [&](const FibreRule& r) {
                const __m128 rx = set(r.cx), ry = set(r.cy), rg = set(r.gamma);
                const __m128 kk = _mm_add_ps(one, _mm_add_ps(_mm_mul_ps(rx, x), _mm_mul_ps(ry, y)));
                const __m128 ss = _mm_sub_ps(_mm_mul_ps(rx, y), _mm_mul_ps(ry, x)), gk = _mm_mul_ps(rg, kk);
                return _mm_div_ps(gk, _mm_mul_ps(_mm_add_ps(_mm_mul_ps(gk, gk), _mm_mul_ps(ss, ss)), set(r.s1 - r.s0)));
            };
            const __m128 own = density(rule), them = density(*other);
            const __m128 own2 = _mm_mul_ps(own, own), sum2 = _mm_add_ps(own2, _mm_mul_ps(them, them));
            t = _mm_mul_ps(t, _mm_div_ps(own2, _mm_max_ps(sum2, _mm_set1_ps(1e-30f))));
        }
        _mm_storeu_ps(&term[k], _mm_and_ps(lit, t));
        _mm_storeu_ps(&cosAlpha[k], _mm_and_ps(lit, c));
    }
}
#else
inline void fibreNodes(const FibreRule& rule, const FibreRule* other, const FibreIntegrand& f, FibreLanes& term,
                       FibreLanes& cosAlpha) {
    const double mid = 0.5 * (rule.s0 + rule.s1), half = 0.5 * (rule.s1 - rule.s0), g = rule.gamma;
    for (std::size_t k = 0; k < kFibreNodes; ++k) {
        const double s = mid + half * kFibreNodeS[k], sn = std::sin(s), cs = std::cos(s);
        const double gs = g * sn, d = 1 / (cs * cs + gs * gs);
        const double cosD = (cs * cs - gs * gs) * d, sinD = 2 * gs * cs * d;
        const double x = rule.cx * cosD - rule.cy * sinD, y = rule.cy * cosD + rule.cx * sinD;
        const double nv = x * f.vx, nl = x * f.lx + y * f.ly, c = 2 * nl * nv - f.lv;
        term[k] = cosAlpha[k] = 0;
        if (!(nv > 0 && nl > 0 && c > 0)) continue;
        const double q = f.sbb * x * x - 2 * f.sab * x * y + f.saa * y * y;  // det S₂ · NᵀS₂⁻¹N
        double weight = 1;
        if (other) {
            const double own = rule.density(float(x), float(y)), them = other->density(float(x), float(y));
            weight = own * own / std::max(own * own + them * them, 1e-30);
        }
        term[k] = float(half * kFibreWeights[k] * 2 * g * d * weight * f.det / (q * std::sqrt(q)) * nv * nl);
        cosAlpha[k] = float(c);
    }
}
#endif

/// Σ over a rule's nodes of jacobian × weight × ρ (N·v)(N·l) cosⁿα / W; with `other`, the
/// power heuristic's weight against it. `power` raises a FibreLanes to the shininess in place.
template <class Power>
double fibreRuleSum(const FibreRule& rule, const FibreRule* other, const FibreIntegrand& f, const Power& power) {
    FibreLanes term, cosAlpha;
    fibreNodes(rule, other, f, term, cosAlpha);
    power(cosAlpha);
    float sum = 0;
    for (std::size_t k = 0; k < kFibreNodes; ++k) sum += term[k] * cosAlpha[k];
    return double(sum) / f.width;
}

/// ∫ D_v(N)(N·l)⁺ (n+2)/2π cosⁿα dN for the SGGX matrix `s` when it is a needle thin enough
/// against the Phong lobe for the limit of an ideal fibre (λ₁/λ₂ below `eigenRatioGate`, which
/// is fibreEigenRatioGate(n)); nullopt otherwise. `power` raises a FibreLanes
/// to the shininess in place; `cosCutoff` is the cos α below which cosⁿα counts as 0.
template <class Power>
std::optional<double> fibreSpecular(const Eigen::Matrix3d& s, const Eigen::Vector3d& l, const Eigen::Vector3d& v,
                                    double shininess, double eigenRatioGate, double cosCutoff, const Power& power) {
    using Eigen::Vector3d;
    // Eigenvalue estimates from the invariants: for λ₁ ≪ λ₂ ≤ λ₃, tr adj S ≈ λ₂λ₃ and det S =
    // λ₁λ₂λ₃; λ₂ is then the smaller root of x² − (λ₂+λ₃)x + λ₂λ₃. Rough elsewhere, where the
    // gate fails anyway.
    Eigen::Matrix3d adj;
    adj(0, 0) = s(1, 1) * s(2, 2) - s(1, 2) * s(1, 2);
    adj(1, 1) = s(0, 0) * s(2, 2) - s(0, 2) * s(0, 2);
    adj(2, 2) = s(0, 0) * s(1, 1) - s(0, 1) * s(0, 1);
    adj(0, 1) = adj(1, 0) = s(0, 2) * s(1, 2) - s(0, 1) * s(2, 2);
    adj(0, 2) = adj(2, 0) = s(0, 1) * s(1, 2) - s(0, 2) * s(1, 1);
    adj(1, 2) = adj(2, 1) = s(0, 1) * s(0, 2) - s(0, 0) * s(1, 2);
    const double det = std::max(s(0, 0) * adj(0, 0) + s(0, 1) * adj(0, 1) + s(0, 2) * adj(0, 2), 0.0);
    const double trAdj = adj.trace();
    if (!(trAdj > 0)) return std::nullopt;
    const double l1 = det / trAdj;
    const double sum = s.trace() - l1, product = trAdj - l1 * sum;
    const double l2 = 2 * product / (sum + std::sqrt(std::max(sum * sum - 4 * product, 0.0)));
    if (!(l2 > 0) || !(l1 < eigenRatioGate * l2)) return std::nullopt;
    // The axis: adj S ≈ λ₂λ₃ t tᵀ, so its longest column.
    int column = 0;
    for (int c = 1; c < 3; ++c)
        if (adj.col(c).squaredNorm() > adj.col(column).squaredNorm()) column = c;
    const Vector3d t = adj.col(column).normalized();
    const double lt = l.dot(t), vt = v.dot(t);
    const double lPerp = std::sqrt(std::max(1 - lt * lt, 0.0)), vPerp = std::sqrt(std::max(1 - vt * vt, 0.0));
    // On the circle cos α = 2(N·l)(N·v) − l·v peaks at the bisector of l⊥ and v⊥, at
    // |l⊥||v⊥| − (l·t)(v·t) = −cos(θ_l + θ_v) (the cone of Kajiya and Kay's fibre highlight).
    // Below the kernel's Phong cut-off every term is under 1e-6 of the lobe's peak and the
    // whole factor under 1e-6 · (n+2)/2π (∫D_v = 1, N·l ≤ 1): the bound the lattice drops too.
    const double peak = lPerp * vPerp - lt * vt;
    if (!(peak > cosCutoff) || !(lPerp > 1e-12) || !(vPerp > 1e-12)) return 0.0;
    // The frame (a, b) of the cross-section: a along v⊥, so that v = (|v⊥|, 0).
    const Vector3d a = (v - t * vt) / vPerp, b = t.cross(a), sa = s * a, sb = s * b;
    FibreIntegrand f{a.dot(sa), b.dot(sb), a.dot(sb), 0, vPerp, 0, l.dot(a), l.dot(b), l.dot(v), 0};
    f.det = std::max(f.saa * f.sbb - f.sab * f.sab, 1e-300);
    f.width = 2 * std::sqrt(f.saa) * vPerp;
    // The arc where N·v > 0 and N·l > 0 is centred on the bisector c of l̂⊥ and v̂⊥, half-width
    // H = π/2 − ∠(l⊥, v⊥)/2: sin H = |l̂⊥ + v̂⊥|/2, cos H = |l̂⊥ − v̂⊥|/2.
    const double lhx = f.lx / lPerp, lhy = f.ly / lPerp;
    const double bx = 1 + lhx, by = lhy, bisector = std::sqrt(bx * bx + by * by);
    if (!(bisector > 1e-9)) return 0.0;  // l⊥ opposite v⊥: no normal faces both
    const double sinH = 0.5 * bisector, cosH = 0.5 * std::sqrt((1 - lhx) * (1 - lhx) + lhy * lhy);
    FibreRule lobe;
    lobe.cx = bx / bisector;
    lobe.cy = by / bisector;
    // Near its peak cosⁿα ≈ cosⁿα* exp(−2n|l⊥||v⊥|Δφ²/cos α*): the lobe's width along φ.
    const double sigma = std::sqrt(std::max(peak, 1e-3) / (4 * (shininess + 1) * lPerp * vPerp));
    lobe.gamma = 0.5 * kLobeSpread * std::clamp(sigma, 1e-6, 1.0);
    lobe.s1 = atanRightHalf(sinH, lobe.gamma * (1 + cosH));
    lobe.s0 = -lobe.s1;
    // The flattest side: S₂'s eigenvector of the larger eigenvalue, on the arc's side.
    const double meanS = 0.5 * (f.saa + f.sbb), spreadS = std::hypot(0.5 * (f.saa - f.sbb), f.sab);
    const double ratio = std::sqrt(std::max(meanS - spreadS, 0.0) / std::max(meanS + spreadS, 1e-300));
    // A round cross-section's ρ is nearly flat: the lobe's rule alone resolves the integrand,
    // and a second rule's share of it (the power heuristic's partition) only adds error.
    if (!(ratio < kFlatSection)) return fibreRuleSum(lobe, nullptr, f, power) * (shininess + 2) / (2 * std::numbers::pi);
    FibreRule flat;
    const double larger = meanS + spreadS;  // (S₂ − λ₊)e = 0: of its two solutions, the longer
    double ex = f.sab, ey = larger - f.saa;
    if (ex * ex + ey * ey < (larger - f.sbb) * (larger - f.sbb) + f.sab * f.sab) ex = larger - f.sbb, ey = f.sab;
    const double en = std::sqrt(ex * ex + ey * ey), sign = ex * lobe.cx + ey * lobe.cy < 0 ? -1.0 : 1.0;
    flat.cx = sign * ex / en;
    flat.cy = sign * ey / en;
    flat.gamma = 0.5 * std::max(ratio, 1e-6);
    // The arc's ends: c rotated by ∓H.
    flat.s0 = flat.sOf(lobe.cx * cosH + lobe.cy * sinH, lobe.cy * cosH - lobe.cx * sinH);
    flat.s1 = flat.sOf(lobe.cx * cosH - lobe.cy * sinH, lobe.cy * cosH + lobe.cx * sinH);
    double total = fibreRuleSum(lobe, &flat, f, power);
    if (flat.s1 > flat.s0) total += fibreRuleSum(flat, &lobe, f, power);
    return total * (shininess + 2) / (2 * std::numbers::pi);
}

}  // namespace vtex::primitive::detail
