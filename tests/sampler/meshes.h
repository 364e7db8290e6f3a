/// @file
/// @brief Small meshes for the sampler tests, built in memory.
#pragma once

#include <vtex/ingest/mesh.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <random>

namespace vtex::sampler::test {

using Vec3 = Eigen::Vector3d;

inline ingest::TriangleMesh emptyMesh() {
    ingest::TriangleMesh mesh;
    mesh.materials.emplace_back();
    return mesh;
}

inline void addTriangle(ingest::TriangleMesh& mesh, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 n = (b - a).cross(c - a).normalized();
    const auto first = std::uint32_t(mesh.positions.size());
    for (const Vec3* p : {&a, &b, &c}) {
        mesh.positions.push_back(p->cast<float>());
        mesh.normals.push_back(n.cast<float>());
    }
    mesh.triangles.push_back({first, first + 1, first + 2});
}

inline double meshArea(const ingest::TriangleMesh& mesh) {
    double area = 0;
    for (const auto& t : mesh.triangles) {
        const Vec3 a = mesh.positions[t[0]].cast<double>(), b = mesh.positions[t[1]].cast<double>(),
                   c = mesh.positions[t[2]].cast<double>();
        area += 0.5 * (b - a).cross(c - a).norm();
    }
    return area;
}

/// An axis-aligned box [lo, hi] with 8 shared vertices, 12 outward triangles, closed.
inline ingest::TriangleMesh boxMesh(const Vec3& lo, const Vec3& hi) {
    ingest::TriangleMesh mesh = emptyMesh();
    for (int i = 0; i < 8; ++i) {
        mesh.positions.emplace_back(float(i & 1 ? hi.x() : lo.x()), float(i & 2 ? hi.y() : lo.y()),
                                    float(i & 4 ? hi.z() : lo.z()));
        mesh.normals.emplace_back(Eigen::Vector3f(float(i & 1 ? 1 : -1), float(i & 2 ? 1 : -1), float(i & 4 ? 1 : -1)).normalized());
    }
    const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {1, 3, 7, 5}, {0, 4, 6, 2}};
    for (const auto& q : quads) {
        mesh.triangles.push_back({q[0], q[1], q[2]});
        mesh.triangles.push_back({q[0], q[2], q[3]});
    }
    mesh.closed = true;
    return mesh;
}

/// The side of a cylinder (open ends) of `radius` around the axis through `base` along unit
/// `axis`, `length` long, `sides` facets.
inline ingest::TriangleMesh cylinderSide(const Vec3& base, const Vec3& axis, double radius, double length, int sides) {
    ingest::TriangleMesh mesh = emptyMesh();
    const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
    for (int s = 0; s < sides; ++s) {
        const double a0 = 2 * std::numbers::pi * s / sides, a1 = 2 * std::numbers::pi * (s + 1) / sides;
        const Vec3 p0 = base + radius * (std::cos(a0) * u + std::sin(a0) * v);
        const Vec3 p1 = base + radius * (std::cos(a1) * u + std::sin(a1) * v);
        addTriangle(mesh, p0, p1, p1 + length * axis);
        addTriangle(mesh, p0, p1 + length * axis, p0 + length * axis);
    }
    return mesh;
}

}  // namespace vtex::sampler::test
