/// @file
/// @brief Filtering a weighted set of micro-primitives into one, and measuring what it loses.
///
/// Neyret 1994 §3.3: the parent of a set of ellipsoids is the ellipsoid whose normal
/// distribution is closest to the weighted sum of theirs. Neither rule below is exact
/// (DESIGN.md, "Octree: filtering and compression"); filterError() measures each.
#pragma once

#include <vtex/core/enum_names.h>
#include <vtex/octree/voxel.h>

#include <optional>
#include <span>
#include <vector>

namespace vtex::octree {

enum class FilterRule {
    Neyret,  ///< the paper's: weighted mean of M = Q⁻¹ of each child normalised by the
             ///< three-axis mean area; invents normals no child has (crossed discs gain area
             ///< along their common line, crossed fibres collapse to a disc)
    Sggx     ///< weighted mean of S of each child normalised by its exact mean area; keeps
             ///< zero-area directions at zero but overestimates the area along each child's
             ///< normal (√2 for two orthogonal planes)
};
/// "neyret", "sggx": `vtex build --filter`, a pipeline texel's `filter`, the .vto header.
inline constexpr EnumNames<FilterRule, 2> kFilterRuleNames{{{{FilterRule::Neyret, "neyret"}, {FilterRule::Sggx, "sggx"}}}};

/// The filtered primitive of `children` weighted by `weights` (densities, ≥ 0), normalised
/// to unit mean apparent area (Exact). Children of zero weight are ignored; empty when the
/// total weight is zero. Sizes must match.
std::optional<Ellipsoid> filterEllipsoids(std::span<const Ellipsoid> children,
                                          std::span<const double> weights, FilterRule rule);

/// The same rule on the children's matrices: `forms[i]` is child i's S normalised to unit
/// exact mean area (Sggx) or its M normalised by the three-axis mean area (Neyret), as
/// filterEllipsoids forms them or storedFilterForm reads them from a voxel.
std::optional<Ellipsoid> filterForms(std::span<const Mat3> forms, std::span<const double> weights,
                                     FilterRule rule);
/// What packEllipsoid stores of filterForms(forms, weights, rule), to the bit, without building
/// the Ellipsoid (its cached forms, checks and copies were an eighth of the octree filter's
/// instructions): the build keeps the Ellipsoid only for the nodes whose filter error it measures.
std::optional<primitive::PackedPrimitive> filterFormsPacked(std::span<const Mat3> forms,
                                                            std::span<const double> weights, FilterRule rule);
/// The weighted mean of `forms` that both rules start from; empty for no positive weight.
std::optional<Mat3> meanFilterForm(std::span<const Mat3> forms, std::span<const double> weights);
/// filterFormsPacked with the Sggx rule for several parents at once, from the means
/// meanFilterForm made of their forms: out[i] is what it gives for means[i], to the bit (the
/// exact mean areas computed together: Ellipsoid::shapesFromS).
void packSggxMeans(std::span<const Mat3> means, std::span<std::optional<primitive::PackedPrimitive>> out);

/// The matrix `rule` averages for a stored voxel, read from its eigen-form (R, σ) without
/// rebuilding its Ellipsoid: the octree build's per-child cost. For Sggx it takes the stored
/// normalisation as exact: packEllipsoid normalises before rounding σ to float, so the
/// unpacked primitive's exact mean area is 1 within float rounding (bounded at 1e-6 by
/// Filtering.StoredFormsGiveTheParentTheEllipsoidsGive and, on the bush's voxels, by
/// Sampler.BushParentsAreTheFilterOfTheirChildrenRebuiltAsEllipsoids). Empty for an empty voxel or a zero σ.
std::optional<Mat3> storedFilterForm(const VoxelData& voxel, FilterRule rule);

/// A fixed, deterministic set of unit directions spread evenly over the sphere (a spherical
/// Fibonacci lattice), each standing for 4π/size() steradians.
inline constexpr std::size_t kDefaultSphericalPoints = 512;
std::span<const Vec3> sphericalPointSet(std::size_t count = kDefaultSphericalPoints);

/// The filter error of `result`: the L2 distance over the sphere, ‖f̂_result − Σwᵢf̂ᵢ/Σwᵢ‖₂
/// estimated on `points`, between the normalised normal distribution f̂ = f/Ā of the result
/// and the weighted mixture of the children's. 0 when the rule is exact; the normalised NDF of
/// a sphere has norm 2/√π ≈ 1.13 for scale. Peaks narrower than the point spacing (discs and
/// needles near the ratio floor) are sampled, not integrated: compare errors on one point set.
double filterError(const Ellipsoid& result, std::span<const Ellipsoid> children,
                   std::span<const double> weights,
                   std::span<const Vec3> points = sphericalPointSet());

/// How well an ellipsoid fitted by Ellipsoid::fitNormals summarises its facets: the relative
/// L2 error over `points` between the fit's projected area and the facets' mean projected
/// area Σwₜ|ω·nₜ| / Σwₜ. 0 for the facets of one ellipsoid, a disc or a fibre.
double fitError(const Ellipsoid& fit, std::span<const Vec3> normals, std::span<const double> weights,
                std::span<const Vec3> points = sphericalPointSet());

}  // namespace vtex::octree
