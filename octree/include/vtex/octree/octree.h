/// @file
/// @brief The filtered, compressed octree of a texel (what a .vto file holds), and its builder.
///
/// Neyret 1994 §3 (multiscale model) and §3.3 (filtering); DESIGN.md, "Octree: filtering and
/// compression". Level ℓ has 2^ℓ voxels per side; level 0 is the whole texel.
///
/// Compression: a stored node with no children (childMask 0) is a *leaf* and stands for all its
/// descendants, every finest voxel below it within the tolerance ε of it in what a render sees:
/// the transmittance along any chord of the leaf's voxel changes by at most ε (per unit τ:
/// max|ρ − ρ_leaf| · √(tr S_max) · √3 · 2^−ℓ ≤ ε, a missing child counting as density 0), and
/// the normalised S and the albedo, on which the reflectance depends, by at most ε entrywise.
/// An internal node's missing children are empty. An empty region is therefore represented
/// once, by the cleared bit of its coarsest non-empty ancestor (or by an empty root).
#pragma once

#include <vtex/core/progress.h>
#include <vtex/octree/filtering.h>
#include <vtex/octree/volume.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::octree {

namespace detail {
class LevelLoader;
}

struct OctreeNode {
    VoxelData data;
    std::uint8_t childMask = 0;    ///< bit c set: child c (see mortonEncode) is stored
    std::uint32_t firstChild = 0;  ///< index of the first stored child in the next level

    bool isLeaf() const { return childMask == 0; }
    friend bool operator==(const OctreeNode&, const OctreeNode&) = default;
};

/// Statistics of one level.
struct LevelStats {
    std::uint64_t storedNodes = 0;    ///< nodes stored at this level
    std::uint64_t occupiedNodes = 0;  ///< non-empty voxels at this level before compression
    /// Mean density over the whole level (empty voxels count 0); filtering conserves it, so it
    /// is the same at every level up to rounding.
    double meanDensity = 0;
    /// Mean density over the non-empty voxels of the level.
    double meanOccupiedDensity = 0;
    /// Filter error (filterError()) of the level's filtered nodes: mean and max over a
    /// deterministic sample of `filterErrorSamples` nodes (0 for the finest level).
    double filterErrorMean = 0;
    double filterErrorMax = 0;
    std::uint64_t filterErrorSamples = 0;
    friend bool operator==(const LevelStats&, const LevelStats&) = default;
};

struct OctreeInfo {
    VolumeInfo source;  ///< what the .vtl said (resolution, mapping, fit error …)
    FilterRule rule = FilterRule::Sggx;
    float tolerance = 0;
    friend bool operator==(const OctreeInfo&, const OctreeInfo&) = default;
};

/// What a render measures of a texel against its source mesh when it loads the texel (the
/// faithful levels, each level's density scale, the shadow levels, the hybrid's mesh level;
/// docs/render.md, "Mesh where the volume is not faithful" and "Levels fitted to the source"),
/// measured once by `vtex build --source` and kept in the .vto's MEAS section (docs/formats.md).
/// The octree only stores and checks it; render::measureSource makes it and a render takes it
/// in place of measuring when version, geometry, τ and tolerance are what it would measure with.
struct SourceMeasures {
    std::uint32_t version = 0;       ///< the measuring code's version (render::sourceMeasuresVersion)
    std::uint64_t geometryHash = 0;  ///< of the source mesh (render::sourceGeometryHash)
    std::uint64_t fileHash = 0;      ///< of the source file's bytes the build read (render::sourceFileHash; 0: none)
    double tau = 0;                  ///< the texel's τ measured with
    double tolerance = 0;            ///< the hybrid's chord tolerance measured with
    std::int32_t faithfulCoarsest = 0, faithfulFinest = 0;  ///< as measured, before any cap
    std::int32_t meshLevel = 0;                             ///< the hybrid's mesh level
    std::vector<double> levelScales;         ///< one per level fitted, from level 0
    std::vector<std::int32_t> shadowLevels;  ///< one per footprint level below the coarsest shadow level
    /// Per level from 0, the share of a voxel's matter on the surface piece a point of it lies on
    /// (render's measureOwnShares), each in [0, 1]; empty in a record of revision 1.
    std::vector<double> ownShares;
    friend bool operator==(const SourceMeasures&, const SourceMeasures&) = default;
};

/// The mean density per layer of each axis at the coarse levels' density profile level (what
/// octree::DensityProfile is made of; octree/density_profile.h): measured by the build, which has
/// every level in memory, and kept in the .vto's PROF section (docs/formats.md), so that a render
/// that marches only coarse levels need not read the profile's finer one.
struct LayerMeans {
    std::uint32_t level = 0;                  ///< the level measured: 2^level layers an axis
    std::array<std::vector<double>, 3> axis;  ///< [0] per x column, [1] per y column, [2] per z layer
    friend bool operator==(const LayerMeans&, const LayerMeans&) = default;
};

class Octree {
public:
    OctreeInfo info;
    /// levels[ℓ]: the stored nodes of level ℓ in Morton order; levels[0] holds the root (an
    /// empty root when the volume is empty). levels.size() = L + 1. A tree opened with openVto
    /// fills levels[ℓ] only when loadLevels(ℓ' ≥ ℓ) asks for it: call loadLevels before reading
    /// levels[0 … ℓ] or find(ℓ, …).
    std::vector<std::vector<OctreeNode>> levels;
    std::vector<LevelStats> stats;  ///< one per level
    /// The render's measures against the source, when `vtex build --source` stored them. A tree
    /// built or updated in memory has none until they are measured for it.
    std::optional<SourceMeasures> measures;
    /// The density profile's layer means, when the tree was built or read with them (a tree
    /// whose levels are changed afterwards must drop them).
    std::optional<LayerMeans> layerMeans;

    Octree();
    ~Octree();
    /// A copy or a move of a tree opened with openVto loads all its levels first: the result is a
    /// tree read whole. Throws vtex::InputError as loadLevels does.
    Octree(const Octree& other);
    Octree(Octree&& other);
    Octree& operator=(const Octree& other);
    Octree& operator=(Octree&& other);
    /// Same info, levels, statistics and measures (every level loaded first).
    friend bool operator==(const Octree& a, const Octree& b);

    /// Levels 0 … min(level, deepest) in memory: a tree opened with openVto reads and checks
    /// each level's section the first time one at or below it is asked for (thread-safe; after
    /// the first call for a level, one atomic load). A no-op for a tree built or read whole.
    /// Throws vtex::InputError naming the file and the section if the section is damaged (or the
    /// file was changed in place since it was opened).
    void loadLevels(std::uint32_t level) const;
    /// Bytes of its .vto file read so far: the whole file for readVto, the header, statistics and
    /// loaded levels for openVto; 0 for a tree built in memory.
    std::uint64_t bytesRead() const;

    std::uint32_t levelCount() const { return std::uint32_t(levels.size()); }
    std::uint32_t resolution() const { return std::uint32_t(1) << info.source.levels; }
    std::uint64_t storedNodes() const;
    /// 1 − stored nodes / N³.
    double compression() const;

    // Lookups of a voxel: OctreeCursor (octree/cursor.h), the one descent of the tree.

    /// Every non-empty voxel of `level` that the compressed tree stands for, each as a block at
    /// `level` (leaves above are replicated): for tests and tools, O(8^level) at worst.
    std::vector<VolumeBlock> expandLevel(std::uint32_t level) const;

private:
    friend Octree readVto(const std::filesystem::path& file);
    friend std::shared_ptr<const Octree> openVto(const std::filesystem::path& file);
    std::unique_ptr<detail::LevelLoader> mLoader;  ///< openVto's open file; null once all is in memory
    std::uint64_t mBytesRead = 0;                  ///< readVto: the file's size
};

struct BuildOptions {
    FilterRule rule = FilterRule::Sggx;
    double tolerance = 0;  ///< ε ≥ 0, see the file comment; 0 keeps only exactly constant regions
    /// Filtered nodes per level on which the filter error is measured (a deterministic,
    /// hash-selected sample); 0 measures all of them.
    std::uint64_t filterErrorSamples = 4096;
    /// false: store every non-empty node (no compression), for comparisons and tests.
    bool compress = true;
};

/// Builds every level from the sampled finest level, keeping the uncompressed pyramid so that
/// a region can be re-sampled and only its ancestors re-filtered (the paper's partial
/// recompute). Memory O(occupied voxels).
class OctreeBuilder {
public:
    OctreeBuilder(SparseVolume finest, const BuildOptions& options, Progress& progress);
    /// The builder that made `tree`, rebuilt from the tree alone, as if from a finest level with
    /// `info` (`vtex build --update`): possible when the tree stores every node of its pyramid —
    /// no node above the finest level merged, as a surface built with tolerance 0 leaves it —
    /// and no solid block; std::nullopt otherwise. `options` must hold the tree's rule and
    /// tolerance. updateRegion then compress() give the full build's tree bit for bit.
    static std::optional<OctreeBuilder> resume(const Octree& tree, const VolumeInfo& info, const BuildOptions& options);
    ~OctreeBuilder();
    OctreeBuilder(OctreeBuilder&&) noexcept;
    OctreeBuilder& operator=(OctreeBuilder&&) noexcept;

    /// Replaces everything inside `region` (finest voxel indices) by `blocks` (each inside the
    /// region; surface voxels and solid blocks as the sampler returns them for that region),
    /// then re-filters only the nodes above the region. Throws std::invalid_argument if a block
    /// lies outside the region.
    void updateRegion(const VoxelBox& region, std::vector<VolumeBlock> blocks, Progress& progress);

    /// The compressed octree of the current state.
    Octree compress(Progress& progress) const;

    /// The current finest level (with the region updates applied).
    const SparseVolume& finest() const;
    /// Nodes filtered so far (full build plus updates): lets tests check that an update
    /// re-filters only the ancestors of its region.
    std::uint64_t filteredNodeCount() const;

private:
    OctreeBuilder();
    // keepFinest false: the finest level's blocks are freed once the pyramid holds them (finest()
    // is then empty), for buildOctree, whose builder nobody sees or updates.
    OctreeBuilder(SparseVolume finest, const BuildOptions& options, Progress& progress, bool keepFinest);
    friend Octree buildOctree(SparseVolume volume, const BuildOptions& options, Progress& progress);
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

/// OctreeBuilder(volume).compress() in one call. Pass the volume by std::move when it is not
/// needed afterwards: the builder keeps it, and a copy of a 1024³ volume is half a gigabyte.
Octree buildOctree(SparseVolume volume, const BuildOptions& options, Progress& progress);

/// An upper estimate of the peak memory (bytes) of reading the .vtl `file` and building its
/// octree, from the file's size alone, before it is read: 12× the file plus 32 MiB (the parsed
/// volume, the uncompressed pyramid and the compressed tree; the peak is 10.0× the file for the
/// bush at 256³, 7.1× for the 20000-leaf bush: `bench/memory_estimates.py build/apps/vtex/vtex
/// /tmp/mem` at 1c31985, docs/render.md "Memory"; checked in tests/cli/memory_limit_test.cpp).
/// 0 for a file that cannot be stat'ed (its reader names the problem).
std::uint64_t estimateBuildMemory(const std::filesystem::path& file);

/// The filter rule's name on the command line and in files: "neyret" or "sggx".
std::string_view filterRuleName(FilterRule rule);
std::optional<FilterRule> parseFilterRule(std::string_view name);

/// .vto file format version written by this program (docs/formats.md).
inline constexpr std::uint32_t kVtoVersion = 1;
std::string serializeVto(const Octree& octree);
/// Parses and validates .vto bytes. Throws vtex::InputError naming the failing section.
Octree parseVto(std::string_view bytes, const std::filesystem::path& file);
void writeVto(const Octree& octree, const std::filesystem::path& file);
/// Reads and checks the whole file (every section's checksum, every level), as `vtex inspect`
/// and the tools that rewrite a tree need.
Octree readVto(const std::filesystem::path& file);
/// Opens `file` for a render: reads and checks the header, the section table, HEAD and STAT now,
/// and each level's section (its checksum and nodes, as readVto does) on first use
/// (Octree::loadLevels). The file stays open until the tree is destroyed, so a file replaced
/// meanwhile (vtex writes by rename) is still read as it was; one changed in place fails its
/// section's checksum. Throws vtex::InputError naming the file and the failing section.
std::shared_ptr<const Octree> openVto(const std::filesystem::path& file);

}  // namespace vtex::octree
