/// @file
/// @brief What one voxel (or one octree node) stores, and the Morton keys that name voxels.
///
/// A voxel of the reference volume (the unit cube, 2^L voxels per side at level L) holds a
/// density ρ (1/length, reference units), the micro-primitive normalised to unit mean apparent
/// area (DESIGN.md, "The micro-primitive") in the stored form of primitive/packing.h, and a
/// linear-RGB albedo. An empty voxel has ρ = 0 and is never stored.
#pragma once

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/packing.h>
#include <vtex/primitive/sggx.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>

namespace vtex::octree {

// The micro-primitive's maths lives in vtex::primitive; the octree uses it by these names.
using primitive::Ellipsoid;
using primitive::Mat3;
using primitive::Normalization;
using primitive::SggxMatrix;
using primitive::Vec3;

/// The deepest level a Morton key can name: 3·20 = 60 bits, 2^20 voxels per side.
inline constexpr int kMaxLevel = 20;

/// How far along the unit direction `dir` a ray from p (reference space, tiled or not) leaves the
/// voxel of `level` it starts in, at most `limit`: p is located a hair along dir (1e-7 of a
/// voxel), so that a point on a face starts in the voxel the ray enters, as a march locates it.
/// What a shadow query from a lit voxel counts as its own voxel (the renderer's own-leaf share).
inline double voxelExit(const Vec3& p, const Vec3& dir, int level, double limit) {
    const double n = std::ldexp(1.0, level), invN = 1 / n;
    const Vec3 q = p + (1e-7 * invN) * dir;
    double exit = limit;
    for (int a = 0; a < 3; ++a)
        if (dir[a] != 0) {
            const double f = std::floor(q[a] * n);
            exit = std::min(exit, ((dir[a] > 0 ? f + 1 : f) * invN - p[a]) / dir[a]);
        }
    return std::max(exit, 0.0);
}

/// Interleaves the low 20 bits of x, y, z into a Morton key: bit 3i is x's bit i, 3i+1 y's,
/// 3i+2 z's. The 8 children of the node with key k have the keys 8k … 8k+7, child c at
/// (2x + (c&1), 2y + ((c>>1)&1), 2z + (c>>2)), so a node's descendants at any level form one
/// contiguous key range.
std::uint64_t mortonEncode(std::uint32_t x, std::uint32_t y, std::uint32_t z);
/// The inverse of mortonEncode.
std::array<std::uint32_t, 3> mortonDecode(std::uint64_t key);

namespace detail {
/// mortonEncode(i, 0, 0) for i < 256: a key's x bits (bit k of i at bit 3k); its y and z bits are
/// the same shifted by 1 and 2.
inline constexpr std::array<std::uint32_t, 256> kMortonSpread = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i)
        for (std::uint32_t k = 0; k < 8; ++k) t[i] |= ((i >> k) & 1u) << (3 * k);
    return t;
}();
}  // namespace detail

/// mortonEncode(x, y, z) for x, y, z < 256 (levels up to 8), from a table: walks that compute
/// one per step (the renderer's level grids, the chord measures' dense levels) wait less on the
/// table's three loads than on a call that spreads the bits.
inline std::uint32_t mortonEncode8(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return detail::kMortonSpread[x & 255u] | (detail::kMortonSpread[y & 255u] << 1) | (detail::kMortonSpread[z & 255u] << 2);
}

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
inline void packEllipsoid(const Ellipsoid& ellipsoid, VoxelData& voxel) {
    const primitive::PackedPrimitive p = primitive::pack(ellipsoid);
    voxel.rotation = p.rotation;
    voxel.sigma = p.sigma;
}
/// Stores the isotropic primitive (a sphere, S = identity).
inline void packIsotropic(VoxelData& voxel) {
    voxel.rotation = primitive::kIsotropic.rotation;
    voxel.sigma = primitive::kIsotropic.sigma;
}
/// The rotation R a voxel stores (primitive::unpackRotation).
inline Mat3 unpackRotation(const VoxelData& voxel) { return primitive::unpackRotation(voxel.rotation); }
/// The normalised SGGX matrix a voxel stores (primitive::unpackS).
inline SggxMatrix unpackS(const VoxelData& voxel) { return primitive::unpackS(voxel.rotation, voxel.sigma); }
/// The ellipsoid a voxel stores; empty for an empty voxel or a degenerate σ.
inline std::optional<Ellipsoid> unpackEllipsoid(const VoxelData& voxel) {
    if (voxel.isEmpty()) return std::nullopt;
    return primitive::unpackEllipsoid(voxel.rotation, voxel.sigma);
}

}  // namespace vtex::octree
