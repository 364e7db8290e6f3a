/// @file
/// @brief Segment visibility against a texel's source mesh in reference space, through the
/// same Embree BVH the reference renderer traces: what `vtex inspect --source`, `vtex build
/// --source` and a pipeline's build stage measure each level's transmittance against
/// (octree/chord_transmittance.h).
#pragma once

#include <vtex/ingest/mesh.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/render/geometry.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

namespace vtex::render {

namespace detail {
class SourceBvh;
}

class SourceVisibility {
public:
    /// `volume`: where the sampler placed the mesh in the unit cube (a .vtl's or .vto's info). `mesh` must outlive this object.
    SourceVisibility(const ingest::TriangleMesh& mesh, const octree::VolumeInfo& volume);
    ~SourceVisibility();
    SourceVisibility(const SourceVisibility&) = delete;
    SourceVisibility& operator=(const SourceVisibility&) = delete;

    /// Whether no source triangle lies on the reference-space segment a → b. Thread-safe.
    bool visible(const Vec3& a, const Vec3& b) const;
    /// Where the segment a → b first meets a source triangle, as a fraction of its length; none
    /// when it misses (octree::ChordFirstHit). Thread-safe.
    std::optional<double> firstHit(const Vec3& a, const Vec3& b) const;

private:
    std::unique_ptr<detail::SourceBvh> mBvh;
};

/// The range of levels at which the volume lets through what the source mesh does within
/// `tolerance` (absolute transmittance, mean over random chords of the whole texel; `chords` from
/// the coarsest level, possibly cut after the first level past the run): from the coarsest level
/// finer, the first level within the tolerance and the finer ones as long as each stays within
/// it. Coarser than that, a voxel spreads clustered leaves over its whole volume and is too
/// opaque; finer, a voxel stands for a piece of one opaque surface that the exponential medium
/// lets light through (and shadows itself). When no level is within the tolerance, the level of
/// least error alone. The hybrid traces the mesh past the finest (docs/render.md, "Mesh where the
/// volume is not faithful") and shadows keep to the coarsest.
struct FaithfulLevels {
    int coarsest = 0, finest = 0;
};
FaithfulLevels faithfulLevels(const std::vector<octree::ChordTransmittance>& chords, double tolerance);

/// The finest level the hybrid marches, whatever the texel (docs/render.md, "No finer than the
/// mesh costs"). A camera span at level l crosses about 2^l voxels of its cell, each with its
/// extinction, reflectance and shadow query; a span through the source mesh costs 2 × 2 rays in
/// the hybrid's band, one past it, each with its shadow ray. On this project's 2-core machine a
/// voxel visited costs about 83 ns of a thread and a mesh segment 0.68 µs (the bush field's
/// middle and near views: 14.5 M voxels in 0.60 s, 1.08 M mesh segments in 0.37 s, on 2
/// threads), so from level 5 (2^5 × 83 ns ≈ 4 × 0.68 µs) the volume is no cheaper than the mesh
/// and at each finer level twice as dear; and at those levels a voxel holds a piece of one
/// surface, which the volume lets light through and shadows with its own matter (fur, topiary
/// and brushed metal 10–27 % too dark near while their faithful levels reached 7–8).
inline constexpr int kFinestMarchedLevel = 5;
/// The faithful levels the hybrid uses: `faithful` with both ends no finer than
/// kFinestMarchedLevel (the shadows' coarsest level, the levels fitted and the mesh level).
inline FaithfulLevels marchedLevels(FaithfulLevels faithful) {
    faithful.coarsest = std::min(faithful.coarsest, kFinestMarchedLevel);
    faithful.finest = std::min(faithful.finest, kFinestMarchedLevel);
    return faithful;
}

/// The shell chords the renderer fits each level's factor of τ over (`--level-fit`, docs/render.md
/// "Levels fitted to the source"): a mean of them has a standard error ≤ 0.5/√16384 = 0.004.
inline constexpr int kLevelFitChords = 16384;
/// The chords the renderer measures a texel's faithful levels and its lit fractions with at load
/// (texel_runtime.cpp; the mean of each has a standard error ≤ 0.5/√4096 = 0.008), seed 1.
inline constexpr int kLoadChords = 4096;

/// What a render measures of a texel against its source at load, stored by `vtex build --source`
/// in the .vto (octree::SourceMeasures, the MEAS section) so that renders need not measure it:
/// the faithful levels, each level's density scale (kLevelFitChords shell chords), the shadow
/// levels and the hybrid's mesh level (kLoadChords chords each), as a render with the default
/// options (hybrid and level fit on) measures them for a texel of τ `tau` at chord tolerance
/// `tolerance` (RenderOptions::hybridTolerance). `file`, when the mesh was read from one: its
/// bytes' hash is kept too (sourceFileHash), so that a render reading that file may leave the mesh
/// unread. Deterministic: the same inputs give the same bits.
octree::SourceMeasures measureSource(const octree::Octree& tree, const ingest::TriangleMesh& source, double tau,
                                     double tolerance, const std::filesystem::path& file = {});
/// The version a record of measureSource carries: a digest of the measuring rules' revision and of
/// the constants above they depend on, so that a texel measured by another build of them is
/// measured again rather than trusted.
std::uint32_t sourceMeasuresVersion();
/// XXH3-64 of a mesh's geometry (positions and triangles), all the measures see of the source.
std::uint64_t sourceGeometryHash(const ingest::TriangleMesh& mesh);
/// XXH3-64 of a source file's bytes: a render whose source file is the one the record was measured
/// from takes the record without reading the mesh (its geometry hash needs the mesh loaded).
/// Throws vtex::InputError naming the file when it cannot be read.
std::uint64_t sourceFileHash(const std::filesystem::path& file);
/// Whether a stored record was measured by these rules (sourceMeasuresVersion) for τ `tau` and
/// tolerance `tolerance`: then it is what measureSource would give now for the same source.
bool measuresApply(const octree::SourceMeasures& stored, double tau, double tolerance);

/// How faithful each level of a texel is to its source mesh (issue 13's measure): the
/// transmittance along 4096 random chords of the whole texel, and over 256 beams of the level
/// (mean, mean |error| and 95th percentile); then the same chords through the levels as the
/// renderer fits them (each level's densities times `fitScale`, fitted over kLevelFitChords shell
/// chords at τ = 1), which is what a render with `--level-fit on` marches: the levels up to the
/// finest the hybrid marches, marchedLevels of the faithful levels at the renderer's default
/// tolerance (finer ones it never marches, and the fit's four times as many chords, each up to
/// 5.8 shell heights long, would walk the finest levels, which hold nearly all the voxels).
struct SourceFidelity {
    std::vector<octree::ChordTransmittance> chords;
    std::vector<octree::BeamError> beams;
    std::vector<double> fitScale;
    std::vector<octree::ChordTransmittance> fitted;
    /// Levels 0 … profiledLevels − 1 carry the texel's density profile, in height and across
    /// (octree::DensityProfile), in every figure above.
    int profiledLevels = 0;
};
SourceFidelity measureSourceFidelity(const octree::Octree& tree, const ingest::TriangleMesh& source);

}  // namespace vtex::render
