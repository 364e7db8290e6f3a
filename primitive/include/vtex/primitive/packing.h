/// @file
/// @brief How a voxel stores its micro-primitive in 7 floats, and the one way back to S.
///
/// The primitive is stored as its SGGX matrix in eigen-form, S = R diag(σ²) Rᵀ: R as a unit
/// quaternion (x, y, z, w), w ≥ 0, and the three σ (the projected areas along R's columns). The
/// 6 entries of S in float would not do: a disc's S has in-plane eigenvalues 1e-8 of the largest
/// (the axis-ratio floor squared), below float resolution, so its in-plane shape would be
/// rounding noise; σ keeps them to 7 digits. octree::VoxelData holds these fields.
#pragma once

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/sggx.h>

#include <array>
#include <optional>

namespace vtex::primitive {

/// A primitive as stored: R as a unit quaternion (x, y, z, w), w ≥ 0, and σ along R's columns.
struct PackedPrimitive {
    std::array<float, 4> rotation{0, 0, 0, 1};
    std::array<float, 3> sigma{};
};

/// The ellipsoid (any size: it is normalised to unit mean apparent area, Exact, first) packed.
PackedPrimitive pack(const Ellipsoid& ellipsoid);
/// The ellipsoid with this shape (Ellipsoid::shape, shapeFromS, shapeFromM) packed: pack(Ellipsoid) is
/// this of its shape.
PackedPrimitive pack(const EllipsoidShape& shape);
/// The isotropic primitive: a sphere, S = identity.
inline constexpr PackedPrimitive kIsotropic{{0, 0, 0, 1}, {1, 1, 1}};

/// S = R diag(σ²) Rᵀ in double precision, R from the quaternion divided by its norm (a file's
/// quaternion is unit only to 1e-3, a float one to ~1e-7); zero for a zero quaternion. The one
/// conversion from the stored form: what the octree filters, the compression compares and the
/// renderer marches.
SggxMatrix unpackS(const std::array<float, 4>& rotation, const std::array<float, 3>& sigma);
/// The rotation R of a stored quaternion (x, y, z, w), normalised; zero for a zero quaternion.
Mat3 unpackRotation(const std::array<float, 4>& rotation);
/// The ellipsoid of unpackS (Ellipsoid::fromS); empty for a degenerate σ.
std::optional<Ellipsoid> unpackEllipsoid(const std::array<float, 4>& rotation, const std::array<float, 3>& sigma);

}  // namespace vtex::primitive
