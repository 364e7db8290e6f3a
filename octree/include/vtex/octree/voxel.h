/// @file
/// @brief What one voxel (or one octree node) stores, and the Morton keys that name voxels.
///
/// A voxel of the reference volume (the unit cube, 2^L voxels per side at level L) holds a
/// density ρ (1/length, reference units), the micro-primitive normalised to unit mean apparent
/// area (DESIGN.md, "The micro-primitive") and a linear-RGB albedo. The primitive is stored as
/// its SGGX matrix in eigen-form, S = R diag(σ²) Rᵀ: R as a unit quaternion and the three σ
/// (the projected areas along the axes). The 6 entries of S in float would not do: a disc's S
/// has in-plane eigenvalues 1e-8 of the largest (the axis-ratio floor squared), below float
/// resolution, so its in-plane shape would be rounding noise; σ keeps them to 7 digits. An empty
/// voxel has ρ = 0 and is never stored.
#pragma once

#include <vtex/octree/ellipsoid.h>

#include <array>
#include <cstdint>
#include <optional>

namespace vtex::octree {

/// The deepest level a Morton key can name: 3·20 = 60 bits, 2^20 voxels per side.
inline constexpr int kMaxLevel = 20;

/// Interleaves the low 20 bits of x, y, z into a Morton key: bit 3i is x's bit i, 3i+1 y's,
/// 3i+2 z's. The 8 children of the node with key k have the keys 8k … 8k+7, child c at
/// (2x + (c&1), 2y + ((c>>1)&1), 2z + (c>>2)), so a node's descendants at any level form one
/// contiguous key range.
std::uint64_t mortonEncode(std::uint32_t x, std::uint32_t y, std::uint32_t z);
/// The inverse of mortonEncode.
std::array<std::uint32_t, 3> mortonDecode(std::uint64_t key);

/// One voxel or node. Plain data; 44 bytes.
struct VoxelData {
    float density = 0;  ///< ρ, 1/length in reference units; 0 = empty
    /// The axes R of the primitive as a unit quaternion (x, y, z, w), w ≥ 0.
    std::array<float, 4> rotation{0, 0, 0, 1};
    /// σ along R's columns: S = R diag(σ²) Rᵀ, normalised (Exact) to unit mean apparent area.
    /// Zero for an empty voxel.
    std::array<float, 3> sigma{};
    std::array<float, 3> albedo{};  ///< linear RGB

    bool isEmpty() const { return density == 0; }
    friend bool operator==(const VoxelData&, const VoxelData&) = default;
};

/// Stores an ellipsoid (any size: it is normalised first) into `voxel`'s rotation and sigma.
void packEllipsoid(const Ellipsoid& ellipsoid, VoxelData& voxel);
/// The ellipsoid a voxel stores; empty for an empty voxel or a degenerate σ.
std::optional<Ellipsoid> unpackEllipsoid(const VoxelData& voxel);
/// The SGGX matrix S = R diag(σ²) Rᵀ a voxel stores (double precision).
Mat3 unpackS(const VoxelData& voxel);
/// The rotation R a voxel stores (its quaternion normalised; zero for a zero quaternion).
Mat3 unpackRotation(const VoxelData& voxel);
/// Stores the isotropic primitive (a sphere, S = identity).
void packIsotropic(VoxelData& voxel);

}  // namespace vtex::octree
