// The specular factor of a thin needle in the limit of an ideal fibre (reflectance_kernel.h).
// A needle's normals lie on the great circle orthogonal to its axis t; in the limit of an ideal
// fibre of elliptic cross-section (the 2×2 block S₂ of S orthogonal to t), the visible normals
// are distributed along the circle's angle φ as ρ(N)(N·v)⁺ / W with ρ(N) = 1/(√det S₂
// (NᵀS₂⁻¹N)^{3/2}) the cross-section's radius of curvature and W = 2√(vᵀS₂v) its width seen
// from v (for a round fibre: (N·v)⁺ / (2|v⊥|)). The integral over φ runs on the arc where N
// faces both l and v, by an 8-node Gauss–Legendre rule through a tangent map centred on the
// lobe's peak with its width; a flat cross-section adds a second rule centred on its flattest
// side (ρ's peak) with S₂'s axis ratio, the two combined by the power heuristic, each
// integrating the part of the integrand it resolves.
#pragma once

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

namespace vtex::primitive::detail {

/// The gate of fibreSpecular, measured by bench/vtex_specular_estimators: the limit's error
/// grows with (axis ratio / lobe width); at 0.15 it is within 4 % (needles of ratio 1e-2 at
/// shininess 100, ReflectanceKernel.FibreLimitAgreesWithThePapersIntegration).
inline constexpr double kFibreGate = 0.15;
/// The lobe rule's Cauchy scale in units of the lobe's standard deviation along the circle:
/// wider than the Gaussian it stands for, since 8 nodes resolve the lobe's tails poorly;
/// chosen on needles against the paper's integration, whose agreement
/// ReflectanceKernel.FibreLimitAgreesWithThePapersIntegration bounds.
inline constexpr double kLobeSpread = 1.4;
/// Below this axis ratio of the cross-section, a second rule follows its flattest side.
inline constexpr double kFlatSection = 0.5;

/// ∫ D_v(N)(N·l)⁺ (n+2)/2π cosⁿα dN for the SGGX matrix `s` when it is a needle thin enough
/// against the Phong lobe for the limit of an ideal fibre (axis ratio √(λ₁/λ₂) below
/// kFibreGate times the lobe's width 1/√(n+1)); nullopt otherwise. `power(c)` is cⁿ.
template <class Power>
std::optional<double> fibreSpecular(const Eigen::Matrix3d& s, const Eigen::Vector3d& l, const Eigen::Vector3d& v,
                                    double shininess, const Power& power) {
    using Eigen::Vector3d;
    constexpr double pi = std::numbers::pi;
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
    if (!(l2 > 0) || !(l1 / l2 * (shininess + 1) < kFibreGate * kFibreGate)) return std::nullopt;
    // The axis: adj S ≈ λ₂λ₃ t tᵀ, so its longest column.
    int column = 0;
    for (int c = 1; c < 3; ++c)
        if (adj.col(c).squaredNorm() > adj.col(column).squaredNorm()) column = c;
    const Vector3d t = adj.col(column).normalized();
    const Vector3d vPerp = v - t * t.dot(v);
    if (!(vPerp.squaredNorm() > 1e-24)) return 0.0;  // seen along its axis: no visible side
    // The cross-section's axes: a along S₂'s larger eigenvalue (ρ's peak), b = t × a.
    Vector3d a = vPerp.normalized(), b = t.cross(a);
    {
        const double saa = a.dot(s * a), sbb = b.dot(s * b), sab = a.dot(s * b);
        const double theta = 0.5 * std::atan2(2 * sab, saa - sbb);
        const Vector3d rotated = std::cos(theta) * a + std::sin(theta) * b;
        b = t.cross(rotated);
        a = rotated;
    }
    const double saa = a.dot(s * a), sbb = b.dot(s * b), sab = a.dot(s * b);
    const double s2Det = std::max(saa * sbb - sab * sab, 1e-300);
    const Eigen::Vector2d v2(v.dot(a), v.dot(b)), l2d(l.dot(a), l.dot(b));
    const double width = 2 * std::sqrt(saa * v2.x() * v2.x() + 2 * sab * v2.x() * v2.y() + sbb * v2.y() * v2.y());
    // The arc where N·v > 0 and N·l > 0, as an interval of φ around v's angle.
    const double phiV = std::atan2(v2.y(), v2.x());
    const double lPerp = l2d.norm(), vPerpLength = v2.norm();
    const double dl = lPerp > 1e-12 ? std::remainder(std::atan2(l2d.y(), l2d.x()) - phiV, 2 * pi) : 0;
    const double lo = phiV - pi / 2 + std::max(dl, 0.0), hi = phiV + pi / 2 + std::min(dl, 0.0);
    if (!(hi > lo)) return 0.0;
    const double middle = 0.5 * (lo + hi);
    const auto nearMiddle = [&](double phi) { return middle + std::remainder(phi - middle, 2 * pi); };
    // Along the circle, cos α = 2(N·l)(N·v) − l·v = |l⊥||v⊥|(cos(2φ − φ_l − φ_v) + cos(φ_l − φ_v))
    // − l·v peaks at the bisector of l⊥ and v⊥, where cosⁿα ≈ cosⁿα* exp(−2n|l⊥||v⊥|Δφ²/cos α*).
    double lobeCentre = middle, lobeSpread = 1;
    if (lPerp > 1e-12) {
        lobeCentre = nearMiddle(phiV + 0.5 * dl);
        const double peak = lPerp * vPerpLength * (1 + std::cos(dl)) - l.dot(v);
        lobeSpread = std::clamp(std::sqrt(std::max(peak, 1e-3) / (4 * (shininess + 1) * lPerp * vPerpLength)), 1e-6, 1.0);
    }
    const double phiFlat = std::abs(nearMiddle(0.0) - middle) < std::abs(nearMiddle(pi) - middle) ? nearMiddle(0.0) : nearMiddle(pi);
    const std::array<double, 2> centre{lobeCentre, phiFlat};
    const std::array<double, 2> spread{kLobeSpread * lobeSpread,
                                       std::max(std::sqrt(std::min(saa, sbb) / std::max(saa, sbb)), 1e-6)};
    // A round cross-section's ρ is nearly flat: the lobe's rule alone resolves the integrand,
    // and a second rule's share of it (the power heuristic's partition) only adds error.
    const std::size_t rules = spread[1] < kFlatSection ? 2 : 1;
    // A rule's density: the Cauchy distribution its tangent map draws, restricted to the arc.
    std::array<double, 2> s0{}, s1{};
    for (std::size_t r = 0; r < rules; ++r) {
        s0[r] = std::atan((lo - centre[r]) / spread[r]);
        s1[r] = std::atan((hi - centre[r]) / spread[r]);
    }
    const auto density = [&](std::size_t r, double phi) {
        const double x = (phi - centre[r]) / spread[r];
        return 1 / (spread[r] * (1 + x * x) * (s1[r] - s0[r]));
    };
    static constexpr std::array<double, 8> nodes{-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                                                 -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                                                 0.7966664774136267,  0.9602898564975363};
    static constexpr std::array<double, 8> weights{0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                                                   0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                                                   0.2223810344533745, 0.1012285362903763};
    const double lv = l.dot(v);
    double total = 0;
    for (std::size_t r = 0; r < rules; ++r) {
        if (!(s1[r] > s0[r])) continue;
        for (std::size_t k = 0; k < nodes.size(); ++k) {
            const double sk = 0.5 * (s0[r] + s1[r]) + 0.5 * (s1[r] - s0[r]) * nodes[k];
            const double tangent = std::tan(sk);
            const double phi = centre[r] + spread[r] * tangent;
            const double c = std::cos(phi), si = std::sin(phi);
            const double nv = c * v2.x() + si * v2.y(), nl = c * l2d.x() + si * l2d.y();
            const double cosAlpha = 2 * nl * nv - lv;
            if (!(nv > 0 && nl > 0 && cosAlpha > 0)) continue;
            // NᵀS₂⁻¹N = (sbb c² − 2 sab c s + saa s²) / det S₂.
            const double q = (sbb * c * c - 2 * sab * c * si + saa * si * si) / s2Det;
            const double rho = 1 / (std::sqrt(s2Det) * q * std::sqrt(q));
            double weight = 1;
            if (rules == 2) {
                const double own = density(r, phi), other = density(1 - r, phi);
                weight = own * own / (own * own + other * other);
            }
            const double jacobian = spread[r] * (1 + tangent * tangent) * 0.5 * (s1[r] - s0[r]) * weights[k];
            total += jacobian * weight * rho * nv / width * nl * power(cosAlpha);
        }
    }
    return total * (shininess + 2) / (2 * pi);
}

}  // namespace vtex::primitive::detail
