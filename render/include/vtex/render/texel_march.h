/// @file
/// @brief Inside a texel: the level a ray footprint picks, and the march through the sparse
/// octree at that level.
///
/// Reference space is the unit cube of the texel (x, y across, z up), tiled `repeat` times along
/// x and y inside a cell; a level ℓ has 2^ℓ voxels per side. A stored node with no children
/// stands for all its missing descendants, and a cleared child bit for an empty block, so the
/// march steps over whole blocks (an Amanatides–Woo traversal at the block's size, in double
/// precision). Extinction along the unit reference direction ω is σₜ(ω) = τ ρ Â(ω),
/// Â(ω) = √(ωᵀSω) for the normalised S a node stores (DESIGN.md, "The micro-primitive").
#pragma once

#include <vtex/octree/octree.h>

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace vtex::render {

/// The GigaVoxels cone rule (Crassin, Neyret, Lefebvre, Eisemann 2009): the level whose voxel
/// size 2^−ℓ matches the cone width, ℓ = −log2(width) + ... shifted by `lodBias` (+1: one level
/// coarser) and clamped to [0, maxLevel]; the two nearest integer levels are blended with
/// weights 1 − fineWeight and fineWeight.
struct LevelChoice {
    double level = 0;   ///< the continuous level, after bias and clamping
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

/// Empty-space distances of an octree, for the march to leap over runs of empty voxels: for each
/// level ℓ ≤ kMaxLevel (and ≤ the octree's deepest), 2^ℓ·2^ℓ·2^ℓ bytes, index (z·2^ℓ + y)·2^ℓ + x,
/// each the Chebyshev distance in voxels of that level from the voxel to the nearest non-empty
/// one (x and y periodic, as the texel tiles), capped at kCap: 0 for a non-empty voxel, d ≥ 1
/// when the (2d−1)³ voxels centred on it are all empty. A march that uses them visits the same
/// non-empty blocks over the same intervals, and steps through fewer empty ones.
struct EmptySpace {
    static constexpr int kMaxLevel = 6;
    static constexpr int kCap = 16;
    std::vector<std::vector<std::uint8_t>> levels;
    const std::uint8_t* level(int l) const {
        return l >= 0 && std::size_t(l) < levels.size() && !levels[std::size_t(l)].empty() ? levels[std::size_t(l)].data() : nullptr;
    }
};
EmptySpace emptySpace(const octree::Octree& octree);

/// exp(−∫ τ ρ Â(ω) dL) along the straight reference-space segment from `from` to `to` (x and y
/// wrap modulo 1, z is clamped to [0,1]) through `octree` at `level` (clamped to its deepest).
/// Stops early once the transmittance is below `cutoff`. `empty`, if given, must be
/// emptySpace(octree): the same answer, faster.
SegmentTransmittance marchTransmittance(const octree::Octree& octree, double tau, const Eigen::Vector3d& from,
                                        const Eigen::Vector3d& to, int level, double cutoff = 0,
                                        const EmptySpace* empty = nullptr);

}  // namespace vtex::render
