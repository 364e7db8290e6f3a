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

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace vtex::primitive::detail {

/// The gate of needleSpecular: the fibre limit takes a needle when its axis ratio √(λ₁/λ₂) times
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
    const double a = std::min(ay, x) / big, z = a * a, z2 = z * z, z4 = z2 * z2;
    // The polynomial in z = a² by Estrin's scheme (pairs, then pairs of pairs): its terms are
    // independent, so that its latency is four multiply-adds instead of Horner's eight, on the
    // serial path from a needle's axis to its first rule.
    const double low = (1 - 0.3333314528 * z) + (0.1999355085 - 0.1420889944 * z) * z2;
    const double high = (0.1065626393 - 0.0752896400 * z) + (0.0429096138 - 0.0161657367 * z) * z2;
    const double p = a * (low + (high + 0.0028662257 * z4) * z4);
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

/// How cosⁿα is raised: by repeated squaring for a whole n (`whole` ≥ 0; exact to a few ulps,
/// ~6 multiplies), else by libm's pow on the lanes that count.
struct FibrePower {
    int whole;
    double shininess;
};

#if defined(__SSE2__)
/// sin s and cos s on four lanes, s in [−π/2, π/2]: Taylor to s¹¹ and s¹², truncation below 6e-8.
/// Horner, not Estrin's scheme: near s = ±π/2, where cos s is small and a narrow lobe's nodes
/// sit, Estrin's larger partial sums rounded in single precision moved vtex_specular_estimators'
/// shininess-1000 random row (0.019 → 0.020).
inline void sinCosLanes(__m128 s, __m128& sn, __m128& cs) {
    const auto poly = [](__m128 x2, std::initializer_list<float> c) {  // Horner in x², highest first
        __m128 r = _mm_set1_ps(*c.begin());
        for (auto it = c.begin() + 1; it != c.end(); ++it) r = _mm_add_ps(_mm_mul_ps(r, x2), _mm_set1_ps(*it));
        return r;
    };
    const __m128 x2 = _mm_mul_ps(s, s);
    sn = _mm_mul_ps(s, poly(x2, {-1.f / 39916800, 1.f / 362880, -1.f / 5040, 1.f / 120, -1.f / 6, 1}));
    cs = poly(x2, {1.f / 479001600, -1.f / 3628800, 1.f / 40320, -1.f / 720, 1.f / 24, -0.5f, 1});
}

/// cⁿ on four lanes; without a whole n, libm's pow only on the lanes set in `mask` (0 elsewhere).
inline __m128 powerLanes(__m128 c, __m128 mask, const FibrePower& power) {
    if (power.whole >= 0) {
        __m128 p = _mm_set1_ps(1.0f);
        for (int e = power.whole; e > 0; e >>= 1) {
            if (e & 1) p = _mm_mul_ps(p, c);
            c = _mm_mul_ps(c, c);
        }
        return p;
    }
    alignas(16) float x[4];
    _mm_store_ps(x, c);
    const int lanes = _mm_movemask_ps(mask);
    for (int k = 0; k < 4; ++k) x[k] = lanes & (1 << k) ? float(std::pow(double(x[k]), power.shininess)) : 0.0f;
    return _mm_load_ps(x);
}

/// Σ over the rule's nodes, four at a time (SSE2, part of every x86-64), of jacobian × ρ (N·v)(N·l)
/// cosⁿα, with `other` times the power heuristic's weight against it; 0 where N faces away from
/// l or v or α ≥ 90°.
inline double fibreRuleSum(const FibreRule& rule, const FibreRule* other, const FibreIntegrand& f, const FibrePower& power) {
    const auto set = [](double x) { return _mm_set1_ps(float(x)); };
    const __m128 mid = set(0.5 * (rule.s0 + rule.s1)), half = set(0.5 * (rule.s1 - rule.s0)), g = set(rule.gamma);
    const __m128 cx = set(rule.cx), cy = set(rule.cy), vx = set(f.vx), lx = set(f.lx), ly = set(f.ly), lv = set(f.lv);
    const __m128 saa = set(f.saa), sbb = set(f.sbb), sab2 = set(2 * f.sab), det = set(f.det);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1), two = _mm_set1_ps(2), tiny = _mm_set1_ps(1e-30f);
    // The rule's own density over φ at its nodes is ds/dφ / (s₁ − s₀) = (C² + γ²S²) / (2γ(s₁ − s₀)):
    // no division. The other's, at a direction of its centre c', is γ'k / ((γ'k)² + s²) / (s'₁ − s'₀)
    // with k = 1 + c'·N, s = c'×N (FibreRule::density).
    const __m128 ownScale = set(other ? 1 / (2 * rule.gamma * (rule.s1 - rule.s0)) : 0);
    const __m128 ox = set(other ? other->cx : 0), oy = set(other ? other->cy : 0), og = set(other ? other->gamma : 0);
    const __m128 oScale = set(other ? 1 / (other->s1 - other->s0) : 0);
    __m128 sum = zero;
    for (std::size_t k = 0; k < kFibreNodes; k += 4) {
        __m128 sn, cs;
        sinCosLanes(_mm_add_ps(mid, _mm_mul_ps(half, _mm_loadu_ps(&kFibreNodeS[k]))), sn, cs);
        const __m128 gs = _mm_mul_ps(g, sn), c2 = _mm_mul_ps(cs, cs), g2 = _mm_mul_ps(gs, gs);
        const __m128 norm = _mm_add_ps(c2, g2), d = _mm_div_ps(one, norm);
        const __m128 cosD = _mm_mul_ps(_mm_sub_ps(c2, g2), d), sinD = _mm_mul_ps(_mm_mul_ps(two, _mm_mul_ps(gs, cs)), d);
        const __m128 x = _mm_sub_ps(_mm_mul_ps(cx, cosD), _mm_mul_ps(cy, sinD));
        const __m128 y = _mm_add_ps(_mm_mul_ps(cy, cosD), _mm_mul_ps(cx, sinD));
        const __m128 nv = _mm_mul_ps(x, vx), nl = _mm_add_ps(_mm_mul_ps(x, lx), _mm_mul_ps(y, ly));
        const __m128 c = _mm_sub_ps(_mm_mul_ps(two, _mm_mul_ps(nl, nv)), lv);
        const __m128 lit = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(nv, zero), _mm_cmpgt_ps(nl, zero)), _mm_cmpgt_ps(c, zero));
        // ρ = det S₂ / q^{3/2}, q = det S₂ · NᵀS₂⁻¹N = sbb x² − 2 sab xy + saa y².
        const __m128 q = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(_mm_mul_ps(sbb, x), _mm_mul_ps(sab2, y)), x),
                                    _mm_mul_ps(_mm_mul_ps(saa, y), y));
        const __m128 rho = _mm_div_ps(det, _mm_mul_ps(q, _mm_sqrt_ps(_mm_max_ps(q, tiny))));
        // dφ/ds = 2γ / (C² + γ²S²).
        const __m128 jacobian = _mm_mul_ps(_mm_mul_ps(half, _mm_loadu_ps(&kFibreWeights[k])), _mm_mul_ps(two, _mm_mul_ps(g, d)));
        __m128 t = _mm_mul_ps(_mm_mul_ps(jacobian, rho), _mm_mul_ps(nv, nl));
        if (other) {
            // The power heuristic: own² / (own² + other²), each rule's density over φ.
            const __m128 kk = _mm_add_ps(one, _mm_add_ps(_mm_mul_ps(ox, x), _mm_mul_ps(oy, y)));
            const __m128 ss = _mm_sub_ps(_mm_mul_ps(ox, y), _mm_mul_ps(oy, x)), gk = _mm_mul_ps(og, kk);
            const __m128 them = _mm_div_ps(_mm_mul_ps(gk, oScale), _mm_add_ps(_mm_mul_ps(gk, gk), _mm_mul_ps(ss, ss)));
            const __m128 own = _mm_mul_ps(norm, ownScale);
            const __m128 own2 = _mm_mul_ps(own, own), sum2 = _mm_add_ps(own2, _mm_mul_ps(them, them));
            t = _mm_mul_ps(t, _mm_div_ps(own2, _mm_max_ps(sum2, tiny)));
        }
        sum = _mm_add_ps(sum, _mm_and_ps(lit, _mm_mul_ps(t, powerLanes(_mm_and_ps(lit, c), lit, power))));
    }
    alignas(16) float parts[4];
    _mm_store_ps(parts, sum);
    return (double(parts[0]) + double(parts[1]) + double(parts[2]) + double(parts[3])) / f.width;
}
#else
inline double fibreRuleSum(const FibreRule& rule, const FibreRule* other, const FibreIntegrand& f, const FibrePower& power) {
    const double mid = 0.5 * (rule.s0 + rule.s1), half = 0.5 * (rule.s1 - rule.s0), g = rule.gamma;
    double sum = 0;
    for (std::size_t k = 0; k < kFibreNodes; ++k) {
        const double s = mid + half * kFibreNodeS[k], sn = std::sin(s), cs = std::cos(s);
        const double gs = g * sn, d = 1 / (cs * cs + gs * gs);
        const double cosD = (cs * cs - gs * gs) * d, sinD = 2 * gs * cs * d;
        const double x = rule.cx * cosD - rule.cy * sinD, y = rule.cy * cosD + rule.cx * sinD;
        const double nv = x * f.vx, nl = x * f.lx + y * f.ly, c = 2 * nl * nv - f.lv;
        if (!(nv > 0 && nl > 0 && c > 0)) continue;
        const double q = f.sbb * x * x - 2 * f.sab * x * y + f.saa * y * y;  // det S₂ · NᵀS₂⁻¹N
        double weight = 1;
        if (other) {
            const double own = rule.density(float(x), float(y)), them = other->density(float(x), float(y));
            weight = own * own / std::max(own * own + them * them, 1e-30);
        }
        const double cn = power.whole >= 0 ? std::pow(c, power.whole) : std::pow(c, power.shininess);
        sum += half * kFibreWeights[k] * 2 * g * d * weight * f.det / (q * std::sqrt(q)) * nv * nl * cn;
    }
    return sum / f.width;
}
#endif

/// Whether S, given by its invariants (trace, trace of its adjugate, determinant), is a needle
/// within the gate: λ₁/λ₂ < eigenRatioGate. Estimates from the invariants: for λ₁ ≪ λ₂ ≤ λ₃,
/// tr adj S ≈ λ₂λ₃ and det S = λ₁λ₂λ₃; λ₂ is then the smaller root of x² − (λ₂+λ₃)x + λ₂λ₃.
/// Rough elsewhere, where the gate fails anyway. The kernel tests it with the invariants its
/// sampler already has, before any of the fibre's set-up (most shapes are no needles).
inline bool takesFibreLimit(double trace, double trAdj, double det, double eigenRatioGate) {
    if (!(trAdj > 0)) return false;
    const double l1 = std::max(det, 0.0) / trAdj;
    const double sum = trace - l1, product = trAdj - l1 * sum;
    const double l2 = 2 * product / (sum + std::sqrt(std::max(sum * sum - 4 * product, 0.0)));
    return l2 > 0 && l1 < eigenRatioGate * l2;
}

/// The adjugate of the symmetric `s` (det S · S⁻¹ where S is invertible).
inline Eigen::Matrix3d adjugate(const Eigen::Matrix3d& s) {
    Eigen::Matrix3d adj;
    adj(0, 0) = s(1, 1) * s(2, 2) - s(1, 2) * s(1, 2);
    adj(1, 1) = s(0, 0) * s(2, 2) - s(0, 2) * s(0, 2);
    adj(2, 2) = s(0, 0) * s(1, 1) - s(0, 1) * s(0, 1);
    adj(0, 1) = adj(1, 0) = s(0, 2) * s(1, 2) - s(0, 1) * s(2, 2);
    adj(0, 2) = adj(2, 0) = s(0, 1) * s(1, 2) - s(0, 2) * s(1, 1);
    adj(1, 2) = adj(2, 1) = s(0, 1) * s(0, 2) - s(0, 0) * s(1, 2);
    return adj;
}

/// The circle of normals of a needle and the rules along it, as needleSpecular (and bandSpecular,
/// band_specular.h) integrate along it.
struct FibreFrame {
    Eigen::Vector3d t, a, b;  ///< the axis, and the frame (a, b) of the cross-section: a along v⊥
    double lt, vt;            ///< l·t and v·t
    double sinH, cosH;        ///< the arc where N faces l and v: c ± H, c the lobe rule's centre
    FibreIntegrand f;
    FibreRule lobe, flat;  ///< flat only where `flatSide`
    bool flatSide;         ///< the cross-section is flat (axis ratio below kFlatSection)
};

/// The frame and rules of needleSpecular for the SGGX matrix `s`, adj = adjugate(s), at shininess
/// n = power.shininess: false where no normal of the circle faces both l and v, or where the
/// fibre's highlight cone misses v by more than `cosCutoff` (then every term is below 1e-6 of
/// the lobe's peak).
inline bool fibreFrame(const Eigen::Matrix3d& s, const Eigen::Matrix3d& adj, const Eigen::Vector3d& l,
                       const Eigen::Vector3d& v, double cosCutoff, double shininess, FibreFrame& out) {
    using Eigen::Vector3d;
    // The axis: adj S ≈ λ₂λ₃ t tᵀ, so its longest column (chosen by index, without a branch:
    // which it is does not follow a pattern).
    const Vector3d norms = adj.colwise().squaredNorm();
    const int first = norms(1) > norms(0) ? 1 : 0;
    const int column = norms(2) > norms(first) ? 2 : first;
    const Vector3d t = adj.col(column).normalized();
    const double lt = l.dot(t), vt = v.dot(t);
    const double lPerp = std::sqrt(std::max(1 - lt * lt, 0.0)), vPerp = std::sqrt(std::max(1 - vt * vt, 0.0));
    // On the circle cos α = 2(N·l)(N·v) − l·v peaks at the bisector of l⊥ and v⊥, at
    // |l⊥||v⊥| − (l·t)(v·t) = −cos(θ_l + θ_v) (the cone of Kajiya and Kay's fibre highlight).
    // Below the kernel's Phong cut-off every term is under 1e-6 of the lobe's peak and the
    // whole factor under 1e-6 · (n+2)/2π (∫D_v = 1, N·l ≤ 1): the bound the lattice drops too.
    const double peak = lPerp * vPerp - lt * vt;
    if (!(peak > cosCutoff) || !(lPerp > 1e-12) || !(vPerp > 1e-12)) return false;
    // The frame (a, b) of the cross-section: a along v⊥, so that v = (|v⊥|, 0).
    const Vector3d a = (v - t * vt) / vPerp, b = t.cross(a), sa = s * a, sb = s * b;
    FibreIntegrand f{a.dot(sa), b.dot(sb), a.dot(sb), 0, vPerp, 0, l.dot(a), l.dot(b), l.dot(v), 0};
    f.det = std::max(f.saa * f.sbb - f.sab * f.sab, 1e-300);
    f.width = 2 * std::sqrt(f.saa) * vPerp;
    // The arc where N·v > 0 and N·l > 0 is centred on the bisector c of l̂⊥ and v̂⊥, half-width
    // H = π/2 − ∠(l⊥, v⊥)/2: sin H = |l̂⊥ + v̂⊥|/2, cos H = |l̂⊥ − v̂⊥|/2.
    // l̂⊥ in (a, b), from t directly (l·a = (l·v − (l·t)(v·t))/|v⊥|, l·b = l·(t×v)/|v⊥|) rather than
    // through f: a division fewer on the serial path to the first rule.
    const double inversePerp = 1 / (lPerp * vPerp);
    const double lhx = (f.lv - lt * vt) * inversePerp, lhy = l.dot(t.cross(v)) * inversePerp;
    const double bx = 1 + lhx, by = lhy, bisector = std::sqrt(bx * bx + by * by);
    if (!(bisector > 1e-9)) return false;  // l⊥ opposite v⊥: no normal faces both
    const double sinH = 0.5 * bisector, cosH = 0.5 * std::sqrt((1 - lhx) * (1 - lhx) + lhy * lhy);
    FibreRule& lobe = out.lobe;
    lobe.cx = bx / bisector;
    lobe.cy = by / bisector;
    // Near its peak cosⁿα ≈ cosⁿα* exp(−2n|l⊥||v⊥|Δφ²/cos α*): the lobe's width along φ.
    const double sigma = std::sqrt(std::max(peak, 1e-3) * inversePerp / (4 * (shininess + 1)));
    lobe.gamma = 0.5 * kLobeSpread * std::clamp(sigma, 1e-6, 1.0);
    lobe.s1 = atanRightHalf(sinH, lobe.gamma * (1 + cosH));
    lobe.s0 = -lobe.s1;
    out.t = t;
    out.a = a;
    out.b = b;
    out.lt = lt;
    out.vt = vt;
    out.sinH = sinH;
    out.cosH = cosH;
    out.f = f;
    // The flattest side: S₂'s eigenvector of the larger eigenvalue, on the arc's side.
    const double meanS = 0.5 * (f.saa + f.sbb), spreadS = std::sqrt(0.25 * (f.saa - f.sbb) * (f.saa - f.sbb) + f.sab * f.sab);
    const double ratio = std::sqrt(std::max(meanS - spreadS, 0.0) / std::max(meanS + spreadS, 1e-300));
    // A round cross-section's ρ is nearly flat: the lobe's rule alone resolves the integrand,
    // and a second rule's share of it (the power heuristic's partition) only adds error.
    out.flatSide = ratio < kFlatSection;
    if (!out.flatSide) return true;
    FibreRule& flat = out.flat;
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
    return true;
}

/// ∫ D_v(N)(N·l)⁺ (n+2)/2π cosⁿα dN for the SGGX matrix `s`, adj = adjugate(s), a needle thin
/// enough against the Phong lobe for the limit of an ideal fibre: one that takesFibreLimit admits
/// at fibreEigenRatioGate(n) (the caller tests the gate, with the invariants it has). `power` says
/// how cosⁿα is raised (n = its shininess); `cosCutoff` is the cos α below which cosⁿα counts as 0.
inline double needleSpecular(const Eigen::Matrix3d& s, const Eigen::Matrix3d& adj, const Eigen::Vector3d& l,
                             const Eigen::Vector3d& v, double cosCutoff, const FibrePower& power) {
    const double shininess = power.shininess;
    FibreFrame frame;
    if (!fibreFrame(s, adj, l, v, cosCutoff, shininess, frame)) return 0.0;
    if (!frame.flatSide) return fibreRuleSum(frame.lobe, nullptr, frame.f, power) * (shininess + 2) / (2 * std::numbers::pi);
    double total = fibreRuleSum(frame.lobe, &frame.flat, frame.f, power);
    if (frame.flat.s1 > frame.flat.s0) total += fibreRuleSum(frame.flat, &frame.lobe, frame.f, power);
    return total * (shininess + 2) / (2 * std::numbers::pi);
}

}  // namespace vtex::primitive::detail
