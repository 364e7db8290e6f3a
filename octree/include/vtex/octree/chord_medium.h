/// @file
/// @brief What the chord measures walk (chord_transmittance.h): a tree's levels with their
/// density profile, each level up to kMaxDenseLevel kept as a dense array of voxels while the
/// measures run, so that a step of a walk reads one entry instead of descending the octree.
///
/// The load's chord walks were bound by those descents' memory reads (a node's density loaded at
/// every level of every step: a third of the bush field's far render process,
/// docs/error-vs-time.md, "The load's chord walks"). Every measure takes a ChordMedium; an Octree
/// converts to one built for that call, and a caller with several measures of one tree (the
/// renderer's load) builds one and passes it to each, so that they share its levels.
#pragma once

#include <vtex/octree/cursor.h>
#include <vtex/octree/density_profile.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/voxel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

namespace vtex::octree {

/// A voxel's extinction per unit length along the unit direction w, before τ: ρ·Â(w).
inline double voxelExtinction(const OctreeNode& node, const Vec3& w) {
    return double(node.data.density) * unpackS(node.data).projectedArea(w);
}

class ChordMedium {
public:
    /// Levels up to this one are dense arrays (1 MiB of cells at level 6); deeper ones are walked
    /// through the octree, the same steps and the same values. Level 7 too (8 MiB, and the
    /// 20 000-leaf bush's level-7 nodes unpacked while the other thread waits) made that bush's
    /// load slower than without any dense level (docs/error-vs-time.md, "The load's chord walks").
    static constexpr std::uint32_t kMaxDenseLevel = 6;

    /// Not explicit: a measure given an Octree walks it through a medium of its own.
    ChordMedium(const Octree& tree);  // NOLINT(google-explicit-constructor)
    ~ChordMedium();

    const Octree& tree() const { return mTree; }
    const DensityProfile& profile() const { return mProfile; }

    /// visit(ρ·Â(w), t0, t1) for the non-empty voxels of `level` the segment a → b crosses, front
    /// to back, as forEachVoxelOnSegment visits them (w the segment's direction; the profile's
    /// factor is the caller's); visit returns false to stop.
    template <class Visit>
    void forEachVoxel(std::uint32_t level, const Vec3& a, const Vec3& b, Visit&& visit) const;

    /// The optical depth ∫ρÂ of a → b at `level`, the profiled levels' voxels varying as the
    /// profile says.
    double depth(std::uint32_t level, const Vec3& a, const Vec3& b) const;

private:
    /// A stored node's ρ and S as voxelExtinction takes them (unpackS: the same values as
    /// unpacking the node at every visit), kept so that a visit unpacks nothing.
    struct Voxel {
        primitive::SggxMatrix s;
        double density;
    };
    /// One level as a dense array in Morton order (the voxels a chord crosses are near each
    /// other in memory): cells[mortonEncode8(x, y, z)] is the index + 1 of the voxel's stored
    /// node (itself or a leaf above) in `voxels`, 0 for empty space.
    struct Dense {
        std::vector<std::uint32_t> cells;
        std::vector<Voxel> voxels;
    };
    /// Level `level` (≤ kMaxDenseLevel, which the tree has) as a dense array, built on first use.
    const Dense& dense(std::uint32_t level) const;

    const Octree& mTree;
    DensityProfile mProfile;
    mutable std::array<std::once_flag, kMaxDenseLevel + 1> mBuilt;
    mutable std::array<std::unique_ptr<Dense>, kMaxDenseLevel + 1> mDense;
};

namespace detail {
/// The Amanatides–Woo walk of forEachVoxelOnSegment, each voxel's node asked of `lookup(x, y, z)`
/// (a pointer, null for empty space) and passed to visit(node, t0, t1) → bool (false: stop).
template <class Lookup, class Visit>
void walkVoxels(std::uint32_t level, const Vec3& a, const Vec3& b, Lookup&& lookup, Visit&& visit) {
    const double n = double(std::uint64_t(1) << level);
    const Vec3 delta = b - a;
    const double length = delta.norm();
    if (!(length > 0) || !a.allFinite() || !b.allFinite()) return;
    const Vec3 w = delta / length;
    std::array<std::int64_t, 3> cell, step;
    std::array<double, 3> next, inc;
    for (int k = 0; k < 3; ++k) {
        const double p = std::clamp(a[k] * n, 0.0, n - 1e-9);
        cell[std::size_t(k)] = std::int64_t(p);
        step[std::size_t(k)] = w[k] > 0 ? 1 : -1;
        const bool moves = std::abs(w[k]) > 1e-300;
        inc[std::size_t(k)] =
            moves ? 1 / (std::abs(w[k]) * n) : std::numeric_limits<double>::infinity();
        const double boundary =
            w[k] > 0 ? double(cell[std::size_t(k)] + 1) : double(cell[std::size_t(k)]);
        next[std::size_t(k)] =
            moves ? (boundary / n - a[k]) / w[k] : std::numeric_limits<double>::infinity();
    }
    const std::int64_t last = std::int64_t(n) - 1;
    double t = 0;
    while (t < length) {
        const std::size_t k = next[0] <= next[1] && next[0] <= next[2] ? 0
                              : next[1] <= next[2]                     ? 1
                                                                       : 2;
        const double t1 = std::min(next[k], length);
        if (const auto* node = lookup(cell[0], cell[1], cell[2]); node && !visit(*node, t, t1))
            return;
        t = t1;
        cell[k] += step[k];
        next[k] += inc[k];
        if (cell[k] < 0 || cell[k] > last) break;
    }
}

/// Whether `tree` has `level`, which a tree opened with openVto reads now if need be.
inline bool readLevel(const Octree& tree, std::uint32_t level) {
    tree.loadLevels(level);
    return !tree.levels.empty() && !tree.levels[0].empty() && level < tree.levels.size();
}

/// walkVoxels through the octree itself, each voxel's node located by an OctreeCursor
/// (forEachVoxelOnSegment's walk, and ChordMedium's past its dense levels); nothing for a
/// level the tree does not have.
template <class Visit>
void walkOctree(const Octree& tree, std::uint32_t level, const Vec3& a, const Vec3& b, Visit&& visit) {
    if (!readLevel(tree, level)) return;
    OctreeCursor cursor(tree);
    walkVoxels(
        level, a, b,
        [&](std::int64_t x, std::int64_t y, std::int64_t z) {
            return cursor.locate(int(level), std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)).node;
        },
        visit);
}

}  // namespace detail

template <class Visit>
void ChordMedium::forEachVoxel(std::uint32_t level, const Vec3& a, const Vec3& b,
                               Visit&& visit) const {
    const Vec3 w = (b - a).normalized();
    if (level > kMaxDenseLevel) {
        detail::walkOctree(mTree, level, a, b, [&](const OctreeNode& node, double t0, double t1) {
            return visit(voxelExtinction(node, w), t0, t1);
        });
        return;
    }
    if (!detail::readLevel(mTree, level)) return;
    const Dense& grid = dense(level);
    detail::walkVoxels(
        level, a, b,
        [&](std::int64_t x, std::int64_t y, std::int64_t z) -> const Voxel* {
            const std::uint32_t c =
                grid.cells[mortonEncode8(std::uint32_t(x), std::uint32_t(y), std::uint32_t(z))];
            return c ? &grid.voxels[c - 1] : nullptr;
        },
        [&](const Voxel& voxel, double t0, double t1) {
            return visit(voxel.density * voxel.s.projectedArea(w), t0, t1);
        });
}

}  // namespace vtex::octree
