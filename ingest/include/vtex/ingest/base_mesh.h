/// @file
/// @brief The base quad mesh the renderer covers with texels (DESIGN.md, "Base mesh and mapping").
///
/// Each face is a bilinear patch P(u,v) = bilerp(P00, P10, P11, P01) given by four corners in
/// counter-clockwise order; a triangle is a collapsed quad whose last corner repeats its third
/// (quad[3] == quad[2]). Two triangles that were one quad of a triangulated export (consecutive
/// as a fan, or sharing their longest edge; within 40° of planar and convex) are that quad again.
/// Polygons with more than four corners are split into quads and a triangle by a fan from their
/// first corner. World (scene) units.
#pragma once

#include <vtex/ingest/ingest.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace vtex::ingest {

struct QuadMesh {
    std::vector<Eigen::Vector3f> positions;
    std::vector<Eigen::Vector3f> normals;  ///< unit, one per position (area-weighted or the file's)
    std::vector<Eigen::Vector2f> uvs;      ///< empty, or one per position
    std::vector<std::array<std::uint32_t, 4>> quads;

    /// True when the face is a triangle stored as a collapsed quad.
    bool isTriangle(std::size_t face) const { return quads[face][3] == quads[face][2]; }
};

/// Loads a base mesh from .obj/.off/.ply/.stl (OpenMesh PolyMesh) or .gltf/.glb (whose
/// triangles become collapsed quads), keeping quads as quads. The same limits and checks as
/// loadMesh() apply (untrusted input; one-line InputError naming the file and the problem).
QuadMesh loadBaseMesh(const std::filesystem::path& file, const IngestOptions& options = {});

}  // namespace vtex::ingest
