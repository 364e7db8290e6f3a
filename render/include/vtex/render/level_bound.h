/// @file
/// @brief The finest octree level a render can use on each texel (DESIGN.md, "Leave out what a
/// scene does not need").
///
/// The renderer picks a level from the footprint of the pixel cone in tiled reference units,
/// −log2(coneSpread · t / scale) − lodBias, with t the distance along the ray and scale the local
/// world size of a reference unit (render/src/footprint.h). A ray cannot meet a cell closer than
/// the distance from the camera to the cell's bounding box, and the scale is bounded by its
/// largest value on a 3×3×3 lattice of the cell (exact for parallelepipeds, an estimate for
/// strongly twisted cells). Levels finer than the bound are never used: a texel need not be
/// sampled, built or loaded beyond it.
#pragma once

#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

#include <vector>

namespace vtex::render {

struct TexelLevelNeed {
    bool used = false;  ///< some surface of the scene references the texel
    /// The finest level a ray can use (the fine level of the blend), before any cap by the
    /// octree's depth; meaningful when `used`. `unbounded` when the camera is inside or on a cell.
    int finestLevel = 0;
    bool unbounded = false;
    double nearestDistance = 0;  ///< world distance from the camera to the nearest cell
};

/// One entry per scene texel. Loads the base meshes the scene names (not the octrees).
/// Throws vtex::InputError as renderScene would for a bad mesh.
std::vector<TexelLevelNeed> finestUsefulLevels(const Scene& scene, const RenderOptions& options);

}  // namespace vtex::render
