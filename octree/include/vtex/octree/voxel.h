/// @file
/// @brief What one voxel (or one octree node) stores, and the Morton keys that name voxels.
///
/// A voxel of the reference volume (the unit cube, 2^L voxels per side at level L) holds a
/// density ρ (1/length, reference units), the micro-primitive as its SGGX matrix S normalised to
/// unit mean apparent area (DESIGN.md, "The micro-primitive"), and a linear-RGB albedo. S is
/// symmetric, so 6 floats suffice; docs/formats.md gives the order. An empty voxel has ρ = 0 and
/// is never stored.
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

/// One voxel or node. Plain data; 40 bytes.
struct VoxelData {
    float density = 0;  ///< ρ, 1/length in reference units; 0 = empty
    /// The SGGX matrix of the micro-primitive, normalised (Exact) to unit mean apparent area:
    /// Sxx, Syy, Szz, Sxy, Sxz, Syz. All zero for an empty voxel.
    std::array<float, 6> s{};
    std::array<float, 3> albedo{};  ///< linear RGB

    bool isEmpty() const { return density == 0; }
    friend bool operator==(const VoxelData&, const VoxelData&) = default;
};

/// Packs a symmetric matrix into the 6-float order of VoxelData::s.
std::array<float, 6> packSymmetric(const Mat3& m);
/// Unpacks VoxelData::s.
Mat3 unpackSymmetric(const std::array<float, 6>& s);
/// The normalised S of an ellipsoid (any size), packed.
std::array<float, 6> packEllipsoid(const Ellipsoid& ellipsoid);
/// The ellipsoid a voxel stores; empty for an empty voxel or a degenerate S.
std::optional<Ellipsoid> unpackEllipsoid(const VoxelData& voxel);

/// The normalised S of an isotropic primitive (a sphere): the identity.
std::array<float, 6> isotropicS();

}  // namespace vtex::octree
