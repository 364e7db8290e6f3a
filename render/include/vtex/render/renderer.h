/// @file
/// @brief The texel renderer: `vtex render`.
///
/// DESIGN.md, "Rendering". Camera rays are traced through Embree against the base faces as
/// bilinear patches and the texel shells as trilinear cells; inside a cell the octree level is
/// picked from the ray's footprint (GigaVoxels' cone rule) and the sparse octree is marched
/// front to back with anisotropic extinction τρÂ(ω); voxels are shaded with the ellipsoid's
/// Phong reflectance, lit through shadow rays. Tiles run in parallel with TBB; the image does
/// not depend on the thread count.
#pragma once

#include <vtex/core/enum_names.h>
#include <vtex/core/progress.h>
#include <vtex/render/image.h>
#include <vtex/render/scene.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace vtex {
class AtomicOutputFile;
}

namespace vtex::render {

/// How a voxel's micro-primitive reflects light (primitive/reflectance.h, reflectance_kernel.h).
enum class ShadingMode {
    /// The paper's numerical integration over the apparent ellipse
    /// (phongReflectanceApparentEllipse): slow, the reference.
    Reference,
    /// A fixed stratified quadrature over SGGX visible normals (closed-form VNDF sampling,
    /// Heitz et al. 2015): R(l,v) = E_{N∼D_v}[(N·l)⁺ ρ(N,l,v)] with 16 deterministic samples.
    Fast
};
/// "fast", "reference": `vtex render --shading`, a pipeline render's `shading`.
inline constexpr EnumNames<ShadingMode, 2> kShadingModeNames{{{{ShadingMode::Fast, "fast"}, {ShadingMode::Reference, "reference"}}}};

/// What both renderers take: the image and how its pixels are sampled.
struct ImageOptions {
    int width = 0;        ///< 0: the scene's camera.width
    int height = 0;       ///< 0: the scene's camera.height
    int spp = 1;          ///< samples per pixel (a √spp × √spp grid, rounded up)
    int threads = 0;      ///< the whole render's, load included; 0: all hardware threads
    bool aovs = false;    ///< fill Image::depth (and, texel renders, Image::level)
    /// Render only the rows [rowBegin, rowEnd) of the full image (row 0 at the top): the camera
    /// rays and every pixel's samples are those of the full image, and the Image holds just these
    /// rows (width × (rowEnd − rowBegin)), so that the row ranges of a split render stacked give
    /// the whole render exactly (a pixel does not depend on which others are rendered). 0/0:
    /// every row. Checked by imageRows.
    int rowBegin = 0, rowEnd = 0;
    /// Refuse (vtex::MemoryLimitError, before anything is loaded) when the renderer's estimate
    /// (estimateRenderMemory, estimateReferenceMemory) exceeds this; 0: no limit. The deformed
    /// reference checks its triangles against it too.
    std::uint64_t maxMemoryBytes = 0;
};

/// Every approximation of the texel renderer that trades error for time, in one place, each
/// with its bound stated and tested (docs/render.md). exact() turns them all off: the render
/// they are measured against. key() is what a pipeline's cache key and stats.json record.
struct ApproximationBudget {
    /// The second level of a blend reuses the first level's shadow rays (docs/render.md); false:
    /// each level casts its own (slower; the exact path the approximation is tested against).
    bool shareShadowRays = true;
    /// Directional lights: a shadow query inside a texel cell marches four lattice steps toward the
    /// light exactly, then interpolates a per-cell lattice of this many steps per side (per tile
    /// of the texel across, up to 4 tiles), each node one shadow ray cast on first use
    /// (docs/render.md, "Shadows"); 0: every query casts its own ray (the exact path), as when
    /// the lattices of all cells would exceed 2^26 nodes.
    int shadowCacheResolution = 8;
    /// The lattice's nodes chain from cell to cell: a node marches its own cell and takes the
    /// neighbour's lattice, interpolated on the shared face, where the light leaves through a
    /// side (docs/render.md, "Shadows"); false: every node casts a shadow ray walked through the
    /// whole scene (the exact nodes this is tested against).
    bool chainLatticeNodes = true;
    /// A lattice query's first, exact stretch toward the light (the four lattice steps) comes
    /// from a table per voxel of the shadow level, shared by the cells that show one tile of the
    /// same texel under the same reference-space light direction (a flat field's cells): the
    /// query's own voxel exactly, the rest interpolated from marches of 3×3 points of the face
    /// it leaves by (docs/render.md, "Shadows"); false: every query marches its stretch.
    bool nearShadowTable = true;
    /// A level whose blend weight is below this is not marched, its weight going to the other
    /// level (docs/render.md, "Levels"); 0: both levels of every blend are marched (exact).
    double blendCutoff = 0.1;
    /// A voxel whose share of the pixel (transmittance in front of it × its opacity × its level's
    /// blend weight) is below this reuses the shadow the march last queried and the reflectance
    /// it last evaluated for that light instead of its own, as long as the shares reused along
    /// the march add up to at most kLightingReuseBudget × this: the pixel moves by at most that
    /// sum (3 % of the largest reflected radiance) (docs/render.md, "Shading"). 0: every voxel
    /// takes its own (exact). 1e-2 since issue 12 (1e-3 with a budget of 10× before); the
    /// shadow's reuse since the seventeenth session: on the bush field's middle view 42 % fewer
    /// shadow queries and about 10 % less time, image mean 0.35 % darker (docs/error-vs-time.md).
    double lightingReuseWeight = 1e-2;
    static constexpr double kLightingReuseBudget = 3;
    /// The base surface of a texel cell, seen through a transmittance at least this, casts exact
    /// shadow rays; seen through less, its shadows come from the cell's transmittance lattice
    /// (as a voxel's do), which moves the pixel by at most that transmittance times the floor's
    /// direct light (docs/render.md, "Shadows"). 0: always exact.
    double exactFloorShadowAbove = 0.05;
    /// The floor of a flat field of identical cells takes its shadows toward a directional light
    /// from a table of the transmittance through the tiled texel (docs/render.md, "Shadows";
    /// FloorShadowTable) instead of an exact ray; false: every floor point casts its ray.
    bool floorShadowTable = true;
    /// A camera march's shadow query in such a cell, in a scene with nothing but that field,
    /// takes its own voxel exactly and the rest from a 3-D table of the tiled texel's optical
    /// depth to the top (FloorShadowTable::inside) instead of the near table and the lattice;
    /// false: those.
    bool fieldShadowVolume = true;
    /// Along a march, a voxel takes a new shadow query once the march's transmittance has fallen
    /// below this fraction of what it was at the last query, and reuses the last one otherwise;
    /// in (0, 1]. 1 (the default): a query at every voxel that absorbs anything, exact. Below 1
    /// deeper voxels reuse shallower voxels' shadows and are too bright: on the bush field 0.25
    /// raised the image mean by 21–51 % (docs/render.md, "Shadows").
    double shadowRefresh = 1;

    /// Every approximation off.
    static ApproximationBudget exact();
    bool isExact() const;
    /// One line naming every value, for cache keys and stats.json.
    std::string key() const;
    friend bool operator==(const ApproximationBudget&, const ApproximationBudget&) = default;
};

struct RenderOptions : ImageOptions {
    double lodBias = 0;   ///< added to the level choice: +1 is one octree level coarser
    ShadingMode shading = ShadingMode::Fast;
    int referenceSamples = 24;  ///< samplesPerAxis of the reference reflectance
    ApproximationBudget approximations;
    /// The mesh/volume hybrid (docs/render.md, "Mesh where the volume is not faithful"): a texel
    /// with a `source` mesh is traced as that mesh where a footprint asks for a level finer than
    /// the finest level whose chord transmittance is within `hybridTolerance` of the mesh's
    /// visibility (measured per texel at load, octree::measureChordTransmittance), blended over
    /// one level. false: always the volume.
    bool hybrid = true;
    double hybridTolerance = 0.02;
    /// For a texel with a source mesh, each level's densities are scaled by the factor that makes
    /// its mean transmittance over chords crossing the shell (top face to floor, as camera and
    /// shadow rays do) equal to the fraction of those chords that miss the mesh, measured at load
    /// (octree::fitShellChords; docs/render.md, "Levels fitted to the source"). false: the
    /// densities as filtered.
    bool fitLevels = true;
};

struct RenderStats {
    std::string renderer = "texel";  ///< "texel", "reference-embedded" or "reference-deformed"
    double wallSeconds = 0;   ///< the whole render, scene loading excluded
    double loadSeconds = 0;   ///< reading meshes and octrees, building the BVH
    int threads = 0;
    int width = 0, height = 0, spp = 0;  ///< the full image's size, whatever rows were rendered
    /// The rows rendered, [rowBegin, rowEnd) of `height` (ImageOptions::rowBegin); stats.json
    /// has them (row_begin, row_end) only when they are not every row.
    int rowBegin = 0, rowEnd = 0;
    std::uint64_t faces = 0;          ///< base faces (plain and textured)
    std::uint64_t cells = 0;          ///< textured faces
    std::uint64_t primaryRays = 0;
    std::uint64_t shadowRays = 0;
    std::uint64_t cellSegments = 0;   ///< ray spans marched inside texel cells
    std::uint64_t voxelsVisited = 0;  ///< octree blocks stepped through (empty ones included)
    std::uint64_t reflectanceEvaluations = 0;
    /// Weight of each octree level in the level choices (blend weights summed over the cell
    /// segments of camera rays); index = level.
    std::vector<double> levelHistogram;
    /// The hybrid's share of camera-ray segments traced through the source mesh (blend weights
    /// summed), and per texel the level past which its mesh takes over (−1: no mesh).
    double meshSegments = 0;
    std::vector<double> meshLevels;
    /// Per texel, the factor of τ of each level (RenderOptions::fitLevels; empty: not fitted).
    std::vector<std::vector<double>> levelScales;
    /// Per texel, the shadow level of each footprint level below its coarsest faithful level, as
    /// measured for fitted levels (docs/render.md, "Shadows at the level that lights what is
    /// seen"; empty: the footprint's level, never coarser than the coarsest faithful one).
    std::vector<std::vector<int>> shadowLevels;
    /// Per texel, the share of a voxel's matter on the surface piece a lit point of it lies on,
    /// per level, which a camera march's shadow query takes off its own voxel (docs/render.md,
    /// "A lit voxel's own leaf"; empty without a source).
    std::vector<std::vector<double>> ownShares;
    /// Per texel: "stored" when the levels above came from the .vto (`vtex build --source`),
    /// "measured" when the load measured them against the source, "none" without a source.
    std::vector<std::string> sourceMeasures;
    /// Per texel, whether its source mesh was read: at load, or by the first ray that traced it
    /// when the stored measures let the load leave it (false without a source).
    std::vector<bool> sourceLoaded;
    /// Texel renders: "exact", or ApproximationBudget::key() of the budget used.
    std::string approximations;
    /// Reference renders: triangles in the BVHs (embedded: each source mesh once; deformed:
    /// the deformed copies).
    std::uint64_t referenceTriangles = 0;
    /// Bytes of the scene's .vto files read (octree::Octree::bytesRead: the header, statistics
    /// and the levels the render used), and those files' sizes; in-memory octrees count 0.
    std::uint64_t vtoBytesRead = 0;
    std::uint64_t vtoFileBytes = 0;
    double meanLevel() const;
};

struct RenderResult {
    Image image;
    RenderStats stats;
    std::vector<std::string> warnings;
};

/// An upper estimate of renderScene's peak memory (bytes), before anything is loaded: 16 MiB, the
/// image (the rows rendered: 22 bytes a pixel, 30 with AOVs: the RGBA floats and the encoders' copies), what the
/// scene loads, from its files' sizes without reading them (base meshes 10× their file, octrees
/// and source meshes 3×), and the shadow lattices' cap (256 MiB) when a texel meets a
/// directional light. `bench/memory_estimates.py build/apps/vtex/vtex /tmp/mem` measured (at
/// 1c31985, docs/render.md "Memory") 20.1 and 28.2 bytes a pixel on a 4096² render with its
/// PNG (hence 22 and 30: at 20 and 28 the 4096² render with --aov peaked 0.4 MiB above the
/// estimate), 1.9× for the bush's octree and mesh; and (at 1123520, primitives built on demand)
/// 6.0× for an OBJ grid, 6.5× for the same grid as binary PLY (fewer bytes a face).
/// tests/cli/memory_limit_test.cpp checks it against measured peaks.
std::uint64_t estimateRenderMemory(const Scene& scene, const RenderOptions& options);

/// The rows [first, second) that `options` asks for of an image `height` rows tall: every row
/// for rowBegin = rowEnd = 0. Throws std::invalid_argument unless 0 ≤ rowBegin < rowEnd ≤ height
/// (a caller's error: the range is not part of the scene).
std::pair<int, int> imageRows(const ImageOptions& options, int height);

/// Loads what the scene references (meshes, octrees), builds the BVH and renders. Throws
/// vtex::InputError for bad scene content (file named), vtex::IoError; std::invalid_argument for a
/// bad row range (imageRows), before anything is loaded.
RenderResult renderScene(const Scene& scene, const RenderOptions& options, Progress& progress);

/// stats.json: wall time, threads, rays, voxels visited, level histogram, mean level; the row
/// range (row_begin, row_end) when only some rows were rendered.
void writeStatsJson(const RenderStats& stats, const std::filesystem::path& file);
/// The same into an output the caller commits (AtomicOutputFile, commitAll).
void writeStatsJson(const RenderStats& stats, AtomicOutputFile& out);
/// The text writeStatsJson writes.
std::string formatStatsJson(const RenderStats& stats);

}  // namespace vtex::render
