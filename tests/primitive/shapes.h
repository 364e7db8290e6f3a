/// @file
/// @brief Shared shapes and integrators for the micro-primitive tests.
#pragma once

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/quadrature.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace vtex::primitive::test {

inline Mat3 randomRotation(std::mt19937& rng) {
    std::normal_distribution<double> gauss;
    Eigen::Quaterniond q(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
    return q.normalized().toRotationMatrix();
}

inline Vec3 randomDirection(std::mt19937& rng) {
    std::normal_distribution<double> gauss;
    Vec3 v;
    do v = Vec3(gauss(rng), gauss(rng), gauss(rng));
    while (v.norm() < 1e-6);
    return v.normalized();
}

struct NamedShape {
    std::string name;
    Ellipsoid ellipsoid;
};

/// The shapes the issue names: sphere, needle 1:100, disc 100:1, random triaxial, each also
/// under a random rotation.
inline std::vector<NamedShape> standardShapes() {
    std::mt19937 rng(1994);
    std::uniform_real_distribution<double> length(0.2, 3.0);
    std::vector<NamedShape> shapes;
    const std::vector<std::pair<std::string, Vec3>> axes = {
        {"sphere", {1.5, 1.5, 1.5}},
        {"needle_1_100", {100, 1, 1}},
        {"disc_100_1", {1, 100, 100}},
        {"triaxial_a", {length(rng), length(rng), length(rng)}},
        {"triaxial_b", {0.3, 1.0, 2.5}},
    };
    for (const auto& [name, a] : axes) {
        shapes.push_back({name, Ellipsoid::fromAxes(Mat3::Identity(), a)});
        shapes.push_back({name + "_rotated", Ellipsoid::fromAxes(randomRotation(rng), a)});
    }
    return shapes;
}

/// ∫_{S²} g(ω) dω with a Gauss–Legendre rule in cos θ and the midpoint rule in φ, about the
/// fixed z axis (independent of any ellipsoid's frame).
inline double integrateSphere(const std::function<double(const Vec3&)>& g, int rings) {
    const QuadratureRule rule = gaussLegendre(rings);
    const int sectors = 2 * rings;
    double sum = 0;
    for (int i = 0; i < rings; ++i) {
        const double z = rule.nodes[i];
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        double ring = 0;
        for (int j = 0; j < sectors; ++j) {
            const double phi = 2 * std::numbers::pi * (j + 0.5) / sectors;
            ring += g(Vec3(r * std::cos(phi), r * std::sin(phi), z));
        }
        sum += rule.weights[i] * ring;
    }
    return sum * 2 * std::numbers::pi / sectors;
}

/// ∫ g(N) f(N) dN over the Gauss map of the ellipsoid, parameterised by the unit sphere u of
/// its affine pre-image x = L u: f(N) dN = det(L) |L⁻ᵀ u| du (Nanson's formula).
inline double integrateOverSurface(const Ellipsoid& e, const std::function<double(const Vec3&)>& g,
                                   int rings) {
    const Vec3& a = e.semiAxes();
    return integrateSphere(
        [&](const Vec3& u) {
            const Vec3 scaled = a.cwiseInverse().cwiseProduct(u);
            const double norm = scaled.norm();
            const Vec3 normal = e.basis() * (scaled / norm);
            return a.prod() * norm * g(normal);
        },
        rings);
}

/// Surface area of the ellipsoid with semi-axes a, by the parametric surface integral
/// ∫∫ |r_x × r_φ| dx dφ with x = cos θ, on a composite Gauss rule whose panels shrink
/// geometrically toward the rim x = 0, where the integrand of a thin disc turns in a width
/// of the order of its thickness.
inline double parametricSurfaceArea(Vec3 a) {
    std::sort(a.data(), a.data() + 3);  // a[2] is the longest; the pole is the shortest axis
    const double c = a[0], b = a[1], l = a[2];
    const QuadratureRule rule = gaussLegendre(24);
    const auto integrand = [&](double x, double phi) {
        const double s2 = 1 - x * x;
        const double cp = std::cos(phi), sp = std::sin(phi);
        return std::sqrt(b * b * c * c * s2 * cp * cp + l * l * c * c * s2 * sp * sp +
                         l * l * b * b * x * x);
    };
    std::vector<double> breaks = {0};
    for (double edge = 1e-6 * c / l; edge < 1; edge *= 2) breaks.push_back(edge);
    breaks.push_back(1);
    double total = 0;
    for (std::size_t p = 0; p + 1 < breaks.size(); ++p) {
        const double x0 = breaks[p], x1 = breaks[p + 1];
        for (std::size_t i = 0; i < rule.nodes.size(); ++i) {
            const double x = x0 + (x1 - x0) * 0.5 * (rule.nodes[i] + 1);
            for (std::size_t j = 0; j < rule.nodes.size(); ++j) {
                // φ over [0, π/2] in 4 panels (the integrand is smooth in φ).
                for (int k = 0; k < 4; ++k) {
                    const double phi = std::numbers::pi / 8 * (k + 0.5 * (rule.nodes[j] + 1));
                    total += rule.weights[i] * rule.weights[j] * 0.5 * (x1 - x0) *
                             (std::numbers::pi / 16) * integrand(x, phi);
                }
            }
        }
    }
    return 8 * total;  // one octant
}

// Normals of the surface of `e` with their areas: the Gauss–Legendre grid of the parametric
// sphere u pushed through x = L u.
inline void sampleSurfaceNormals(const Ellipsoid& e, int rings, std::vector<Vec3>& normals,
                          std::vector<double>& areas) {
    const Vec3& a = e.semiAxes();
    const QuadratureRule rule = gaussLegendre(rings);
    for (int i = 0; i < rings; ++i) {
        const double z = rule.nodes[i], r = std::sqrt(1 - z * z);
        for (int j = 0; j < 2 * rings; ++j) {
            const double phi = std::numbers::pi * (j + 0.5) / rings;
            const Vec3 scaled = a.cwiseInverse().cwiseProduct(Vec3(r * std::cos(phi), r * std::sin(phi), z));
            normals.push_back(e.basis() * scaled.normalized());
            areas.push_back(rule.weights[i] * a.prod() * scaled.norm());
        }
    }
}

}  // namespace vtex::primitive::test
