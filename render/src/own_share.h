// How much of a voxel's matter belongs to the surface a shadow query leaves (issue 12's
// self-shadowing; docs/render.md, "A lit voxel's own leaf").
//
// A camera march lights a voxel by a shadow query from inside it; the volume spreads every leaf
// of the voxel over the voxel, the one being lit included, so the query's first stretch is
// attenuated by the very leaf it lights. On the mesh a lit point's shadow ray never meets its
// own convex surface piece (a flat leaf, a disc, a box). What the volume should take off is that
// piece's share of the voxel's matter; a query does not know which piece it stands for, so the
// renderer takes off the expected share over the points a voxel stands for:
//
//     s_L = Σ_v Σ_c a_vc² / A_v  /  Σ_v A_v,
//
// a_vc the area of connected component c inside voxel v of level L, A_v = Σ_c a_vc: the mean,
// over surface points drawn uniformly by area, of the fraction of their voxel's area that lies
// on their own component. A component is a set of triangles joined by shared corners (corners
// at the same position count as shared, so a mesh whose faces were split for their normals
// keeps its pieces whole). Area stands for matter here because the sampler's density is the
// surface's projected area per volume (Neyret 1994, §4.1), averaged over directions.
//
// What it leaves out: a non-convex component can shadow itself (a branch's twig, a bent hair),
// which this takes off all the same; and a piece that straddles a voxel face still shadows
// from the neighbouring voxel, which this leaves in (only the query's own voxel is corrected).
#pragma once

#include <vector>

namespace vtex::render::detail {

class SourceBvh;

/// s_L for levels 0 … finestLevel (clamped to [0, kMaxOwnShareLevel]) of the source mesh placed
/// in the unit cube as the sampler placed it (wrapped in x and y when the volume is cyclic), by
/// exact clipping of its triangles to each level's voxels. A mesh without area gives 0 at every
/// level. Deterministic.
std::vector<double> measureOwnShares(const SourceBvh& source, int finestLevel);

/// The finest level measured: the voxel's coordinates at 10 bits each pack into one word with
/// the component's index.
inline constexpr int kMaxOwnShareLevel = 10;

}  // namespace vtex::render::detail
