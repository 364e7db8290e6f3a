// The micro-primitive's maths at the axis-ratio floor and beyond the shapes of
// ellipsoid_test.cpp (issue 15, "stability"): discs and needles of axis ratio 1e-4 … 1e-2 (and
// their inverses, the same shapes scaled) against quadrature in double, with the relative
// errors each quantity keeps there.
#include "shapes.h"

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/quadrature.h>
#include <vtex/primitive/reflectance.h>
#include <vtex/primitive/reflectance_kernel.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <numbers>
#include <random>
#include <utility>

namespace vtex::primitive {
namespace {

using test::integrateOverSurface;
using test::parametricSurfaceArea;
using test::randomDirection;
using test::randomRotation;

constexpr double kPi = std::numbers::pi;

// Discs (one short axis), needles (two) and flat triaxial shapes at axis ratio `ratio`, under a
// random rotation; semi-axes scaled by `scale` (a ratio of 1e4 is the same shape as 1e-4).
std::vector<test::NamedShape> extremeShapes(std::mt19937& rng) {
    std::vector<test::NamedShape> shapes;
    for (const double ratio : {1e-4, 1e-3, 1e-2})
        for (const double scale : {1.0, 1e4}) {
            const std::string suffix = " ratio " + std::to_string(ratio) + " scale " + std::to_string(scale);
            shapes.push_back({"disc" + suffix, Ellipsoid::fromAxes(randomRotation(rng), scale * Vec3(ratio, 1, 1))});
            shapes.push_back({"needle" + suffix, Ellipsoid::fromAxes(randomRotation(rng), scale * Vec3(ratio, ratio, 1))});
            shapes.push_back({"flat" + suffix, Ellipsoid::fromAxes(randomRotation(rng), scale * Vec3(ratio, 0.3, 1))});
        }
    return shapes;
}

// ∫_{S²} g(N) dN in polar coordinates about `axis`, with composite Gauss panels in θ that
// shrink geometrically toward the pole and the equator and in φ toward `zero` (a direction ⟂
// axis) and its opposite: it resolves a peak of width `width` at the pole (a disc's normals),
// along the equator (a needle's) or at the equator's φ = 0 (a flat shape's), and knows nothing
// of the ellipsoid's formulas.
double integrateRefined(const std::function<double(const Vec3&)>& g, const Vec3& axis, const Vec3& zero, double width) {
    const QuadratureRule rule = gaussLegendre(12);
    const Vec3 other = axis.cross(zero);
    const auto breaks = [&](double span) {  // [0, span] refined toward both ends
        std::vector<double> b = {0};
        for (double e = 0.01 * width; e < 0.25 * span; e *= 2) b.push_back(e);
        const std::size_t n = b.size();
        for (std::size_t i = n; i-- > 1;) b.push_back(span - b[i]);
        b.push_back(span);
        std::sort(b.begin(), b.end());
        return b;
    };
    const std::vector<double> thetas = breaks(kPi / 2), phis = breaks(kPi);
    double total = 0;
    for (int hemisphere : {-1, 1})
        for (std::size_t p = 0; p + 1 < thetas.size(); ++p)
            for (std::size_t i = 0; i < rule.nodes.size(); ++i) {
                const double theta = thetas[p] + (thetas[p + 1] - thetas[p]) * 0.5 * (rule.nodes[i] + 1);
                const double wt = rule.weights[i] * 0.5 * (thetas[p + 1] - thetas[p]) * std::sin(theta);
                const double z = hemisphere * std::cos(theta), r = std::sin(theta);
                for (int half : {-1, 1})
                    for (std::size_t q = 0; q + 1 < phis.size(); ++q)
                        for (std::size_t j = 0; j < rule.nodes.size(); ++j) {
                            const double phi = half * (phis[q] + (phis[q + 1] - phis[q]) * 0.5 * (rule.nodes[j] + 1));
                            const double wp = rule.weights[j] * 0.5 * (phis[q + 1] - phis[q]);
                            total += wt * wp * g(z * axis + r * (std::cos(phi) * zero + std::sin(phi) * other));
                        }
            }
    return total;
}

// The polar axis of integrateRefined for `e`: a needle's long axis (its normals lie on the
// equator), otherwise its shortest axis (a disc's normals gather at the pole).
struct Frame {
    Vec3 axis, zero;
};
Frame refinedFrame(const Ellipsoid& e) {
    const bool needle = e.semiAxes()[1] / e.semiAxes()[2] < 0.05;
    return needle ? Frame{e.basis().col(2), e.basis().col(0)} : Frame{e.basis().col(0), e.basis().col(1)};
}

// ∫ f dN over the sphere of normals is the surface area (f is area per steradian of normal), on
// a grid refined about the shape's own axes, against the parametric surface area. Measured:
// within 9e-9 at every ratio and scale. Bound 1e-7.
TEST(ExtremeRatios, NormalDistributionIntegratesToTheSurfaceArea) {
    std::mt19937 rng(15);
    for (const auto& [name, e] : extremeShapes(rng)) {
        const Frame f = refinedFrame(e);
        const double ratio = e.semiAxes()[0] / e.semiAxes()[2];
        const double integral = integrateRefined([&](const Vec3& n) { return e.normalDistribution(n); }, f.axis, f.zero, ratio);
        EXPECT_NEAR(integral / parametricSurfaceArea(e.semiAxes()), 1.0, 1e-7) << name;
    }
}

// A(ω) = √(ωᵀSω) against ½∫|ω·N| f dN over the surface (Nanson's parameterisation, 400 rings),
// 20 random directions per shape. Measured: within 5e-6 everywhere. Bound 2e-5.
TEST(ExtremeRatios, ProjectedAreaEqualsHalfTheIntegralOfAbsCosineTimesF) {
    std::mt19937 rng(15);
    for (const auto& [name, e] : extremeShapes(rng))
        for (int k = 0; k < 20; ++k) {
            const Vec3 w = randomDirection(rng);
            const double half = 0.5 * integrateOverSurface(e, [&](const Vec3& n) { return std::abs(w.dot(n)); }, 400);
            EXPECT_NEAR(e.projectedArea(w) / half, 1.0, 2e-5) << name << " ω=" << w.transpose();
        }
}

// One factor of both reflectance methods against quadrature: for 20 random light and view
// directions per extreme shape (the back-lit and grazing ones included), `integrand(N, v, l)`
// integrated over the surface (`rings`) and divided by A(v), against `factor` of each method's
// result at `shininess`, as an error relative to `scale`; each within its bound. Returns the
// worst errors, fast and paper's method.
std::pair<double, double> expectFactorMatchesQuadrature(std::mt19937& rng, double shininess, int rings, double scale,
                                                       const std::function<double(const Vec3&, const Vec3&, const Vec3&)>& integrand,
                                                       double ReflectanceFactors::*factor, double fastBound,
                                                       double referenceBound) {
    double worstFast = 0, worstReference = 0;
    for (const auto& [name, e] : extremeShapes(rng))
        for (int k = 0; k < 20; ++k) {
            const Vec3 v = randomDirection(rng), l = randomDirection(rng);
            const double truth =
                integrateOverSurface(e, [&](const Vec3& n) { return integrand(n, v, l); }, rings) / e.projectedArea(v);
            const double fast = reflectanceFast(e.sggx(), l, v, shininess).*factor;
            const double reference = reflectanceReference(e.sggx(), l, v, shininess).*factor;
            EXPECT_TRUE(std::isfinite(fast) && std::isfinite(reference)) << name;  // NaN also fails the bounds
            EXPECT_LE(std::abs(fast - truth) / scale, fastBound) << name << " n=" << shininess << " v=" << v.transpose()
                                                                 << " l=" << l.transpose();
            EXPECT_LE(std::abs(reference - truth) / scale, referenceBound)
                << name << " n=" << shininess << " v=" << v.transpose() << " l=" << l.transpose();
            worstFast = std::max(worstFast, std::abs(fast - truth) / scale);
            worstReference = std::max(worstReference, std::abs(reference - truth) / scale);
        }
    return {worstFast, worstReference};
}

// The diffuse factor ∫(N·v)⁺(N·l)⁺/π f dN / A(v), relative to 1/π (a facet facing both, the
// largest value). Measured worst over 20 pairs per shape: the paper's method 0.008, the fast
// 16-point VNDF quadrature 0.049 (flat triaxial shapes at ratio 1e-2, whose visible normals
// spread over a band the 16 points cross coarsely; discs at 1e-4 are exact to 2e-5). Bounds
// 0.015 and 0.07.
TEST(ExtremeRatios, DiffuseReflectanceOfBothMethodsMatchesQuadrature) {
    std::mt19937 rng(15);
    const auto diffuse = [](const Vec3& n, const Vec3& v, const Vec3& l) {
        return std::max(0.0, n.dot(v)) * std::max(0.0, n.dot(l)) / kPi;
    };
    const auto [fast, reference] = expectFactorMatchesQuadrature(rng, 10, 400, 1 / kPi, diffuse, &ReflectanceFactors::diffuse, 0.07, 0.015);
    std::cout << "diffuse against quadrature, worst: fast " << fast << ", reference " << reference << "\n";
}

// The specular factor ∫(N·v)⁺(N·l)⁺ (n+2)/(2π) cosⁿα f dN / A(v) (α between l and v mirrored
// about N), for shininess 1, 10 and 100, relative to (n+2)/(2π) (a facet mirroring v onto l).
// Measured worst over 20 pairs per shape and shininess: the paper's method 0.0057, the fast path
// 0.060 (at shininess 100: its 16 visible normals miss part of a narrow lobe; issue 15's first
// part is its error on ordinary shapes). Bounds 0.012 and 0.08.
TEST(ExtremeRatios, SpecularReflectanceOfBothMethodsMatchesQuadrature) {
    std::mt19937 rng(16);
    for (const double n : {1.0, 10.0, 100.0}) {
        const double peak = (n + 2) / (2 * kPi);
        const auto specular = [&](const Vec3& normal, const Vec3& v, const Vec3& l) {
            const double nv = normal.dot(v), nl = normal.dot(l);
            if (nv <= 0 || nl <= 0) return 0.0;
            const Vec3 mirrored = 2 * nv * normal - v;
            return nv * nl * peak * std::pow(std::max(0.0, mirrored.dot(l)), n);
        };
        const auto [fast, reference] =
            expectFactorMatchesQuadrature(rng, n, 300, peak, specular, &ReflectanceFactors::specular, 0.08, 0.012);
        std::cout << "specular, shininess " << n << ", worst: fast " << fast << ", reference " << reference << "\n";
    }
}

}  // namespace
}  // namespace vtex::primitive
