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
// Which cells may use it is decided before any pixel (floorTableCells, floor_shadow_table.cpp):
// those whose every cell the line can cross is a translate of them with the same table, with no
// primitive of another surface inside the field's bounds. Values are computed on first use, each
// a function of its grid point alone: images do not depend on the tiles' order.
#pragma once

#include <vtex/render/texel_march.h>

#include "cell_adjacency.h"
#include "frame.h"
#include "light_cache.h"
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
    /// The longest reach of the line across the field, in cells along x or y: a lower light
    /// walks its rays.
    static constexpr double kMaxReach = 4;

    /// One table per slot of `slots` (NearShadowTable's: a texel and a reference-space light
    /// direction), its levels allocated on first use.
    explicit FloorShadowTable(std::size_t slots) : mLevels(slots) {
        for (auto& s : mLevels)
            for (auto& l : s) l.store(nullptr);
    }
    ~FloorShadowTable() {
        for (auto& s : mLevels)
            for (auto& l : s) delete[] l.load();
    }
    FloorShadowTable(const FloorShadowTable&) = delete;
    FloorShadowTable& operator=(const FloorShadowTable&) = delete;

    static constexpr std::uint32_t side(int level) { return std::uint32_t(kPerVoxel) << level; }
    /// The memory one light's tables may take at most (NearShadowTable::kMaxSlotsPerLight slots).
    static constexpr std::uint64_t kBytesPerLight = [] {
        std::uint64_t points = 0;
        for (int l = 0; l <= kMaxLevel; ++l) points += (std::uint64_t(kPerVoxel) << l) * (std::uint64_t(kPerVoxel) << l);
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
            std::atomic<float>& v = values[std::size_t(j) * n + i];
            float t = v.load(std::memory_order_relaxed);
            if (std::isnan(t)) {
                const double line = lineTransmittance(volume, tau, level, lr, double(i) / n, double(j) / n);
                t = float(-std::log(std::max(line, kCutoff)));
                v.store(t, std::memory_order_relaxed);
            }
            return double(t);
        };
        return std::exp(-((1 - wx) * (1 - wy) * at(i0, j0) + wx * (1 - wy) * at(i1, j0) + (1 - wx) * wy * at(i0, j1) +
                          wx * wy * at(i1, j1)));
    }

    /// The exact value the table interpolates: the march from (x, y, 0) along lr to z = 1.
    static double lineTransmittance(const MarchVolume& volume, double tau, int level, const Vec3& lr, double x,
                                    double y) {
        const Vec3 from(x, y, 0);
        return marchTransmittance(volume, tau, from, from + (1 / lr.z()) * lr, level, kCutoff).transmittance;
    }
    /// Below this a line is dark: the march stops (the exact walk's cut-off).
    static constexpr double kCutoff = 1e-4;

private:
    mutable std::vector<std::array<std::atomic<std::atomic<float>*>, kMaxLevel + 1>> mLevels;
};

/// Per primitive and lattice slot (`lights` of them, primitive-major, as `nearSlots`), whether a
/// floor point of that cell may take the floor table: see the file's comment.
std::vector<bool> floorTableCells(const PrimTable& prims, const CellAdjacency& adjacency,
                                  const std::vector<SurfaceRuntime>& surfaces, const std::vector<int>& nearSlots,
                                  std::size_t lights, const NearShadowTable& near);

}  // namespace vtex::render::detail
