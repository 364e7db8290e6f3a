#pragma once
// The ray footprint of the renderer, shared with the bound on the levels a render can use
// (level_bound.cpp): both must compute it the same way.

#include <vtex/ingest/base_mesh.h>
#include <vtex/render/geometry.h>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vtex::render::detail {

/// The pixel cone's width per unit distance (at the image centre), split among the `strata`
/// per axis of a pixel's samples.
inline double coneSpread(double fovYDegrees, int height, int strata) {
    return 2 * std::tan(fovYDegrees * std::numbers::pi / 360) / double(height) / double(strata);
}

/// World length per unit of tiled reference space around cell coordinates r: the cube root of
/// the Jacobian of the map from tiled reference space to the world (a geometric mean over the
/// three directions).
inline double localScale(const TrilinearCell& cell, const Vec3& r, double repeatU, double repeatV) {
    const double det = std::abs(cell.jacobian(r).determinant()) / (repeatU * repeatV);
    const double scale = std::cbrt(det);
    return scale > 0 && std::isfinite(scale) ? scale : cell.size() / std::max(repeatU, repeatV);
}

/// The corners of base face `face` in the order of the bilinear patch (P00, P10, P01, P11:
/// QuadMesh stores them counter-clockwise, P00, P10, P11, P01) and their normals. False when a
/// corner index is out of range or a value is not finite.
inline bool baseFaceCorners(const ingest::QuadMesh& mesh, std::size_t face, std::array<Vec3, 4>& p,
                            std::array<Vec3, 4>& n) {
    const auto& q = mesh.quads[face];
    const std::uint32_t order[4] = {q[0], q[1], q[3], q[2]};
    for (std::size_t c = 0; c < 4; ++c) {
        if (order[c] >= mesh.positions.size()) return false;
        p[c] = mesh.positions[order[c]].cast<double>();
        n[c] = order[c] < mesh.normals.size() ? mesh.normals[order[c]].cast<double>() : Vec3(0, 0, 1);
        if (!p[c].allFinite() || !n[c].allFinite()) return false;
    }
    return true;
}

}  // namespace vtex::render::detail
