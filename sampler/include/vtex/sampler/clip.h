/// @file
/// @brief Exact clipping of triangles to the voxels of a grid: each piece's area, once.
///
/// Coordinates are in voxel units (the reference cube scaled by N, voxel (i,j,k) is the box
/// [i,i+1)×[j,j+1)×[k,k+1)). Boxes are half-open, so every point of space belongs to exactly one
/// voxel and the pieces of a triangle partition it: their areas sum to the triangle's, and a
/// triangle lying exactly on a voxel face is counted once (in the voxel on the + side of the
/// face). The far faces of the volume (x = N, …) are closed instead when the axis is not
/// periodic, so nothing on the boundary is lost. Cyclic axes (x and y with `cyclic`) wrap voxel
/// indices modulo N; z never wraps; pieces outside a non-cyclic volume are dropped.
///
/// Method: the triangle is peeled slab by slab along x, each slab piece along y, each of those
/// along z, by splitting convex polygons with axis-aligned planes (Sutherland–Hodgman, one plane
/// at a time). Work is O(pieces); intersection points land exactly on the plane.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross, in ClipPolygon::area

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace vtex::sampler {

/// A convex polygon, voxel units. A triangle cut by the 6 faces of a box has at most 9 vertices.
struct ClipPolygon {
    static constexpr int kMaxVertices = 16;
    int count = 0;
    std::array<Eigen::Vector3d, kMaxVertices> v;

    void push(const Eigen::Vector3d& p) {
        if (count < kMaxVertices) v[std::size_t(count++)] = p;
    }
    /// Area (voxel units²).
    double area() const {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (int i = 1; i + 1 < count; ++i) sum += (v[std::size_t(i)] - v[0]).cross(v[std::size_t(i + 1)] - v[0]);
        return 0.5 * sum.norm();
    }
    double minCoord(int axis) const {
        double m = v[0][axis];
        for (int i = 1; i < count; ++i) m = std::min(m, v[std::size_t(i)][axis]);
        return m;
    }
    double maxCoord(int axis) const {
        double m = v[0][axis];
        for (int i = 1; i < count; ++i) m = std::max(m, v[std::size_t(i)][axis]);
        return m;
    }
};

namespace detail {

/// Splits `p` by the plane coord[axis] = c into the parts ≤ c and ≥ c (points on the plane
/// belong to both; intersection points are put exactly on the plane).
inline void splitPolygon(const ClipPolygon& p, int axis, double c, ClipPolygon& below, ClipPolygon& above) {
    below.count = above.count = 0;
    for (int i = 0; i < p.count; ++i) {
        const Eigen::Vector3d& a = p.v[std::size_t(i)];
        const Eigen::Vector3d& b = p.v[std::size_t((i + 1) % p.count)];
        const double da = a[axis] - c, db = b[axis] - c;
        if (da <= 0) below.push(a);
        if (da >= 0) above.push(a);
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
            Eigen::Vector3d x = a + (b - a) * (da / (da - db));
            x[axis] = c;
            below.push(x);
            above.push(x);
        }
    }
}

/// Keeps the part of `p` with coord[axis] within [lo, hi].
inline void clampPolygon(ClipPolygon& p, int axis, double lo, double hi) {
    ClipPolygon below, above;
    if (p.count >= 3 && p.minCoord(axis) < lo) {
        splitPolygon(p, axis, lo, below, above);
        p = above;
    }
    if (p.count >= 3 && p.maxCoord(axis) > hi) {
        splitPolygon(p, axis, hi, below, above);
        p = below;
    }
}

/// Peels `p` into slabs [i, i+1) along `axis` and calls emit(i, piece) for each piece with at
/// least 3 vertices. A piece lying in the plane x = i goes to slab i.
template <class Emit>
void peelSlabs(const ClipPolygon& p, int axis, Emit&& emit) {
    if (p.count < 3) return;
    ClipPolygon rest = p, below, above;
    double lo = rest.minCoord(axis);
    for (double i = std::floor(lo);; i += 1.0) {
        const double c = i + 1.0;
        if (rest.maxCoord(axis) < c) {
            emit(std::int64_t(i), rest);
            return;
        }
        if (rest.minCoord(axis) >= c) continue;  // nothing in this slab
        splitPolygon(rest, axis, c, below, above);
        if (below.count >= 3) emit(std::int64_t(i), below);
        rest = above;
        if (rest.count < 3) return;
    }
}

}  // namespace detail

/// Calls emit(ix, iy, iz, piece) for every piece of triangle (a, b, c) (voxel units) inside a
/// voxel of the N³ grid; ix, iy, iz ∈ [0, N). Pieces may have zero area (a triangle touching a
/// voxel along an edge); callers skip them.
template <class Emit>
void clipTriangleToGrid(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                        std::uint32_t n, bool cyclic, Emit&& emit) {
    ClipPolygon tri;
    tri.push(a);
    tri.push(b);
    tri.push(c);
    const double N = double(n);
    // Non-periodic axes: keep [0, N] only, so a far-away triangle costs nothing.
    for (int axis = 0; axis < 3; ++axis)
        if (axis == 2 || !cyclic) detail::clampPolygon(tri, axis, 0.0, N);
    if (tri.count < 3) return;
    // A voxel index along one axis; -1 when outside a non-periodic axis. A piece lying in the
    // far face (coordinate N) of a closed axis belongs to the last voxel.
    auto index = [&](std::int64_t i, const ClipPolygon& piece, int axis) -> std::int64_t {
        const bool periodic = cyclic && axis < 2;
        if (periodic) return ((i % std::int64_t(n)) + std::int64_t(n)) % std::int64_t(n);
        if (i == std::int64_t(n) && piece.minCoord(axis) == N) return std::int64_t(n) - 1;
        return (i >= 0 && i < std::int64_t(n)) ? i : -1;
    };
    detail::peelSlabs(tri, 0, [&](std::int64_t i, const ClipPolygon& px) {
        const std::int64_t ix = index(i, px, 0);
        if (ix < 0) return;
        detail::peelSlabs(px, 1, [&](std::int64_t j, const ClipPolygon& py) {
            const std::int64_t iy = index(j, py, 1);
            if (iy < 0) return;
            detail::peelSlabs(py, 2, [&](std::int64_t k, const ClipPolygon& pz) {
                const std::int64_t iz = index(k, pz, 2);
                if (iz < 0) return;
                emit(std::uint32_t(ix), std::uint32_t(iy), std::uint32_t(iz), pz);
            });
        });
    });
}

}  // namespace vtex::sampler
