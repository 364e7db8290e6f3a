// The specular factor of a needle too thick for the fibre limit against a narrow Phong lobe
// (reflectance_kernel.h). Its normals fill a band around the great circle orthogonal to its axis
// t, and the lobe crosses the band on a patch whose width across the band is comparable to the
// band's own: the fibre limit (fibre_specular.h) takes the band as a line, the D_v lattice has
// a few points in it, the lobe's 8 points a few in the band, and the product of the two is what
// the integral needs (a needle of axis ratios 0.10 and 0.21 of the bush's voxels at shininess
// 1000, lit at its highlights: the lattice and lobe 0.069 off the paper's integration on average,
// 0.232 at the 95th percentile; ReflectanceKernel.BandRuleAgreesWithThePapersIntegration). Here the integral is a product rule over exact
// coordinates of the sphere around t: N = (u(φ) + τ t)/√(1+τ²), u(φ) on the circle, τ = tan of
// the latitude, dN = dφ dτ/(1+τ²)^{3/2}.
//
// Along φ, the fibre limit's rules (fibreFrame: a wrapped-Cauchy rule on the lobe, and one on the
// flattest side of a flat cross-section, by the power heuristic), the lobe's centred on h's
// direction on the circle and widened to the lobe's width there. Across, at each node of those,
// two rules in τ by the power heuristic, each τ = c + w tan ψ with ψ Gauss–Legendre on
// [−atan 3, atan 3]:
//   - the band's: SGGX's D(N) = 1/(π √|S| (NᵀS⁻¹N)²) (Heitz et al. 2015) over τ at fixed φ is,
//     exactly, ∝ (1+τ²)²/P(τ)² with P(τ) = (u + τt)ᵀ adj S (u + τt) = tᵀadj S t ((τ − τ₀)² + κ²), a
//     squared Cauchy profile: c = τ₀, w = κ make it cos²ψ, which Gauss–Legendre integrates well;
//   - the lobe's: around the half vector h, 1 − cos α ≈ 2(C²|δ|² + (δ·l)²) for a small offset δ
//     of N (C = h·l), a Gaussian of width 1/(2√(n(C² + (e·l)²))) across (e the direction of
//     increasing τ at h), whose centre moves across with the offset along (the lobe's tilt to
//     the band); c and w are those, w widened by kAcrossSpread as the fibre's lobe rule is.
// Each evaluates the exact integrand D_v(N)(N·l)(n+2)/2π cosⁿα, so the rule converges to the
// integral with its nodes: 8 along (16 on a flat cross-section) × 12 across resolve needles from
// 0.15 to 4 lobe widths thick at shininess 50–1000 to a few per cent (bench/vtex_specular_estimators,
// ReflectanceKernel.BandRule*), below which the fibre limit does as well, and beyond which the
// lattice and lobe do.
#pragma once

#include "fibre_specular.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vtex::primitive::detail {

/// The band rule's window: needles past the fibre gate up to a thickness (axis ratio √(λ₁/λ₂)
/// times √(n+1), the ratio in units of the lobe's width) of kBandThickest, from shininess
/// kBandShininess. Below it the lattice and lobe meet the row-16 goal (the estimator table's rows
/// at 1 and 10), and the scene default (20) keeps their cost; beyond a thickness of 4 they do as
/// well as this rule (a throw-away scan of needles against a converged rule, docs/micro-primitive.md).
inline constexpr double kBandShininess = 50;
inline constexpr double kBandThickest = 4;
/// The largest λ₁/λ₂ the band rule takes at shininess n: 0 (none) below kBandShininess.
inline double bandEigenRatioGate(double n) { return n < kBandShininess ? 0.0 : kBandThickest * kBandThickest / (n + 1); }
/// From kBandShininess the band rule also takes needles between a thickness of kBandThinnest and
/// the fibre gate (0.105 (n+1)^0.3: 0.42 at 100, 0.83 at 1000): there the fibre limit, which has
/// no normals off its circle, misses where the lobe meets the band's tails off the circle. On
/// round needles under random l and v against the paper's integration at 192 cells
/// (ReflectanceKernel.BandRuleTakesThickFibresUnderAnyLight) it is 0.03–0.06 off at a thickness
/// of 0.2 and 0.09–0.17 at 0.4 (shininess 100–1000), the band rule within 0.017; lit at their
/// highlights both are within 0.025. At 0.15 the fibre limit keeps the needles of
/// ReflectanceKernel.FibreLimitAgreesWithThePapersIntegration (axis ratio 0.01 at shininess 100).
inline constexpr double kBandThinnest = 0.15;
/// Whether the band rule takes S: λ₁ < gate · λ₂ for its two smallest eigenvalues, exactly.
/// detail::takesFibreLimit's test from the invariants (λ₁ ≈ det S / tr adj S) is right for needles
/// only: for a sphere it estimates λ₁/λ₂ = 0.21, which the band's window (up to 16/(n+1), 0.31 at
/// n = 50) admitted, so spheres at shininess 50–79 took the band rule around an arbitrary axis and
/// were 25–46 % off (docs/micro-primitive.md, "The band rule's gate, exact";
/// ReflectanceKernel.BandRuleTakesOnlyNeedles). Its ratio is a lower bound of the
/// true one (its λ₁, 1/Σ 1/λᵢ, is at most λ₁, and its λ₂, the smaller root of the quadratic left
/// with that λ₁, at least λ₂), so it stays the cheap first test and this one confirms what it passes.
/// A needle's cross-section flatter than kBandFlattest (axis ratio √(λ₂/λ₃)) is a disc, whose
/// normals crowd around one direction: the lattice and lobe take it (on discs within 0.02, the
/// estimator table's rows; through the band rule one such shape was 25 % off at shininess 60). The
/// band rule's window holds down to it (ReflectanceKernel.BandRuleHoldsAcrossItsWindow).
inline constexpr double kBandFlattest = 0.01;
inline bool bandTakes(const Eigen::Matrix3d& s, double gate) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(s, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d& lambda = solver.eigenvalues();  // increasing
    return lambda(1) > 0 && lambda(0) < gate * lambda(1) && lambda(1) >= kBandFlattest * kBandFlattest * lambda(2);
}

/// The largest λ₁/λ₂ the kernel's fibre limit takes at shininess n: fibreEigenRatioGate(n), from
/// kBandShininess at most kBandThinnest²/(n+1).
inline double kernelFibreEigenRatioGate(double n) {
    const double gate = fibreEigenRatioGate(n);
    return n < kBandShininess ? gate : std::min(gate, kBandThinnest * kBandThinnest / (n + 1));
}

/// The lobe's rule across is wider than its Gaussian, as the fibre's along it (kLobeSpread).
inline constexpr double kAcrossSpread = 1.4;
/// Each rule across reaches ψ = ±atan 3, |τ − c| ≤ 3w: the rest of a squared Cauchy profile holds
/// under 1 % of it, and the other rule covers the lobe's side.
inline constexpr float kAcrossReach = 3;
/// The 6-node Gauss–Legendre rule on ψ ∈ [−atan 3, atan 3]: tan ψ, the weights (Gauss–Legendre
/// weight × atan 3 × (1 + tan²ψ): dτ = w × this) and 1 + tan²ψ, in the lanes of bandAcrossSum's
/// three groups: the band's nodes 0–3, the lobe's 0–3, then the band's 4–5 and the lobe's 4–5.
alignas(16) inline constexpr std::array<float, 12> kAcrossTan{
    -2.325573937f, -1.084429298f, -0.307196877f, 0.307196877f, -2.325573937f, -1.084429298f,
    -0.307196877f, 0.307196877f,  1.084429298f,  2.325573937f, 1.084429298f,  2.325573937f};
alignas(16) inline constexpr std::array<float, 12> kAcrossWeight{
    1.371324531f, 0.980516491f, 0.639600037f, 0.639600037f, 1.371324531f, 0.980516491f,
    0.639600037f, 0.639600037f, 0.980516491f, 1.371324531f, 0.980516491f, 1.371324531f};
alignas(16) inline constexpr std::array<float, 12> kAcrossSecant2{
    6.408294136f, 2.175986902f, 1.094369921f, 1.094369921f, 6.408294136f, 2.175986902f,
    1.094369921f, 1.094369921f, 2.175986902f, 6.408294136f, 2.175986902f, 6.408294136f};

/// What the rules across need, in the frame (a, b, t) of fibreFrame.
struct BandAcross {
    double aaa, aab, abb, aat, abt, att;  ///< adj S in (a, b, t)
    double vx, vt, lx, ly, lt, lv;        ///< v = (vx, 0, vt), l = (lx, ly, lt), l·v
    double lobeTau, lobeWidth, lobeTilt;  ///< the lobe's centre τ_h + tilt · sin Δφ and width across
    double hx, hy;                        ///< the direction of h on the circle (Δφ from it)
    double cosCutoff;                     ///< cos α below which cosⁿα counts as 0
};

/// The nodes of `rule` along the circle: their direction (x, y) in (a, b), and their weight
/// dφ/ds × Gauss–Legendre weight × half the arc in s, times the power heuristic's weight against
/// `other`: fibreRuleSum's nodes (the same map, four at a time without a libm call).
inline void fibreNodes(const FibreRule& rule, const FibreRule* other, float* xs, float* ys, float* ws) {
#if defined(__SSE2__)
    const auto set = [](double x) { return _mm_set1_ps(float(x)); };
    const __m128 mid = set(0.5 * (rule.s0 + rule.s1)), half = set(0.5 * (rule.s1 - rule.s0)), g = set(rule.gamma);
    const __m128 cx = set(rule.cx), cy = set(rule.cy), one = _mm_set1_ps(1), two = _mm_set1_ps(2), tiny = _mm_set1_ps(1e-30f);
    const __m128 ownScale = set(other ? 1 / (2 * rule.gamma * (rule.s1 - rule.s0)) : 0);
    const __m128 ox = set(other ? other->cx : 0), oy = set(other ? other->cy : 0), og = set(other ? other->gamma : 0);
    const __m128 oScale = set(other ? 1 / (other->s1 - other->s0) : 0);
    for (std::size_t k = 0; k < kFibreNodes; k += 4) {
        __m128 sn, cs;
        sinCosLanes(_mm_add_ps(mid, _mm_mul_ps(half, _mm_loadu_ps(&kFibreNodeS[k]))), sn, cs);
        const __m128 gs = _mm_mul_ps(g, sn), c2 = _mm_mul_ps(cs, cs), g2 = _mm_mul_ps(gs, gs);
        const __m128 norm = _mm_add_ps(c2, g2), d = _mm_div_ps(one, norm);
        const __m128 cosD = _mm_mul_ps(_mm_sub_ps(c2, g2), d), sinD = _mm_mul_ps(_mm_mul_ps(two, _mm_mul_ps(gs, cs)), d);
        const __m128 x = _mm_sub_ps(_mm_mul_ps(cx, cosD), _mm_mul_ps(cy, sinD));
        const __m128 y = _mm_add_ps(_mm_mul_ps(cy, cosD), _mm_mul_ps(cx, sinD));
        __m128 w = _mm_mul_ps(_mm_mul_ps(half, _mm_loadu_ps(&kFibreWeights[k])), _mm_mul_ps(two, _mm_mul_ps(g, d)));
        if (other) {
            const __m128 kk = _mm_add_ps(one, _mm_add_ps(_mm_mul_ps(ox, x), _mm_mul_ps(oy, y)));
            const __m128 ss = _mm_sub_ps(_mm_mul_ps(ox, y), _mm_mul_ps(oy, x)), gk = _mm_mul_ps(og, kk);
            const __m128 them = _mm_div_ps(_mm_mul_ps(gk, oScale), _mm_add_ps(_mm_mul_ps(gk, gk), _mm_mul_ps(ss, ss)));
            const __m128 own = _mm_mul_ps(norm, ownScale);
            const __m128 own2 = _mm_mul_ps(own, own), sum2 = _mm_add_ps(own2, _mm_mul_ps(them, them));
            w = _mm_mul_ps(w, _mm_div_ps(own2, _mm_max_ps(sum2, tiny)));
        }
        _mm_storeu_ps(xs + k, x);
        _mm_storeu_ps(ys + k, y);
        _mm_storeu_ps(ws + k, w);
    }
#else
    const double mid = 0.5 * (rule.s0 + rule.s1), half = 0.5 * (rule.s1 - rule.s0);
    for (std::size_t k = 0; k < kFibreNodes; ++k) {
        const double s = mid + half * kFibreNodeS[k], sn = std::sin(s), cs = std::cos(s);
        const double gs = rule.gamma * sn, d = 1 / (cs * cs + gs * gs);
        const double cosD = (cs * cs - gs * gs) * d, sinD = 2 * gs * cs * d;
        const double x = rule.cx * cosD - rule.cy * sinD, y = rule.cy * cosD + rule.cx * sinD;
        double weight = half * kFibreWeights[k] * 2 * rule.gamma * d;
        if (other) {
            const double own = rule.density(float(x), float(y)), them = other->density(float(x), float(y));
            weight *= own * own / std::max(own * own + them * them, 1e-30);
        }
        xs[k] = float(x);
        ys[k] = float(y);
        ws[k] = float(weight);
    }
#endif
}

/// Σ over the 12 nodes across the band at the node u = (x, y) of the circle of
/// (m·v)(m·l) cosⁿα / (P'² √(1+τ²)) dτ × the power heuristic's weight, m = u + τt and
/// P' = (τ − τ₀)² + κ² = P(τ)/tᵀadj S t: the integrand per dφ dτ up to bandSpecular's constant.
inline double bandAcrossSum(const BandAcross& b, double x, double y, const FibrePower& power) {
    const double uv = x * b.vx, ul = x * b.lx + y * b.ly;
    const double uAu = x * x * b.aaa + 2 * x * y * b.aab + y * y * b.abb, uAt = x * b.aat + y * b.abt;
    const double tau0 = -uAt / b.att, kappa2 = std::max(uAu * b.att - uAt * uAt, 1e-300) / (b.att * b.att);
    const double lobeTau = b.lobeTau + b.lobeTilt * (b.hx * y - b.hy * x);
#if defined(__SSE2__)
    const auto set = [](double v) { return _mm_set1_ps(float(v)); };
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1), two = _mm_set1_ps(2), reach = _mm_set1_ps(kAcrossReach);
    const __m128 absMask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 uvV = set(uv), ulV = set(ul), vtV = set(b.vt), ltV = set(b.lt), lvV = set(b.lv);
    const __m128 tau0V = set(tau0), kappa2V = set(kappa2), cut = set(std::max(b.cosCutoff, 0.0));
    // Each lane's own rule's centre and width and the other rule's, in kAcrossTan's order.
    const __m128 cb = tau0V, wb = set(std::sqrt(kappa2)), cl = set(lobeTau), wl = set(b.lobeWidth);
    const __m128 own[3][2] = {{cb, wb}, {cl, wl}, {_mm_movelh_ps(cb, cl), _mm_movelh_ps(wb, wl)}};
    const __m128 other[3][2] = {{cl, wl}, {cb, wb}, {_mm_movelh_ps(cl, cb), _mm_movelh_ps(wl, wb)}};
    __m128 total = zero;
    for (std::size_t group = 0; group < 3; ++group) {
        const std::size_t k = 4 * group;
        const __m128 c = own[group][0], w = own[group][1], co = other[group][0], wo = other[group][1];
        const __m128 tau = _mm_add_ps(c, _mm_mul_ps(w, _mm_load_ps(&kAcrossTan[k])));
        const __m128 db = _mm_sub_ps(tau, tau0V), p = _mm_add_ps(_mm_mul_ps(db, db), kappa2V);
        const __m128 mv = _mm_add_ps(uvV, _mm_mul_ps(tau, vtV)), ml = _mm_add_ps(ulV, _mm_mul_ps(tau, ltV));
        const __m128 g = _mm_add_ps(one, _mm_mul_ps(tau, tau)), mlv = _mm_mul_ps(ml, mv);
        const __m128 cosA = _mm_sub_ps(_mm_div_ps(_mm_mul_ps(two, mlv), g), lvV);
        const __m128 lit = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(mv, zero), _mm_cmpgt_ps(ml, zero)), _mm_cmpgt_ps(cosA, cut));
        // Most groups away from the lobe's peak have no node above the cut-off (cosⁿα
        // under 1e-6 of the peak): they skip the power, the weights and the divisions.
        if (_mm_movemask_ps(lit) == 0) continue;
        // The power heuristic: the rules' densities over τ are w/(w² + d²) within their reach, so
        // other/own = r/q with r = wo w (1 + tan²ψ), q = wo² + do², and own²/(own² + other²) =
        // q²/(q² + r²): one division with the integrand's.
        const __m128 dO = _mm_sub_ps(tau, co), q = _mm_add_ps(_mm_mul_ps(wo, wo), _mm_mul_ps(dO, dO));
        const __m128 inside = _mm_cmple_ps(_mm_and_ps(dO, absMask), _mm_mul_ps(reach, wo));
        const __m128 r = _mm_and_ps(inside, _mm_mul_ps(_mm_mul_ps(wo, w), _mm_load_ps(&kAcrossSecant2[k])));
        const __m128 q2 = _mm_mul_ps(q, q), dTau = _mm_mul_ps(w, _mm_load_ps(&kAcrossWeight[k]));
        const __m128 denominator = _mm_mul_ps(_mm_add_ps(q2, _mm_mul_ps(r, r)), _mm_mul_ps(_mm_mul_ps(p, p), _mm_sqrt_ps(g)));
        const __m128 value = _mm_div_ps(_mm_mul_ps(mlv, _mm_mul_ps(dTau, q2)), denominator);
        total = _mm_add_ps(total, _mm_and_ps(lit, _mm_mul_ps(value, powerLanes(_mm_and_ps(lit, cosA), lit, power))));
    }
    alignas(16) float parts[4];
    _mm_store_ps(parts, total);
    return double(parts[0]) + double(parts[1]) + double(parts[2]) + double(parts[3]);
#else
    const double centre[2] = {tau0, lobeTau}, width[2] = {std::sqrt(kappa2), b.lobeWidth};
    double sum = 0;
    for (std::size_t j = 0; j < 12; ++j) {
        const std::size_t own = j < 4 || (j >= 8 && j < 10) ? 0 : 1, other = 1 - own;
        const double t = kAcrossTan[j], tau = centre[own] + width[own] * t, dTau = width[own] * kAcrossWeight[j];
        const double db = tau - tau0, p = db * db + kappa2, mv = uv + tau * b.vt, ml = ul + tau * b.lt, g = 1 + tau * tau;
        const double cosA = 2 * ml * mv / g - b.lv;
        if (!(mv > 0 && ml > 0 && cosA > std::max(b.cosCutoff, 0.0))) continue;
        const double dO = tau - centre[other], q = width[other] * width[other] + dO * dO;
        const double r = std::abs(dO) <= kAcrossReach * width[other] ? width[other] * width[own] * kAcrossSecant2[j] : 0;
        const double cn = power.whole >= 0 ? std::pow(cosA, power.whole) : std::pow(cosA, power.shininess);
        sum += mv * ml * dTau * q * q / ((q * q + r * r) * p * p * std::sqrt(g)) * cn;
    }
    return sum;
#endif
}

/// ∫ D_v(N)(N·l)⁺ (n+2)/2π cosⁿα dN for the SGGX matrix `s`, adj = adjugate(s), a needle that
/// bandEigenRatioGate(n) admits (the caller tests the gate, with the invariants it has), by the
/// product rule above. `power` says how cosⁿα is raised (n = its shininess); `cosCutoff` is the
/// cos α below which cosⁿα counts as 0 (the kernel calls it out of line, in clones of its own).
inline double bandSpecular(const Eigen::Matrix3d& s, const Eigen::Matrix3d& adj, const Eigen::Vector3d& l,
                           const Eigen::Vector3d& v, double cosCutoff, const FibrePower& power) {
    using Eigen::Vector3d;
    const double n = power.shininess;
    FibreFrame frame;
    // No cut-off on the circle's highlight cone: normals off the circle may still meet the lobe.
    if (!fibreFrame(s, adj, l, v, -2, n, frame)) return 0.0;
    const Vector3d& a = frame.a;
    const Vector3d& b = frame.b;
    const Vector3d& t = frame.t;
    const Vector3d adjA = adj * a, adjB = adj * b, adjT = adj * t;
    BandAcross across{a.dot(adjA), a.dot(adjB), b.dot(adjB), a.dot(adjT), b.dot(adjT), t.dot(adjT),
                      frame.f.vx, frame.vt, frame.f.lx, frame.f.ly, frame.lt, frame.f.lv, 0, 0, 0, 0, 0, cosCutoff};
    // The lobe across the band, around h = (l + v)/|l + v| (module comment).
    const Vector3d h(frame.f.lx + frame.f.vx, frame.f.ly, frame.lt + frame.vt);
    if (!(h.squaredNorm() > 1e-18)) return 0.0;  // l = −v: no mirror direction
    const Vector3d hn = h.normalized();
    const double hRadius = std::hypot(hn.x(), hn.y()), hPerp = std::max(hRadius, 1e-3);
    const double secant2 = 1 + (hn.z() / hPerp) * (hn.z() / hPerp);
    across.hx = hRadius > 0 ? hn.x() / hRadius : frame.lobe.cx;  // ĥ⊥, unit
    across.hy = hRadius > 0 ? hn.y() / hRadius : frame.lobe.cy;
    // e·l and e_φ·l, e = (t − (h·t)h)/|h⊥| across and e_φ = t × ĥ⊥ along, at h; C = h·l.
    const double C = std::sqrt(0.5 * (1 + frame.f.lv));
    const double lTau = (frame.lt - hn.z() * C) / hPerp, lPhi = across.hx * frame.f.ly - across.hy * frame.f.lx;
    const double curvature = std::max(C * C + lTau * lTau, 1e-6);
    // The lobe's centre and width across are kept within 10³ in τ (h within 0.06° of the axis, or
    // l nearly −v): the band's D is there ~10⁻¹² of its peak, and the float sums across stay far
    // from overflow (τ⁴ under 10¹⁵; with h on the axis they overflowed to NaN).
    across.lobeTau = std::clamp(hn.z() / hPerp, -1e3, 1e3);
    across.lobeWidth = std::min(kAcrossSpread * secant2 / (2 * std::sqrt(std::max(n, 1.0) * curvature)), 1e3);
    across.lobeTilt = -lTau * lPhi / curvature * hPerp * secant2;
    // Along: the lobe rule on h's direction on the circle, ĥ⊥ (not the bisector of l̂⊥ and v̂⊥,
    // where cos α peaks on the circle itself), with the larger of the fibre's width and the lobe's
    // width along φ at h, 1/(2√(n(C² + (e_φ·l)²))) over |h⊥|: off the circle the lobe is wider in
    // φ, and where it lies far from the circle (near the needle's tip) the integrand is there,
    // in D's tail, and not on the circle's peak.
    const double sigmaH = 1 / (2 * std::sqrt(std::max(n, 1.0) * std::max(C * C + lPhi * lPhi, 1e-6))) / hPerp;
    FibreRule onH = frame.lobe;
    onH.gamma = std::max(onH.gamma, 0.5 * kLobeSpread * std::min(sigmaH, 1.0));
    onH.cx = across.hx;
    onH.cy = across.hy;
    // The arc's ends: the bisector rotated by ∓H (ĥ⊥ lies on the arc but off its middle).
    const double bx = frame.lobe.cx, by = frame.lobe.cy, sinH = frame.sinH, cosH = frame.cosH;
    onH.s0 = onH.sOf(bx * cosH + by * sinH, by * cosH - bx * sinH);
    onH.s1 = onH.sOf(bx * cosH - by * sinH, by * cosH + bx * sinH);
    // (The map needs −π/2 ≤ s₀ < s₁ ≤ π/2: with l or v within rounding of the axis, l̂⊥ or v̂⊥ is
    // not unit and the ends are not; the fibre's own rule is kept then.)
    constexpr double kHalfPi = std::numbers::pi / 2;
    if (onH.s1 > onH.s0 && onH.s0 >= -kHalfPi && onH.s1 <= kHalfPi) frame.lobe = onH;
    // Along: the fibre's rules' nodes.
    alignas(16) float xs[2 * kFibreNodes], ys[2 * kFibreNodes], ws[2 * kFibreNodes];
    const bool flat = frame.flatSide && frame.flat.s1 > frame.flat.s0;
    fibreNodes(frame.lobe, flat ? &frame.flat : nullptr, xs, ys, ws);
    if (flat) fibreNodes(frame.flat, &frame.lobe, xs + kFibreNodes, ys + kFibreNodes, ws + kFibreNodes);
    double total = 0;
    for (std::size_t k = 0; k < (flat ? 2 : 1) * kFibreNodes; ++k) total += ws[k] * bandAcrossSum(across, xs[k], ys[k], power);
    // D_v (N·l)(n+2)/2π dN/(dφ dτ) = det^{3/2} / (π A(v) (tᵀadj t)²) × the sum's terms × (n+2)/2π.
    const double det = std::max(s.determinant(), 1e-300), area = std::sqrt(std::max(v.dot(s * v), 1e-300));
    return total * det * std::sqrt(det) / (std::numbers::pi * area * across.att * across.att) * (n + 2) /
           (2 * std::numbers::pi);
}

}  // namespace vtex::primitive::detail
