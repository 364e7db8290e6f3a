/// @file
/// @brief How the matter of a coarse voxel is spread within it: the density profiles that the
/// coarsest levels keep from a finer one, over height and, on the coarsest two, across.
///
/// A parent's density is the mean of its children's (DESIGN.md, "Octree"), so a level-0 voxel
/// spreads a bush's leaves evenly from the texel's floor to its top, where the bush has few at
/// the bottom and top and many in the middle (level 6's layer means, bottom to top, every eighth
/// layer: 0, 44, 100, 108, 92, 100, 107, 27). Along the chords of `vtex inspect` the one factor
/// per level that fits the shell's chords then leaves the bottom and top quarters too opaque and
/// the middle too transparent (docs/error-vs-time.md, "Issue 13's coarse levels: a direction
/// factor and vertical profiles"). Where a voxel spans many layers of the profile level, its
/// density is therefore taken to vary with height as the texel's layer means do: ρ(z) = ρ·p(z),
/// p = the layer's mean density (over x and y, the whole texel) over the mean of the layers the
/// voxel spans, so that the voxel keeps its mass. No free parameter; a texel whose layers are
/// equally dense has p ≡ 1.
///
/// The same holds across: a voxel as wide as half the texel or more spreads the bush's leaves
/// into the tile's empty corners, which an isotropic chord crosses and the leaves' own chords
/// do not. There the density is separable, ρ(x, y, z) = ρ·p_x(x)·p_y(y)·p(z), each factor the
/// profile level's mean over the other two axes (across, on kColumns columns a side), normalised
/// over the voxel's span: the product of three factors of mean 1 over a box has mean 1 over it,
/// so the voxel still keeps its mass.
#pragma once

#include <vtex/octree/octree.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace vtex::octree {

class DensityProfile {
public:
    /// The level whose layer means the profile keeps (capped at the texel's finest).
    static constexpr int kProfileLevel = 6;
    /// A level is profiled in height where one voxel spans at least this many of the profile's
    /// layers (levels 0–3 of a texel of 64³ voxels or more). Measured on the 256³ bush
    /// (bench/vtex_chord_families, bench/bush_field.sh): at levels 0–2 the uniform voxel misses
    /// issue 13's chord goal (−0.04, −0.04, −0.02) and the profile halves it; at level 3 it
    /// takes the bush field's far RMSE from 0.00276 to 0.00268 at no measurable cost; profiling
    /// levels 4–5 too (2 layers a voxel) would cost the far and middle views 5–7 % of their time
    /// for RMSEs 0.4–0.5 % lower.
    static constexpr int kMinLayers = 8;
    /// A level is profiled across as well where one voxel spans at least this many of the
    /// profile's columns (levels 0–1 of a texel of 64³ voxels or more), half the tile or more.
    /// Measured on the 256³ bush (`vtex inspect bush.vto --source bush.glb`, fitted): the
    /// isotropic chord error at levels 0–1 goes from −0.022 / −0.021 to −0.010 / −0.009; level 2
    /// meets the goal without it (−0.012; −0.007 with it), and the rule stops where the goal
    /// needed it.
    static constexpr int kMinColumns = 32;
    /// The profile across keeps this many columns a side (each the mean of 4 of level 6's), so
    /// that a walk through a voxel crosses few. With kColumns set to 64, 16 and 8 and rebuilt, the
    /// bush field's far view forced to levels 0–1 (`vtex render far.toml --lod-bias 3` in the
    /// folder bench/bush_field.sh leaves, against its truth_far.exr; one run each) had RMSEs
    /// 0.00468, 0.00470, 0.00477 in 0.120, 0.092, 0.089 s (uniform across: 0.00585 in 0.077 s),
    /// and `vtex inspect bush.vto --source bush.glb` chord errors at level 0 of −0.0098, −0.0100,
    /// −0.0102.
    static constexpr int kColumns = 16;
    static_assert(kColumns <= kMinColumns, "a level profiled across spans whole columns of the profile");

    /// How many levels (0 … n − 1) a tree whose deepest level is `deepest` profiles in height.
    static constexpr int profiledLevels(int deepest) { return levelsSpanning(deepest, kMinLayers); }
    /// How many levels (0 … n − 1) it also profiles across.
    static constexpr int profiledAcrossLevels(int deepest) { return levelsSpanning(deepest, kMinColumns); }

    /// None: every factor is 1.
    DensityProfile() = default;
    /// `tree`'s profile (loads its profile level).
    explicit DensityProfile(const Octree& tree);

    /// Whether `level`'s voxels carry the profile in height.
    bool profiles(int level) const { return level >= 0 && level < int(mFactor.size()); }
    /// Whether they also carry it across.
    bool profilesAcross(int level) const { return level >= 0 && level < int(mAcross.size()); }
    /// The mean of p over the heights z0 … z1 (reference units, clamped to [0, 1], in either
    /// order) at `level`: the factor by which a segment's optical depth through a voxel of
    /// `level` between those heights differs from the uniform voxel's. 1 at levels not profiled.
    double meanFactor(int level, double z0, double z1) const;
    /// The same factor for the segment a → b (reference units; x and y periodic with the tile,
    /// z clamped to [0, 1]): the mean of p_x·p_y·p over it where `level` is profiled across
    /// (exact: a walk through the profile's columns, in each of which p_x·p_y is constant and p's
    /// mean comes from its cumulative sums), else meanFactor(level, a.z, b.z). A segment longer
    /// than kMaxAcrossTiles tiles across (a grazing ray through one run of a level-0 voxel over
    /// a large field) takes the mean over its first kMaxAcrossTiles tiles: the walk's cost stays
    /// below (kMaxAcrossTiles + 4)·kColumns columns, and the factors being periodic, what the
    /// rest of the segment crosses is what its first tiles crossed (exactly so for a segment
    /// along an axis or of small rational slope).
    double meanFactor(int level, const Vec3& a, const Vec3& b) const;
    static constexpr double kMaxAcrossTiles = 64;

private:
    static constexpr int levelsSpanning(int deepest, int minLayers) {
        int n = 0;
        for (int layers = 1 << std::clamp(deepest, 0, kProfileLevel); layers >= minLayers; layers /= 2) ++n;
        return n;
    }

    int mLayers = 0;                          ///< 2^(profile level)
    std::vector<std::vector<double>> mFactor;  ///< [level][layer]: p on the layer
    /// [level][k]: ∫ p from z = 0 to the layer boundary k / mLayers, in layer widths (k = 0 … mLayers)
    std::vector<std::vector<double>> mCumulative;
    std::vector<std::array<std::vector<double>, 2>> mAcross;  ///< [level][x or y][column]: p_x, p_y
};

}  // namespace vtex::octree
