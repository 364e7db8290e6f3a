#pragma once
// The ray footprint of the renderer, shared with the bound on the levels a render can use
// (level_bound.cpp): both must compute it the same way.

#include <vtex/ingest/base_mesh.h>
#include <vtex/render/cell_map.h>
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
inline double localScale(const TrilinearCell& cell, const Vec3& r, const CellMap& map) {
    const double det = std::abs(cell.jacobian(r).determinant()) / map.areaScale();
    const double scale = std::cbrt(det);
    return scale > 0 && std::isfinite(scale) ? scale : cell.size() / map.maxExtent();
}

/// The corners of base face `face` in the order of the bilinear patch (ingest::patchCorners).
inline bool baseFaceCorners(const ingest::QuadMesh& mesh, std::size_t face, std::array<Vec3, 4>& p,
                            std::array<Vec3, 4>& n) {
    return ingest::patchCorners(mesh, face, p, n);
}

}  // namespace vtex::render::detail
