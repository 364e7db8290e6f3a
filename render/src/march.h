// The block-skipping march through a sparse octree (see texel_march.h). Header-only so that the
// renderer's per-voxel shading inlines into the loop.
#pragma once

#include <vtex/octree/cursor.h>
#include <vtex/octree/octree.h>
#include <vtex/render/texel_march.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

namespace vtex::render::detail {

/// std::clamp(std::floor(x), −4e15, 4e15) in a few instructions: x86-64's baseline (SSE2) has no
/// rounding instruction, and std::floor compiles to a long sequence there; within ±4e15 every
/// double converts to an int64 exactly. x must not be NaN.
inline double clampedFloor(double x) {
    x = std::clamp(x, -4e15, 4e15);
    const double t = double(std::int64_t(x));
    return t > x ? t - 1 : t;
}

/// Marches p0 + s·dir, s ∈ [0, length] (reference units, dir unit), at `level`, calling
/// visit(node, s0, ds) for every non-empty block in front-to-back order; visit returns false to
/// stop. Returns the number of blocks stepped through (empty ones included). The walk for levels
/// too deep for a dense grid (MarchVolume).
template <class Visit>
std::uint64_t marchBlocks(const octree::Octree& tree, int level, const Eigen::Vector3d& p0,
                          const Eigen::Vector3d& dir, double length, Visit&& visit) {
    if (tree.levels.empty() || tree.levels[0].empty() || !(length > 0)) return 0;
    level = std::clamp(level, 0, std::min(int(tree.levels.size()) - 1, 30));
    tree.loadLevels(std::uint32_t(level));  // a tree opened with openVto reads the level now
    const std::int64_t n = std::int64_t(1) << level;
    const double invN = 1.0 / double(n);
    // Every step looks the block up a little past its entry so that a point on a block face
    // falls in the block ahead; 1e-7 of a voxel is far above double rounding at 2^20 voxels.
    const double nudge = 1e-7 * invN;
    const Eigen::Vector3d invDir(1 / dir.x(), 1 / dir.y(), 1 / dir.z());
    // A line crosses at most (extent·n + 1) voxels per axis; the cap only guards against a
    // pathological loop.
    const double extent = std::abs(dir.x()) * length + std::abs(dir.y()) * length + std::abs(dir.z()) * length;
    const std::uint64_t maxSteps = std::uint64_t(std::min(1e7, 3 * (extent + 3) * double(n) + 64));
    std::uint64_t steps = 0;
    octree::OctreeCursor cursor(tree);
    double s = 0;
    while (s < length && steps < maxSteps) {
        ++steps;
        const double sq = s + std::min(nudge, 0.5 * (length - s));
        const Eigen::Vector3d p = p0 + sq * dir;
        std::int64_t idx[3];
        for (int a = 0; a < 3; ++a) {
            const double f = std::floor(p[a] * double(n));
            idx[a] = std::int64_t(std::clamp(f, -4e15, 4e15));
        }
        idx[2] = std::clamp<std::int64_t>(idx[2], 0, n - 1);
        // n and the block sizes are powers of two: masks instead of (slow) integer divisions;
        // on two's complement, idx & (n − 1) is the non-negative idx mod n.
        const std::uint32_t wx = std::uint32_t(idx[0] & (n - 1));
        const std::uint32_t wy = std::uint32_t(idx[1] & (n - 1));
        const octree::Located found = cursor.locate(level, wx, wy, std::uint32_t(idx[2]));
        const std::int64_t size = std::int64_t(1) << (level - found.blockLevel);
        const std::int64_t base[3] = {idx[0] & ~(size - 1), idx[1] & ~(size - 1), idx[2] & ~(size - 1)};
        double exit = length;
        for (int a = 0; a < 3; ++a) {
            if (dir[a] > 0) exit = std::min(exit, (double(base[a] + size) * invN - p0[a]) * invDir[a]);
            else if (dir[a] < 0) exit = std::min(exit, (double(base[a]) * invN - p0[a]) * invDir[a]);
        }
        if (!(exit > s)) exit = std::min(length, sq);  // rounding: never stand still
        if (!(exit > s)) exit = length;  // within rounding of the end, where sq = s
        if (found.node && !visit(*found.node, s, exit - s)) return steps;
        s = exit;
    }
    return steps;
}

/// Marches p0 + s·dir, s ∈ [0, length] (reference units, dir unit) through a level's dense grid,
/// calling visit(voxel, s0, ds) for every run of consecutive voxels that hold the same stored
/// node, in front-to-back order (a leaf standing for a block is one visit, as in marchBlocks);
/// visit returns false to stop. Returns the number of voxels stepped through (empty ones
/// included; a leap over empty space counts one).
///
/// An Amanatides–Woo walk: each axis's next plane crossing is recomputed from the voxel index
/// (not accumulated), so it is the same expression marchBlocks uses and rounding does not drift.
/// From an empty voxel at empty-space distance d the walk leaps to where the ray leaves the empty
/// (2d−1)³ cube around it, and relocates there.
template <class Visit>
std::uint64_t marchGrid(const LevelGrid& grid, const Eigen::Vector3d& p0, const Eigen::Vector3d& dir, double length,
                        Visit&& visit) {
    if (!(length > 0)) return 0;
    const std::int64_t n = grid.n;
    const std::uint32_t mask = grid.n - 1;
    const double invN = 1.0 / double(n);
    // Locations are taken a little past the point so that a point on a voxel face falls in the
    // voxel ahead; 1e-7 of a voxel is far above double rounding at 2^20 voxels.
    const double nudge = 1e-7 * invN;
    const Eigen::Vector3d invDir(1 / dir.x(), 1 / dir.y(), 1 / dir.z());
    const int step[3] = {dir.x() > 0 ? 1 : dir.x() < 0 ? -1 : 0, dir.y() > 0 ? 1 : dir.y() < 0 ? -1 : 0,
                         dir.z() > 0 ? 1 : dir.z() < 0 ? -1 : 0};
    const double extent = (std::abs(dir.x()) + std::abs(dir.y()) + std::abs(dir.z())) * length;
    const std::uint64_t maxSteps = std::uint64_t(std::min(1e7, 3 * (extent + 3) * double(n) + 64));
    std::int64_t idx[3];
    double next[3];
    // The plane through which the ray leaves voxel idx along axis a.
    const auto planeCrossing = [&](int a) {
        if (step[a] == 0) return std::numeric_limits<double>::infinity();
        const std::int64_t plane = step[a] > 0 ? idx[a] + 1 : idx[a];
        return (double(plane) * invN - p0[a]) * invDir[a];
    };
    const auto locateAt = [&](double s) {
        const Eigen::Vector3d p = p0 + (s + std::min(nudge, 0.5 * (length - s))) * dir;
        for (int a = 0; a < 3; ++a) idx[a] = std::int64_t(clampedFloor(p[a] * double(n)));
        idx[2] = std::clamp<std::int64_t>(idx[2], 0, n - 1);
        for (int a = 0; a < 3; ++a) next[a] = planeCrossing(a);
        // On the top or bottom layer, leaving the grid in z keeps the clamped layer (as
        // marchBlocks does): the segment ends within rounding of it.
        if ((idx[2] == n - 1 && step[2] > 0) || (idx[2] == 0 && step[2] < 0)) next[2] = std::numeric_limits<double>::infinity();
    };
    locateAt(0);
    std::uint64_t steps = 0;
    std::uint32_t run = 0;  // the voxel of the run being walked, 0: none
    double runStart = 0;
    double s = 0;
    while (s < length && steps < maxSteps) {
        ++steps;
        const std::uint32_t cell = grid.cell(std::uint32_t(idx[0]) & mask, std::uint32_t(idx[1]) & mask, std::uint32_t(idx[2]));
        const std::uint32_t voxel = cell & LevelGrid::kEmpty ? 0 : cell;
        if (voxel != run) {
            if (run && !visit(grid.voxels[run], runStart, s - runStart)) return steps;
            run = voxel;
            runStart = s;
        }
        // The axis whose plane comes first, without branches: which axis that is changes from step
        // to step along a diagonal ray, where a conditional jump would be mispredicted often.
        const int a01 = int(!(next[0] <= next[1]));
        const int a = std::min(next[0], next[1]) <= next[2] ? a01 : 2;
        if (!voxel) {
            const std::int64_t d = cell & 0xFFu;
            if (d > 1) {
                // The cube idx ± (d − 1) is empty; z is kept inside the grid, where the walk
                // clamps its index.
                double leap = length;
                for (int b = 0; b < 3; ++b) {
                    if (step[b] > 0) {
                        const std::int64_t plane = b == 2 ? std::min(idx[b] + d, n) : idx[b] + d;
                        leap = std::min(leap, (double(plane) * invN - p0[b]) * invDir[b]);
                    } else if (step[b] < 0) {
                        const std::int64_t plane = b == 2 ? std::max(idx[b] - d + 1, std::int64_t(0)) : idx[b] - d + 1;
                        leap = std::min(leap, (double(plane) * invN - p0[b]) * invDir[b]);
                    }
                }
                if (leap > s && leap > next[a]) {
                    s = leap;
                    if (s < length) locateAt(s);
                    continue;
                }
            }
        }
        if (!(next[a] < length)) {
            s = length;
            break;
        }
        s = std::max(s, next[a]);
        idx[a] += step[a];
        if (a == 2 && (idx[2] == n - 1 || idx[2] == 0)) {
            next[2] = (idx[2] == n - 1 && step[2] > 0) || (idx[2] == 0 && step[2] < 0) ? std::numeric_limits<double>::infinity()
                                                                                        : planeCrossing(2);
        } else {
            next[a] = planeCrossing(a);
        }
    }
    if (run) visit(grid.voxels[run], runStart, std::min(s, length) - runStart);
    return steps;
}

/// What a march of `volume` at `level` multiplies a voxel's extinction by over the segment
/// p0 + s·dir, s ∈ [s0, s0 + ds] (dir unit): the level's density profile's mean factor over the
/// segment (octree::DensityProfile, over its heights and across), 1 on a level whose voxels are
/// uniform. One walk along the line serves a march's calls front to back (DensityProfile::Line).
class ProfileFactor {
public:
    ProfileFactor(const MarchVolume& volume, int level, const Eigen::Vector3d& p0, const Eigen::Vector3d& dir) {
        level = std::clamp(level, 0, std::max(volume.maxLevel(), 0));
        if (const octree::DensityProfile* profile = volume.profile(level))
            mLine.emplace(*profile, level, octree::Vec3(p0), octree::Vec3(dir));
    }
    double operator()(double s0, double ds) { return mLine ? mLine->mean(s0, s0 + ds) : 1.0; }

private:
    std::optional<octree::DensityProfile::Line> mLine;
};

/// The march of `volume` at `level` (clamped to its deepest): through the level's grid, or block
/// by block through the octree beyond the deepest grid. Same contract as marchGrid.
template <class Visit>
std::uint64_t march(const MarchVolume& volume, int level, const Eigen::Vector3d& p0, const Eigen::Vector3d& dir,
                    double length, Visit&& visit) {
    if (volume.maxLevel() < 0) return 0;
    level = std::clamp(level, 0, volume.maxLevel());
    if (const LevelGrid* grid = volume.grid(level)) return marchGrid(*grid, p0, dir, length, visit);
    return marchBlocks(volume.tree(), level, p0, dir, length, [&](const octree::OctreeNode& node, double s, double ds) {
        return visit(gridVoxel(node.data), s, ds);
    });
}

}  // namespace vtex::render::detail
