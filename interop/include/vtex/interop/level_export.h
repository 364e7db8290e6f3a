/// @file
/// @brief One level of a texel's octree as other tools take it: constant cubes of voxels, each
/// with the values a volume renderer reads (docs/export.md).
///
/// Level ℓ of the reference volume (the unit cube) has 2^ℓ voxels per side. At an exported level
/// L, a stored node of level L is one voxel; a stored leaf of a coarser level ℓ < L (a node with
/// no children: it stands for every descendant, octree.h) is a constant cube of 2^(L−ℓ) voxels
/// per side. Nothing else is non-empty, so these cubes are exactly the voxels that
/// Octree::expandLevel(L) lists, without replicating the leaves.
#pragma once

#include <vtex/octree/octree.h>

#include <array>
#include <cstdint>
#include <vector>

namespace vtex::interop {

/// A constant cube of voxels of the exported level.
struct LevelBlock {
    std::array<std::uint32_t, 3> origin{};  ///< its first voxel, voxel indices at the exported level
    std::uint32_t size = 1;                 ///< voxels per side, 2^(exported level − storedLevel)
    std::uint32_t storedLevel = 0;          ///< the level of the stored node it comes from
    const octree::VoxelData* data = nullptr;  ///< the node's values (points into the octree)
};

/// The constant cubes that make up `level` (≤ octree.levelCount() − 1), in level order then the
/// stored (Morton) order. Walks the stored levels through firstChild/childMask; empty nodes (the
/// empty root of an empty volume) are left out. Throws std::out_of_range for a level the octree
/// does not have.
std::vector<LevelBlock> levelBlocks(const octree::Octree& octree, std::uint32_t level);

/// The six entries of a voxel's SGGX matrix S = R diag(σ²) Rᵀ (normalised to unit mean projected
/// area, reference axes), in the order xx, yy, zz, xy, xz, yz (Heitz et al. 2015's S_xx … S_yz).
std::array<double, 6> sggxEntries(const octree::VoxelData& voxel);

/// The names of sggxEntries' entries, for grid names: "xx", "yy", "zz", "xy", "xz", "yz".
inline constexpr std::array<const char*, 6> kSggxEntryNames{"xx", "yy", "zz", "xy", "xz", "yz"};

}  // namespace vtex::interop
