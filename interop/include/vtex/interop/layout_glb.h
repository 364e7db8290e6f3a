/// @file
/// @brief A scene's base meshes and the shells of their texel cells as one binary glTF, for
/// laying out exported texels in Blender (docs/export.md, "Layout").
///
/// Per surface of the scene, in world units: a node `surface<i> <mesh file>` holding the base
/// mesh (each quad as two triangles, a collapsed quad as one, the surface's diffuse colour), and
/// for a textured surface a node `surface<i> cells <texel>` holding every face's trilinear cell
/// X(u,v,w) = bilerp(Pij + (w − w0)·H·Nij) (docs/render.md, "Geometry") as a closed hexahedron of
/// 12 triangles (its bilinear faces split along a diagonal) in a translucent material, plus its
/// 12 edges as lines. The cell node's extras hold what the scene says of its texel: name, volume,
/// tau, height, placement, repeat.
#pragma once

#include <vtex/render/scene.h>

#include <cstddef>
#include <filesystem>
#include <string>

namespace vtex::interop {

struct LayoutSummary {
    std::size_t surfaces = 0;
    std::size_t faces = 0;  ///< base faces, all surfaces
    std::size_t cells = 0;  ///< texel cells (faces of textured surfaces)
};

/// The layout of `scene` as .glb bytes; reads each surface's base mesh (render::loadSurfaceMesh;
/// the texels' volumes are not read). Throws vtex::InputError for a mesh that cannot be read or a
/// face with an invalid corner.
std::string encodeLayoutGlb(const render::Scene& scene, LayoutSummary* summary = nullptr);

/// encodeLayoutGlb written to `file` atomically. Throws vtex::InputError / vtex::IoError.
LayoutSummary writeLayoutGlb(const render::Scene& scene, const std::filesystem::path& file);

}  // namespace vtex::interop
