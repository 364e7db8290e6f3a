/// @file
/// @brief The base quad mesh the renderer covers with texels (DESIGN.md, "Base mesh and mapping").
///
/// Each face is a bilinear patch P(u,v) = bilerp(P00, P10, P11, P01) given by four corners in
/// counter-clockwise order; a triangle is a collapsed quad whose last corner repeats its third
/// (quad[3] == quad[2]). Two triangles that were one quad of a triangulated export (consecutive
/// as a fan, or sharing their longest edge; within 40° of planar and convex; of the same material
/// and group) are that quad again.
/// Polygons with more than four corners are split into quads and a triangle by a fan from their
/// first corner. World (scene) units.
#pragma once

#include <vtex/ingest/ingest.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vtex::ingest {

struct QuadMesh {
    std::vector<Eigen::Vector3f> positions;
    std::vector<Eigen::Vector3f> normals;  ///< unit, one per position (area-weighted or the file's)
    std::vector<Eigen::Vector2f> uvs;      ///< empty, or one per position
    std::vector<std::array<std::uint32_t, 4>> quads;
    /// The names faces go by, which a scene's `texels` gives them their texel by (docs/render.md,
    /// "A texel per face"): per face (or empty, when the file names none) the index into `names`
    /// of its material (OBJ `usemtl`, glTF material name) and of its group (OBJ `g`, glTF mesh
    /// name), kNoName for none.
    static constexpr std::uint32_t kNoName = 0xffffffffu;
    std::vector<std::string> names;
    std::vector<std::array<std::uint32_t, 2>> faceNames;

    /// True when the face is a triangle stored as a collapsed quad.
    bool isTriangle(std::size_t face) const { return quads[face][3] == quads[face][2]; }
};

/// The corners of face `face` in the order of its bilinear patch, P00, P10, P01, P11 (a quad is
/// stored counter-clockwise, P00 P10 P11 P01), and their normals (+z where the mesh has none):
/// what the renderers and the layout export place a cell on. False when a corner index is out of
/// range or a value is not finite.
/// The vertex indices of those corners, P00, P10, P01, P11.
inline std::array<std::uint32_t, 4> patchOrder(const QuadMesh& mesh, std::size_t face) {
    const auto& q = mesh.quads[face];
    return {q[0], q[1], q[3], q[2]};
}

inline bool patchCorners(const QuadMesh& mesh, std::size_t face, std::array<Eigen::Vector3d, 4>& p,
                         std::array<Eigen::Vector3d, 4>& n) {
    const std::array<std::uint32_t, 4> order = patchOrder(mesh, face);
    for (std::size_t c = 0; c < 4; ++c) {
        if (order[c] >= mesh.positions.size()) return false;
        p[c] = mesh.positions[order[c]].cast<double>();
        n[c] = order[c] < mesh.normals.size() ? mesh.normals[order[c]].cast<double>() : Eigen::Vector3d(0, 0, 1);
        if (!p[c].allFinite() || !n[c].allFinite()) return false;
    }
    return true;
}

/// Loads a base mesh from .obj/.off/.ply/.stl (OpenMesh PolyMesh) or .gltf/.glb (whose
/// triangles become collapsed quads), keeping quads as quads. The same limits and checks as
/// loadMesh() apply (untrusted input; one-line InputError naming the file and the problem).
QuadMesh loadBaseMesh(const std::filesystem::path& file, const IngestOptions& options = {});

}  // namespace vtex::ingest
