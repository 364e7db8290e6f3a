/// @file
/// @brief What each level of a texel lets through, against its source mesh: transmittance
/// along random chords of the whole texel.
///
/// A parent's density is the mean of its children's (DESIGN.md, "Octree"), so a coarse voxel
/// lets through what an *uncorrelated* medium of that mean would; a bush's leaves are correlated
/// opaque surfaces, clustered inside the voxel and across neighbouring voxels (the mean of
/// exp(−ρL) over a heterogeneous region exceeds exp(−mean ρ L): coarse levels are too opaque),
/// and a fine voxel across one opaque leaf lets e^−1 through where the leaf blocks every chord
/// that crosses it (fine levels are too transparent). This measures both, per level, as Vicini,
/// Jakob & Kaplanyan 2021 and Loubet & Neyret 2017 measure it before fitting: the fraction of
/// chords that miss the mesh against the model transmittance along the same chords.
#pragma once

#include <vtex/octree/chord_medium.h>
#include <vtex/octree/octree.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace vtex::octree {

/// Whether the straight reference-space segment a → b (inside the unit cube) meets no source
/// surface. Called concurrently from several threads.
using ChordVisibility = std::function<bool(const Vec3& a, const Vec3& b)>;

/// One level, over isotropic uniform random chords of the whole unit cube (a uniform
/// direction, an entry point uniform over the cube's projection along it): the mean fraction
/// that misses the source, and the mean model transmittance exp(−∫ρÂ) along the same chords
/// (the level's voxels walked exactly, exp(−τ∫ρÂ) with the renderer's τ). error() > 0: the level lets through more than the
/// explicit geometry.
struct ChordTransmittance {
    double visibility = 0;
    double transmittance = 0;
    double error() const { return transmittance - visibility; }
};

/// Every level of `tree`, `chords` chords each (the same chords for every level; a pure
/// function of `seed`, whatever the thread count). The mean of `chords` binary visibilities has
/// a standard error of at most 0.5/√chords (0.008 at the default).
std::vector<ChordTransmittance> measureChordTransmittance(const ChordMedium& medium, const ChordVisibility& visible,
                                                          double tau = 1, int chords = 4096, std::uint64_t seed = 1);

/// The same chords, level l's densities scaled by tauPerLevel[l] instead of one τ (a fitted
/// level's, fitShellChords's scale times τ): levels 0 … min(tauPerLevel.size(), levels) − 1.
std::vector<ChordTransmittance> measureChordTransmittance(const ChordMedium& medium, const ChordVisibility& visible,
                                                          const std::vector<double>& tauPerLevel, int chords = 4096,
                                                          std::uint64_t seed = 1);

/// Whether a level-by-level measurement has seen enough: called with each level's result in
/// turn, coarsest first; true stops before the next level is read or walked.
using EnoughLevels = std::function<bool(std::size_t level, const ChordTransmittance&)>;

/// The same levels and chords, from the coarsest down to the first level after which `enough`
/// says stop (the result holds the levels measured): finer levels are neither walked nor read
/// from a lazily opened file, whose finest levels hold nearly all its bytes.
std::vector<ChordTransmittance> measureChordTransmittance(const ChordMedium& medium, const ChordVisibility& visible,
                                                          double tau, int chords, std::uint64_t seed,
                                                          const EnoughLevels& enough);

/// One level over multi-voxel beams (the scale at which a fit of the level would be judged,
/// Vicini, Jakob & Kaplanyan 2021): a beam is a bundle of parallel chords on a stratified grid
/// over a square cross-section one voxel of the level across, four voxels long (at most half
/// the texel), in a uniform random direction, placed uniformly where the whole bundle lies
/// inside the unit cube. A beam's error is the mean model transmittance of its chords minus the
/// fraction of them that miss the source.
struct BeamError {
    double mean = 0;     ///< signed mean over the beams (> 0: the level lets through too much)
    double meanAbs = 0;  ///< mean |error|
    double p95Abs = 0;   ///< 95th percentile of |error|
    /// Mean binomial standard error of a beam's missing fraction, √(f(1−f)/chords): the
    /// sampling noise in meanAbs and p95Abs (an upper bound: the grid is stratified).
    double noise = 0;
};

/// Every level of `tree`, `beams` beams of `chordsPerBeam` chords each (rounded down to a
/// square); a pure function of `seed`, whatever the thread count.
std::vector<BeamError> measureBeamTransmittance(const ChordMedium& medium, const ChordVisibility& visible, double tau = 1,
                                                int beams = 256, int chordsPerBeam = 256, std::uint64_t seed = 1);

/// One level fitted over chords that cross the texel's shell as camera rays and shadow rays do:
/// from the top face (z = 1) down to the floor (z = 0) through the texel tiled in x and y, the
/// entry point uniform over the top face and the direction cosine-weighted (the flux through the
/// face), zenith angles up to 80° (chords up to 5.8 shell heights long). `scale` is the factor of
/// the level's densities whose mean transmittance over those chords equals the fraction of them
/// that miss the source (Loubet & Neyret 2017 fit extinction to the opacity observed through the
/// mesh; Vicini, Jakob & Kaplanyan 2021 over multi-voxel beams): below 1 where the level spreads
/// clustered leaves over its voxels and is too opaque, above 1 where a voxel across one opaque
/// leaf lets e^−1 through. Clamped to [1/64, 64]; 1 for a level without density.
struct ShellChordFit {
    double visibility = 0;     ///< fraction of the chords that miss the source
    double transmittance = 0;  ///< the level's mean transmittance with its own densities
    double scale = 1;
    double error() const { return transmittance - visibility; }  ///< > 0: lets more through
};
/// Levels 0 … min(finestLevel, deepest) of `tree`, over `chords` shell chords (the same for every
/// level; a pure function of `seed`, whatever the thread count). The visibility's standard error
/// is ≤ 0.5/√chords.
std::vector<ShellChordFit> fitShellChords(const ChordMedium& medium, const ChordVisibility& visible, double tau = 1,
                                          int chords = 4096, std::uint64_t seed = 1, std::uint32_t finestLevel = 30);
/// The mean transmittance of `level` with its densities times `scale`, over `chords` shell chords
/// drawn from `seed` (what fitShellChords equates to the visibility; for checking a fit on
/// chords it was not fitted on).
ShellChordFit measureShellChords(const ChordMedium& medium, const ChordVisibility& visible, std::uint32_t level,
                                 double scale, double tau = 1, int chords = 4096, std::uint64_t seed = 1);

/// Where the segment a → b (inside the unit cube) first meets a source surface, as a fraction of
/// its length; none when it misses. Called concurrently from several threads.
using ChordFirstHit = std::function<std::optional<double>(const Vec3& a, const Vec3& b)>;

/// How often what a camera sees of the texel is lit, through the source mesh and through the
/// levels (issue 12: a voxel shadows the leaves it stands for, the more so the denser and finer it
/// is, and a coarse one the clump around it). Camera chords are fitShellChords's; a light direction
/// per chord is drawn as the chords' own (cosine-weighted over the upper hemisphere, zenith ≤ 80°).
/// On the mesh: the first surface the chord meets, and whether a ray from it toward the light
/// reaches the top face through the tiled texel (the surface itself skipped: its orientation is
/// the reflectance's business, not the shadow's). In the volume at camera level c (densities ×
/// scales[c]): a point drawn where the chord's march puts its weight (density ∝ T·σ along the
/// chord, the share of the pixel each voxel gets) and the transmittance toward the light from it at
/// shadow level l (densities × scales[l]), each chord weighted by its opacity 1 − T. Measured for
/// camera and shadow levels up to finestShadowLevel, all below scales.size() and the tree's levels,
/// shadow levels from c − 1 (a shadow's cone is never narrower than its camera ray's; NaN
/// elsewhere), and of those only the pairs (c, l) `wanted` says (all when empty; NaN for the
/// others: a fine shadow level's walks are most of the cost). `ownShares[l]`, when given (as
/// SourceMeasures::ownShares), is taken off the density of the level-l voxel a shadow ray starts
/// in, up to where it leaves it (its density times 1 − share), as the renderer's queries from a
/// lit voxel do: the piece it lights does not shadow it. A pure function of `seed`, whatever the
/// thread count.
struct LitFractions {
    double mesh = 1;                          ///< fraction of the mesh's seen points that are lit
    std::size_t seen = 0;                     ///< chords whose first surface the mesh shows
    std::vector<std::vector<double>> volume;  ///< [camera level][shadow level]
    double error(std::size_t camera, std::size_t shadow) const { return volume[camera][shadow] - mesh; }
    /// The binomial standard error of `mesh` (0.5/√seen at most), the noise every error shares.
    double meshStandardError() const { return seen > 0 ? std::sqrt(mesh * (1 - mesh) / double(seen)) : 0; }
};
using LitPairs = std::function<bool(std::size_t camera, std::size_t shadow)>;
LitFractions measureLitFractions(const ChordMedium& medium, const ChordFirstHit& hit, const ChordVisibility& visible,
                                 double tau, const std::vector<double>& scales, std::size_t finestShadowLevel,
                                 int chords, std::uint64_t seed = 1, const LitPairs& wanted = {},
                                 const std::vector<double>& ownShares = {});

/// Visits the non-empty voxels of `level` that the segment a → b (inside the unit cube) crosses,
/// front to back, as visit(node that stands for the voxel, t0, t1) with [t0, t1] the distances
/// from a along the segment (an exact Amanatides–Woo walk; a leaf above the level stands for its
/// voxels). Nothing for a level the tree does not have.
void forEachVoxelOnSegment(const Octree& tree, std::uint32_t level, const Vec3& a, const Vec3& b,
                           const std::function<void(const OctreeNode&, double, double)>& visit);

}  // namespace vtex::octree
