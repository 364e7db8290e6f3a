/// @file
/// @brief Inside a texel: the level a ray footprint picks, and the march through the sparse
/// octree at that level.
///
/// Reference space is the unit cube of the texel (x, y across, z up), tiled `repeat` times along
/// x and y inside a cell; a level ℓ has 2^ℓ voxels per side. A stored node with no children
/// stands for all its missing descendants, and a cleared child bit for an empty block. A march
/// walks a level voxel by voxel (Amanatides–Woo, double precision) through a dense grid of that
/// level (MarchVolume), leaping over empty space. Extinction along the unit reference direction ω is σₜ(ω) = τ ρ Â(ω),
/// Â(ω) = √(ωᵀSω) for the normalised S a node stores (DESIGN.md, "The micro-primitive").
#pragma once

#include <vtex/octree/octree.h>
#include <vtex/octree/density_profile.h>
#include <vtex/octree/voxel.h>
#include <vtex/primitive/sggx.h>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace vtex::render {

/// The GigaVoxels cone rule (Crassin, Neyret, Lefebvre, Eisemann 2009): the level whose voxel
/// size 2^−ℓ matches the cone width, ℓ = −log2(width) + ... shifted by `lodBias` (+1: one level
/// coarser) and clamped to [0, maxLevel]; the two nearest integer levels are blended with
/// weights 1 − fineWeight and fineWeight.
struct LevelChoice {
    double level = 0;   ///< the continuous level, after bias and clamping
    /// The continuous level after bias, before clamping (+∞ for a zero width): how much finer
    /// than the deepest level the footprint is, for the mesh/volume switch.
    double requested = 0;
    int coarse = 0;     ///< floor(level)
    int fine = 0;       ///< coarse + 1, or coarse at maxLevel
    double fineWeight = 0;
};
/// `width`: the cone's width in reference units (> 0; 0 or non-finite picks maxLevel or 0).
LevelChoice chooseLevel(double width, double lodBias, int maxLevel);

struct SegmentTransmittance {
    double transmittance = 1;
    std::uint64_t blocks = 0;  ///< octree blocks stepped through
};

/// One voxel's data as a march reads it: the octree node's, with S unpacked once
/// (octree::unpackS, kept in double precision: the same values as unpacking it at every visit)
/// so that a march does not rebuild it from the quaternion at every visit. 64 bytes, a cache line.
struct GridVoxel {
    primitive::SggxMatrix s;
    float density = 0;  ///< ρ; 0 only for the empty sentinel
    std::array<float, 3> albedo{};

    /// The extinction along the unit direction w, σ(w) = τ ρ √(wᵀSw) (the projected area of the
    /// voxel's ellipsoid; DESIGN.md, "Rendering"): what every march of the voxel multiplies its
    /// lengths by, camera and shadow alike.
    double extinction(double tau, const Eigen::Vector3d& w) const { return tau * double(density) * s.projectedArea(w); }
};
GridVoxel gridVoxel(const octree::VoxelData& data);

/// Level ℓ (≤ 8) of a texel as a dense grid, for marching it with a plain voxel walk instead of
/// descending the octree at every step. One 32-bit cell per voxel, in Morton (Z) order so that
/// the voxels a ray crosses are near each other in memory (the walk waits on these loads): a
/// non-empty voxel's cell is an index ≥ 1 into `voxels`, one entry per stored node that stands
/// for voxels of level ℓ (itself, or a leaf above), voxels[0] unused; an empty voxel's cell is
/// kEmpty | d, d its empty-space distance: the Chebyshev distance in voxels to the nearest
/// non-empty voxel of the level (x and y periodic, as the texel tiles), capped at kCap, so that
/// the (2d−1)³ voxels centred on it are all empty.
struct LevelGrid {
    static constexpr int kCap = 16;
    static constexpr std::uint32_t kEmpty = 0x80000000u;
    static constexpr int kMaxLevel = 8;
    int level = 0;
    std::uint32_t n = 1;
    std::vector<std::uint32_t> cells;
    std::vector<GridVoxel> voxels;

    /// octree::mortonEncode(x, y, z) for x, y, z < 256 (octree::mortonEncode8).
    static std::uint32_t morton(std::uint32_t x, std::uint32_t y, std::uint32_t z) { return octree::mortonEncode8(x, y, z); }
    std::uint32_t cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) const { return cells[morton(x, y, z)]; }
    /// The empty-space distance at a voxel (0 when it is not empty).
    int distance(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
        const std::uint32_t c = cell(x, y, z);
        return c & kEmpty ? int(c & 0xFFu) : 0;
    }
};

/// A texel's octree prepared for marching. Levels up to `maxGridLevel` are marched as dense
/// LevelGrids, each built the first time a march asks for it (thread-safe; a render builds only
/// the levels its rays use); deeper levels, whose grids would be too large (8^ℓ cells), are
/// marched through the octree itself, block by block. Both walks visit the same voxels.
class MarchVolume {
public:
    static constexpr int kDefaultMaxGridLevel = LevelGrid::kMaxLevel;  ///< 64 MiB of cells at 256³
    explicit MarchVolume(std::shared_ptr<const octree::Octree> tree, int maxGridLevel = kDefaultMaxGridLevel);
    ~MarchVolume();
    MarchVolume(const MarchVolume&) = delete;
    MarchVolume& operator=(const MarchVolume&) = delete;

    const octree::Octree& tree() const { return *mTree; }
    int maxLevel() const { return mMaxLevel; }
    /// Level ℓ's grid (built now if need be), or null beyond maxGridLevel or the octree's depth.
    const LevelGrid* grid(int level) const;
    /// The density profile of level ℓ's voxels (octree::DensityProfile; measured now if need
    /// be), or null where the level's voxels are uniform: every march multiplies a voxel's
    /// extinction over a segment by the profile's mean factor over the segment.
    const octree::DensityProfile* profile(int level) const {
        return level >= 0 && level < mProfiledLevels ? measuredProfile(level) : nullptr;
    }

private:
    struct Slot;
    struct ProfileSlot;
    const octree::DensityProfile* measuredProfile(int level) const;
    std::shared_ptr<const octree::Octree> mTree;
    int mProfiledLevels = 0;  ///< levels that may carry a profile (an upper bound, known before it is measured)
    std::unique_ptr<ProfileSlot> mProfile;
    int mMaxLevel = -1;
    int mMaxGridLevel = 0;
    std::unique_ptr<Slot[]> mSlots;
};

/// exp(−∫ τ ρ Â(ω) dL) along the straight reference-space segment from `from` to `to` (x and y
/// wrap modulo 1, z is clamped to [0,1]) through `volume` at `level` (clamped to its deepest).
/// Stops early once the transmittance is below `cutoff`. `ownFactor` scales the density of the
/// voxel `from` lies in, up to where the segment leaves it (a camera march's shadow query takes
/// off the share of the surface piece it lights: TexelRuntime::ownDepthFactor).
SegmentTransmittance marchTransmittance(const MarchVolume& volume, double tau, const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to, int level, double cutoff = 0, double ownFactor = 1);

}  // namespace vtex::render
