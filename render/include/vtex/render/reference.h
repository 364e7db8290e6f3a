/// @file
/// @brief The explicit-geometry reference renderer: `vtex reference`.
///
/// DESIGN.md, "The reference renderer". The scene of `vtex render`, with each texel's source
/// mesh in place of its volume: Phong-shaded two-sided triangles with the texel's material
/// (diffuse times the mesh's base colour), shadow rays against the same geometry, jittered
/// stratified samples per pixel, Embree throughout. It is the ground truth a texel render's
/// error is measured against, and the baseline its speed is compared with.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

namespace vtex::render {

enum class ReferenceMode {
    /// A ray that enters a cell is carried into reference space exactly as the texel renderer
    /// carries it (the straight segment between the mapped entry and exit points) and traced
    /// against one BVH of the source mesh, shared by every cell: isolates what voxelisation and
    /// filtering lose.
    Embedded,
    /// The source mesh is deformed by each cell's trilinear map (triangles clipped to the cell
    /// and subdivided until the map is linear on them to `tolerance`) into one world-space BVH:
    /// measures what the straight-segment assumption loses as well.
    Deformed
};
/// "embedded", "deformed": `vtex reference --mode`, a pipeline render's `mode`.
inline constexpr EnumNames<ReferenceMode, 2> kReferenceModeNames{{{{ReferenceMode::Embedded, "embedded"}, {ReferenceMode::Deformed, "deformed"}}}};

/// ImageOptions with 16 jittered samples per pixel by default; aovs fill Image::depth only
/// (Image::level stays −1).
struct ReferenceOptions : ImageOptions {
    ReferenceOptions() { spp = 16; }
    ReferenceMode mode = ReferenceMode::Embedded;
    /// Deformed: the largest distance between a subdivided triangle and the true deformed
    /// surface, as a fraction of the cell's size.
    double tolerance = 1e-3;
};

/// An upper estimate of renderReference's peak memory (bytes) before anything is loaded: the
/// image and the scene's files as estimateRenderMemory counts them, without the shadow
/// lattices. The deformed mode's triangles are estimated and checked once the sources are
/// loaded.
std::uint64_t estimateReferenceMemory(const Scene& scene, const ReferenceOptions& options);

/// Loads the scene's base meshes and the source meshes of its texels (`source =`; the `.vto`
/// supplies where the sampler placed the mesh in the unit cube), and renders. Throws
/// vtex::InputError for a texel without a source, bad content, or (deformed) a scene over the
/// memory limit; vtex::IoError.
RenderResult renderReference(const Scene& scene, const ReferenceOptions& options, Progress& progress);

}  // namespace vtex::render
