// The shadows on a flat field's floor from a table per light instead of a ray per floor point
// (docs/render.md, "Shadows"; issue 12's "a per-light volume in reference space shared by all
// cells").
//
// A floor point of a texel cell seen through more than exactFloorShadowAbove casts an exact
// shadow ray: walked cell by cell through the BVH and marched in each, it was a sixth of the
// bush field's middle view. Over a flat field of identical cells (each the translate of the
// others, each showing one whole tile of the same texel, so one reference-space light direction
// and one shadow level for all), the light's path from the floor point (x, y, 0) to the shell's
// top is the straight line through the tiled texel: its transmittance T(x, y) is the same
// function in every cell whose neighbours toward the light are in the field. The table holds T
// on a grid of kPerVoxel × kPerVoxel points a voxel of the shadow level over the tile (periodic),
// each the march of that line, and a floor point takes the optical depth −ln T bilinearly
// interpolated: along the line each voxel's chord is linear in where the line starts, except
// across the starts whose line grazes a voxel's edge, so the depth is piecewise linear and its
// interpolation exact but there (on the bush field the image mean moved by −0.06 %, where
// interpolating T itself, which overestimates T's convex fall across a leaf's shadow, moved it by
// +0.2 %). What lies above the shell (another surface, an opaque object over the field) is still
// walked exactly from where the line leaves the top. The approximation is that interpolation;
// its bounds are the tests FloorShadowTable.* (against the line in a bush, and against the exact
// walk on a field of bushes under a plate) and, on the bush field, the image means.
//
// In a scene of that field alone, where a line that reaches the top has reached the light, the
// camera marches' shadow queries in those cells take a 3-D table too (inside(): the query's own
// voxel exactly, the line's depth beyond it at 2 points a voxel, trilinear) instead of the near
// table and the lattice, which interpolate over a coarser lattice and march its nodes at the
// lattice's level: on the bush field 5 times closer to exact shadow rays (docs/render.md, "Field
// shadow volume").
//
// Which cells may use it is decided before any pixel (floorTableCells, floor_shadow_table.cpp):
// those whose every cell the line can cross is a translate of them with the same table, with no
// primitive of another surface inside the field's bounds. Values are computed on first use, each
// a function of its grid point alone: images do not depend on the tiles' order.
#pragma once

#include <vtex/render/texel_march.h>

#include "cell_adjacency.h"
#include "frame.h"
#include "light_cache.h"
#include "march.h"
#include "near_shadow_table.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace vtex::render::detail {

class FloorShadowTable {
public:
    /// Levels with a table (256² points at 6); finer shadows walk their rays.
    static constexpr int kMaxLevel = 6;
    /// Grid points per voxel of the shadow level, along x and y.
    static constexpr int kPerVoxel = 4;
    /// Levels with a volume table (64 × 64 × 65 points at 5, 1 MiB); finer queries take the near
    /// table and the lattice.
    static constexpr int kMaxVolumeLevel = 5;
    /// The longest reach of the line across the field, in cells along x or y: a lower light
    /// walks its rays.
    static constexpr double kMaxReach = 4;

    /// One table per slot of `slots` (NearShadowTable's: a texel and a reference-space light
    /// direction), its levels allocated on first use.
    explicit FloorShadowTable(std::size_t slots) : mLevels(slots), mVolume(slots) {
        for (auto& s : mLevels)
            for (auto& l : s) l.store(nullptr);
        for (auto& s : mVolume)
            for (auto& l : s) l.store(nullptr);
    }
    ~FloorShadowTable() {
        for (auto& s : mLevels)
            for (auto& l : s) delete[] l.load();
        for (auto& s : mVolume)
            for (auto& l : s) delete[] l.load();
    }
    FloorShadowTable(const FloorShadowTable&) = delete;
    FloorShadowTable& operator=(const FloorShadowTable&) = delete;

    static constexpr std::uint32_t side(int level) { return std::uint32_t(kPerVoxel) << level; }
    /// The memory one light's floor tables may take at most (NearShadowTable::kMaxSlotsPerLight
    /// slots), and its volume tables.
    static constexpr std::uint64_t kBytesPerLight = [] {
        std::uint64_t points = 0;
        for (int l = 0; l <= kMaxLevel; ++l) points += (std::uint64_t(kPerVoxel) << l) * (std::uint64_t(kPerVoxel) << l);
        return std::uint64_t(NearShadowTable::kMaxSlotsPerLight) * points * sizeof(float);
    }();
    static constexpr std::uint64_t kVolumeBytesPerLight = [] {
        std::uint64_t points = 0;
        for (int l = 0; l <= kMaxVolumeLevel; ++l) points += (std::uint64_t(2) << l) * (std::uint64_t(2) << l) * ((std::uint64_t(2) << l) + 1);
        return std::uint64_t(NearShadowTable::kMaxSlotsPerLight) * points * sizeof(float);
    }();

    /// T at tiled reference coordinates (x, y) of the floor (any real x, y: the tile repeats),
    /// for the light direction lr (unit, lr.z() > 0) of slot `slot`, through `volume` at `level`
    /// (≤ kMaxLevel) with extinction factor tau.
    double transmittance(int slot, const MarchVolume& volume, double tau, int level, const Vec3& lr, double x,
                         double y) const {
        const std::uint32_t n = side(level);
        std::atomic<float>* values = claimNanBlock(mLevels[std::size_t(slot)][std::size_t(level)], std::size_t(n) * n);
        const auto wrap = [n](double g, std::uint32_t& i) {
            const double f = std::floor(g);
            i = std::uint32_t(std::int64_t(f) & std::int64_t(n - 1));
            return g - f;
        };
        std::uint32_t i0, j0;
        const double wx = wrap(x * n, i0), wy = wrap(y * n, j0);
        const std::uint32_t i1 = (i0 + 1) & (n - 1), j1 = (j0 + 1) & (n - 1);
        const auto at = [&](std::uint32_t i, std::uint32_t j) {
            return lineDepth(values[std::size_t(j) * n + i], volume, tau, level, lr, Vec3(double(i) / n, double(j) / n, 0));
        };
        return std::exp(-((1 - wx) * (1 - wy) * at(i0, j0) + wx * (1 - wy) * at(i1, j0) + (1 - wx) * wy * at(i0, j1) +
                          wx * wy * at(i1, j1)));
    }

    /// The transmittance toward the light from p0 (tiled reference space, inside the shell) of a
    /// cell of a field with nothing above it (`inverse`: lr's per-component reciprocal): the
    /// query's own voxel of `grid` (level `level`) exactly (ownVoxel with `ownFactor`, as the near
    /// table takes it),
    /// times the line's from where it leaves that voxel to the top: its optical
    /// depth from a 3-D table of 2 points a voxel along x, y and z over the tile (periodic in x and
    /// y), each the march from the point to z = 1 on first use, interpolated trilinearly.
    double inside(int slot, const MarchVolume& volume, const LevelGrid& grid, double tau, int level, const Vec3& lr,
                  const Vec3& inverse, const Vec3& p0, double ownFactor = 1) const {
        const OwnVoxel o =
            ownVoxel(volume, grid, tau, level, p0, lr, inverse, std::numeric_limits<double>::infinity(), ownFactor);
        const double own = o.depth;
        const Vec3 q = p0 + o.exit * lr;
        if (q.z() >= 1) return std::exp(-own);
        const std::uint32_t m = 2u << level;
        std::atomic<float>* values =
            claimNanBlock(mVolume[std::size_t(slot)][std::size_t(level)], std::size_t(m) * m * (m + 1));
        const auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
            const auto x = std::uint32_t(i & std::int64_t(m - 1)), y = std::uint32_t(j & std::int64_t(m - 1));
            const auto z = std::uint32_t(std::clamp<std::int64_t>(k, 0, m));
            return lineDepth(values[(std::size_t(z) * m + y) * m + x], volume, tau, level, lr,
                             Vec3(double(x) / m, double(y) / m, double(z) / m));
        };
        const double gx = q.x() * m, gy = q.y() * m, gz = std::max(q.z(), 0.0) * m;
        const double fx = clampedFloor(gx), fy = clampedFloor(gy), fz = std::min(clampedFloor(gz), double(m - 1));
        const double w[3] = {gx - fx, gy - fy, gz - fz};
        const auto i = std::int64_t(fx), j = std::int64_t(fy), k = std::int64_t(fz);
        double depth = 0;
        for (int c = 0; c < 8; ++c) {
            const double weight = (c & 1 ? w[0] : 1 - w[0]) * (c & 2 ? w[1] : 1 - w[1]) * (c & 4 ? w[2] : 1 - w[2]);
            if (weight > 0) depth += weight * at(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        }
        return std::exp(-(own + depth));
    }

    /// The exact value both tables interpolate: the march from `from` (tiled reference space, in
    /// the shell) along lr to z = 1.
    static double lineTransmittance(const MarchVolume& volume, double tau, int level, const Vec3& lr, const Vec3& from) {
        return marchTransmittance(volume, tau, from, from + ((1 - from.z()) / lr.z()) * lr, level, kCutoff).transmittance;
    }
    /// Below this a line is dark: the march stops (the exact walk's cut-off).
    static constexpr double kCutoff = 1e-4;

private:
    /// A table's entry: the optical depth of the line from `from`, marched the first time it is
    /// asked for (NaN until then; whichever thread marches it writes the same value).
    static double lineDepth(std::atomic<float>& entry, const MarchVolume& volume, double tau, int level, const Vec3& lr,
                            const Vec3& from) {
        float depth = entry.load(std::memory_order_relaxed);
        if (std::isnan(depth)) {
            depth = float(-std::log(std::max(lineTransmittance(volume, tau, level, lr, from), kCutoff)));
            entry.store(depth, std::memory_order_relaxed);
        }
        return double(depth);
    }

    mutable std::vector<std::array<std::atomic<std::atomic<float>*>, kMaxLevel + 1>> mLevels;
    mutable std::vector<std::array<std::atomic<std::atomic<float>*>, kMaxVolumeLevel + 1>> mVolume;
};

/// Whether every primitive of `prims` is a cell of one surface: then nothing lies above a field's
/// shells, and a query that reaches the top has reached the light (FloorShadowTable::inside).
bool oneSurfaceOnly(const PrimTable& prims);

/// Per primitive and lattice slot (`lights` of them, primitive-major, as `nearSlots`), whether a
/// floor point of that cell may take the floor table: see the file's comment.
std::vector<bool> floorTableCells(const PrimTable& prims, const CellAdjacency& adjacency,
                                  const std::vector<SurfaceRuntime>& surfaces, const std::vector<int>& nearSlots,
                                  std::size_t lights, const NearShadowTable& near);

}  // namespace vtex::render::detail
