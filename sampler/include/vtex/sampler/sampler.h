/// @file
/// @brief Sampling a triangle mesh into the finest level of a texel: density, fitted ellipsoid
/// and albedo per voxel (DESIGN.md, "Sampling (mesh → finest level)").
///
/// F. Neyret 1994 §3 (the reference volume and its "presence"), §3.3 (the micro-primitive
/// summarising the local normals). Per voxel, from the exact pieces of every triangle inside it
/// (vtex/sampler/clip.h):
///  * density ρ = (area inside) / (2 · voxel volume), reference units (1/length);
///  * the ellipsoid Ellipsoid::fitNormals of the pieces' normals weighted by their areas (the
///    normal's sign is ignored: source triangles are two-sided);
///  * the albedo, the area-weighted linear-RGB base colour (factor × texture, the texture decoded
///    from sRGB and sampled where the pieces are).
/// Inside a closed mesh the interior is solid (ρ_solid, an isotropic primitive), stored as
/// octree-aligned blocks. Work is O(triangles + pieces), memory O(occupied voxels), parallel.
#pragma once

#include <vtex/core/enum_names.h>

#include <vtex/core/progress.h>
#include <vtex/ingest/mesh.h>
#include <vtex/octree/volume.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace vtex::sampler {

enum class SolidMode {
    Auto,  ///< fill the interior when the mesh is closed (ingest's `closed` flag)
    On,    ///< fill it; the mesh must be closed
    Off    ///< surfaces only
};
/// "auto", "on", "off": `vtex sample --solid`, a pipeline texel's `solid`.
inline constexpr EnumNames<SolidMode, 3> kSolidModeNames{{{{SolidMode::Auto, "auto"}, {SolidMode::On, "on"}, {SolidMode::Off, "off"}}}};

/// How source (world) coordinates map onto the unit reference cube.
enum class BoundsMode {
    Auto,  ///< Unit if the mesh lies inside [0,1]³ (procedural patterns do), else Fit
    Unit,  ///< identity: the source is already in reference units
    Fit    ///< uniform scale so that the bounding box's longest side is 1, its minimum corner at 0
};
/// "auto", "unit", "fit": `vtex sample --bounds`.
inline constexpr EnumNames<BoundsMode, 3> kBoundsModeNames{{{{BoundsMode::Auto, "auto"}, {BoundsMode::Unit, "unit"}, {BoundsMode::Fit, "fit"}}}};

struct SampleOptions {
    std::uint32_t resolution = 128;  ///< N, a power of two, 1 … 2^20
    bool cyclic = false;             ///< periodic x and y (tileable patterns)
    SolidMode solid = SolidMode::Auto;
    /// ρ_solid in 1/length; 0 picks 16·N (optical depth 16 across one finest voxel).
    double solidDensity = 0;
    BoundsMode bounds = BoundsMode::Auto;
    /// Sample only the voxels inside this box (finest voxel indices), for a partial recompute
    /// (octree::OctreeBuilder::updateRegion); the values equal a full sampling's bit for bit.
    std::optional<octree::VoxelBox> region;
    /// Refuse (vtex::MemoryLimitError, before any work) when estimateSampleMemory() exceeds
    /// this; 0 = no limit.
    std::uint64_t maxMemoryBytes = 0;
    /// The mesh's file, named in a vtex::MemoryLimitError.
    std::filesystem::path source;
    /// Surface voxels on which the fit error is measured, about (hash-selected with a threshold
    /// from the mesh's area, so that updateRegion selects the same ones); 0 = all.
    std::uint64_t fitErrorSamples = 4096;
};

/// An upper estimate of the peak memory sampleMesh() needs (bytes), from the triangles' areas
/// and perimeters in voxel units: O(triangles), no allocation.
std::uint64_t estimateSampleMemory(const ingest::TriangleMesh& mesh, const SampleOptions& options);

/// The source → reference mapping that `options.bounds` gives for `mesh`.
void referenceMapping(const ingest::TriangleMesh& mesh, BoundsMode bounds, double& scale,
                      std::array<double, 3>& offset);

/// Samples `mesh`. Throws std::invalid_argument for a bad resolution or a region outside the
/// volume, vtex::MemoryLimitError (see maxMemoryBytes), vtex::InputError when `--solid on` is
/// asked of an open mesh.
octree::SparseVolume sampleMesh(const ingest::TriangleMesh& mesh, const SampleOptions& options,
                                Progress& progress);

/// The partial recompute: `old` (read from `oldFile`) with every voxel inside `options.region`
/// (finest voxel indices, min inclusive, max exclusive) sampled again from `mesh`, the others
/// kept, and the fit error measured again on the voxels a full sampling measures it on. When
/// `old` was sampled with these options from a mesh that differs from `mesh` only by triangles
/// whose pieces lie inside the region, the result equals sampleMesh(mesh, options without the
/// region) bit for bit. The work is the region's sampling plus the fit error's few thousand
/// voxels. Throws vtex::InputError naming `oldFile` when `old` was sampled at another
/// resolution, cyclic or not, with another mapping to the unit cube, or holds a solid interior
/// (which the region alone cannot classify); std::invalid_argument as sampleMesh does.
octree::SparseVolume updateRegion(const ingest::TriangleMesh& mesh, const octree::SparseVolume& old,
                                  const SampleOptions& options, const std::filesystem::path& oldFile, Progress& progress);

/// The region updateRegion needs for an edit from `before` to `after` (sampled with `options`,
/// its region ignored): every voxel a triangle that differs touches, in either mesh. Triangles
/// are compared by what the sampling reads of them (corners, texture coordinates, material) index
/// by index when the counts agree, else outside their common prefix and suffix. An empty box when
/// nothing differs; std::nullopt when no region will do: the mapping to the unit cube, a material
/// or a texture changed (or the texture coordinates appeared or went).
std::optional<octree::VoxelBox> changedRegion(const ingest::TriangleMesh& before, const ingest::TriangleMesh& after,
                                              const SampleOptions& options);

}  // namespace vtex::sampler
