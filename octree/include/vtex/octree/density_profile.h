/// @file
/// @brief How the matter of a coarse voxel is spread within it: the density profile that the
/// coarse levels keep from a finer one, over height and across.
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
/// The same holds across: a coarse voxel spreads a bush's leaves evenly into the tile's empty
/// corners, which an isotropic chord crosses and the leaves' own chords do not. So the density
/// is separable, ρ(x, y, z) = ρ·p_x(x)·p_y(y)·p(z), each factor the profile level's mean over the
/// other two axes (across, on columnsAcross(level) columns a side), normalised over the voxel's
/// span: the product of three factors of mean 1 over a box has mean 1 over it, so the voxel
/// still keeps its mass, and a texel whose density is separable comes back exactly.
#pragma once

#include <vtex/octree/octree.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace vtex::octree {

class DensityProfile {
public:
    /// The level whose layer means the profile keeps (capped at the texel's finest).
    static constexpr int kProfileLevel = 6;
    /// A level is profiled where one voxel spans at least this many of the profile's layers
    /// (levels 0–3 of a texel of 64³ voxels or more), in height on every layer. Measured on the
    /// 256³ bush (bench/vtex_chord_families, `vtex inspect bush.vto --source bush.glb`,
    /// bench/bush_field.sh; docs/render.md, "The coarse levels' density profile"): at levels 0–2
    /// the uniform voxel misses issue 13's chord goal (−0.04, −0.04, −0.02), the profile in height
    /// halves that and the profile across halves levels 0–1's again; at level 3 the profile brings
    /// the bush field's far view closer to its truth. Profiling level 4 too darkened the middle
    /// view's leaves further and cost both views more than a tenth of their time.
    static constexpr int kMinLayers = 8;
    /// Across, level l keeps max(kTileColumns, kVoxelColumns·2^l) columns a side (at most the
    /// profile level's): 16 at levels 0–2, 32 at level 3, so a level-0 voxel sees the tile on 16
    /// columns and a level-3 voxel on 4 of its own. More columns cost a march's walk more
    /// crossings. Set to 8 and 8 (8 per voxel at every level) and rebuilt, the far view gave RMSE
    /// 0.002606 against 0.002610 and a largest bias of 3.3 % against 3.4 %, in 14 % more time
    /// against 8 %; 8 and 4 columns at level 0 raised its chord error to −0.0102 and −0.0142
    /// (from −0.0100). Commands and conditions: docs/render.md, "The coarse levels' density
    /// profile".
    static constexpr int kTileColumns = 16;
    static constexpr int kVoxelColumns = 4;
    static constexpr int columnsAcross(int level) { return std::max(kTileColumns, kVoxelColumns << level); }

    /// How many levels (0 … n − 1) a tree whose deepest level is `deepest` profiles.
    static constexpr int profiledLevels(int deepest) {
        int n = 0;
        for (int layers = 1 << std::clamp(deepest, 0, kProfileLevel); layers >= kMinLayers; layers /= 2) ++n;
        return n;
    }

    /// None: every factor is 1.
    DensityProfile() = default;
    /// `tree`'s profile: from tree.layerMeans when the build stored them for this profile level,
    /// else measured now (which reads the profile level).
    explicit DensityProfile(const Octree& tree);

    /// Whether `level`'s voxels carry the profile.
    bool profiles(int level) const { return level >= 0 && level < int(mFactor.size()); }
    /// The mean of p over the heights z0 … z1 (reference units, clamped to [0, 1], in either
    /// order) at `level`: the factor by which the optical depth through a voxel of `level`
    /// between those heights differs from the uniform voxel's, for a texel uniform across.
    /// 1 at levels not profiled.
    double meanFactor(int level, double z0, double z1) const;
    /// The factor for the segment a → b (reference units; x and y periodic with the tile, z
    /// clamped to [0, 1]): the mean of p_x·p_y·p over it (exact: a walk through the profile's
    /// columns, in each of which p_x·p_y is constant and p's mean comes from its cumulative
    /// sums); 1 at levels not profiled. A segment longer
    /// than kMaxAcrossTiles tiles across (a grazing ray through one run of a level-0 voxel over
    /// a large field) takes the mean over its first kMaxAcrossTiles tiles: the walk's cost stays
    /// below (kMaxAcrossTiles + 4) times the level's columns, and the factors being periodic, what the
    /// rest of the segment crosses is what its first tiles crossed (exactly so for a segment
    /// along an axis or of small rational slope).
    double meanFactor(int level, const Vec3& a, const Vec3& b) const;
    static constexpr double kMaxAcrossTiles = 64;

    /// The profile of `level` along one line, origin + s·dir (reference units, dir unit):
    /// mean(s0, s1) is meanFactor(level, origin + s0·dir, origin + s1·dir), taken by a walk
    /// through the columns that goes on from where the last call ended. A march asks for its
    /// voxels front to back, so each call walks only the columns its own segment crosses instead
    /// of setting a walk up (floors and divisions) per voxel. An earlier s0, or one more than
    /// kRestartColumns columns ahead, sets the walk up again. 1 at a level not profiled.
    class Line {
    public:
        Line(const DensityProfile& profile, int level, const Vec3& origin, const Vec3& dir);
        double mean(double s0, double s1);
        static constexpr double kRestartColumns = 16;

    private:
        void start(double s);
        bool advanceTo(double s);  ///< false: behind, or too far ahead (start instead)
        std::size_t nextAxis() const { return mNext[0] <= mNext[1] ? 0 : 1; }  ///< whose boundary comes first
        void cross(std::size_t k) {  ///< into the next column along axis k
            mCell[k] += mStep[k];
            mNext[k] += mInc[k];
        }
        double across() const;                         ///< p_x·p_y in the current column
        double heightMean(double s0, double s1) const;  ///< p's mean between the line's heights at s0, s1

        const double* mFactor = nullptr;  ///< p per layer; null: the level is not profiled
        const double* mCumulative = nullptr;  ///< its cumulative sums
        const double* mAcross[2] = {nullptr, nullptr};
        int mLayers = 0;
        Vec3 mOrigin, mDir;
        double mZ0 = 0, mDz = 0;     ///< the line's height at s = 0 and per unit of s, in layers
        std::int64_t mMask = 0;      ///< columns − 1 (a power of two less one)
        double mColumnsPerUnit = 0;  ///< columns crossed per unit of s, x and y together
        double mLongest = 0;         ///< the length of kMaxAcrossTiles tiles across
        std::array<std::int64_t, 2> mCell{};
        std::array<double, 2> mNext{}, mInc{};
        std::array<int, 2> mStep{};
        /// Where the walk stands (the current columns hold it); +∞ before the first call.
        double mAt = std::numeric_limits<double>::infinity();
    };

private:
    explicit DensityProfile(const LayerMeans& means);
    int mLayers = 0;                          ///< 2^(profile level)
    std::vector<std::vector<double>> mFactor;  ///< [level][layer]: p on the layer
    /// [level][k]: ∫ p from z = 0 to the layer boundary k / mLayers, in layer widths (k = 0 … mLayers)
    std::vector<std::vector<double>> mCumulative;
    /// [level][x or y][column]: p_x, p_y on the level's columnsAcross(level) columns
    std::vector<std::array<std::vector<double>, 2>> mAcross;
};

/// The profile level's mean density per layer of each axis (what DensityProfile is made of), at
/// level min(DensityProfile::kProfileLevel, deepest): one descent of the stored nodes, which reads
/// that level. What OctreeBuilder::compress stores in the tree, so that renders need not.
LayerMeans measureLayerMeans(const Octree& tree);

}  // namespace vtex::octree
