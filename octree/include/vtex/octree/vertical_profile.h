/// @file
/// @brief How the matter of a coarse voxel is spread over its height: the vertical density
/// profile that the coarsest levels keep from a finer one.
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
#pragma once

#include <vtex/octree/octree.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace vtex::octree {

class VerticalProfile {
public:
    /// The level whose layer means the profile keeps (capped at the texel's finest).
    static constexpr int kProfileLevel = 6;
    /// A level is profiled where one voxel spans at least this many of the profile's layers
    /// (levels 0–3 of a texel of 64³ voxels or more). Measured on the 256³ bush
    /// (bench/vtex_chord_families, bench/bush_field.sh): at levels 0–2 the uniform voxel misses
    /// issue 13's chord goal (−0.04, −0.04, −0.02) and the profile halves it; at level 3 it
    /// takes the bush field's far RMSE from 0.00276 to 0.00268 at no measurable cost; profiling
    /// levels 4–5 too (2 layers a voxel) would cost the far and middle views 5–7 % of their time
    /// for RMSEs 0.4–0.5 % lower.
    static constexpr int kMinLayers = 8;

    /// How many levels (0 … n − 1) a tree whose deepest level is `deepest` profiles.
    static constexpr int profiledLevels(int deepest) {
        int n = 0;
        for (int layers = 1 << std::clamp(deepest, 0, kProfileLevel); layers >= kMinLayers; layers /= 2) ++n;
        return n;
    }

    /// None: every factor is 1.
    VerticalProfile() = default;
    /// `tree`'s profile (loads its profile level).
    explicit VerticalProfile(const Octree& tree);

    /// Whether `level`'s voxels carry the profile.
    bool profiles(int level) const { return level >= 0 && level < int(mFactor.size()); }
    /// The mean of p over the heights z0 … z1 (reference units, clamped to [0, 1], in either
    /// order) at `level`: the factor by which a segment's optical depth through a voxel of
    /// `level` between those heights differs from the uniform voxel's. 1 at levels not profiled.
    double meanFactor(int level, double z0, double z1) const;

private:
    int mLayers = 0;                          ///< 2^(profile level)
    std::vector<std::vector<double>> mFactor;  ///< [level][layer]: p on the layer
    /// [level][k]: ∫ p from z = 0 to the layer boundary k / mLayers, in layer widths (k = 0 … mLayers)
    std::vector<std::vector<double>> mCumulative;
};

}  // namespace vtex::octree
