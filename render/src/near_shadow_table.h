// The first stretch of a shadow query toward a directional light, from a table per voxel instead
// of a march per query (docs/render.md, "Shadows"; issue 12's "a per-light volume in reference
// space shared by all cells").
//
// A shadow query inside a texel cell marches the first kExactLatticeSteps lattice steps toward
// the light exactly (ShadowQueries::nearAndCachedShadow), about half a tile: on the bush field's
// middle view those marches were a fifth of the render, and most of them crossed the same voxels
// as the query of the neighbouring pixel. For a cell that shows exactly one tile of its texel
// (the cell's sides are the tile's), with a constant Jacobian (so one reference-space light
// direction for the whole cell), what such a march meets depends only on where it starts in the
// tile. The table holds, per voxel of the shadow level and per face of it toward the light, the
// transmittances of that march from 3×3 points of the face: a query takes its own voxel's share
// exactly (from where it stands to the face it leaves by) and the rest interpolated at the point
// where it leaves. The approximation is that interpolation (and, where the stretch's length ends
// the march, its last voxel's chord at the entry's end extinction); its bounds are the tests
// NearShadowTable.* and, on the bush field, the image means (within 0.02 % of the marches').
//
// Cells share a table when they share the texel and the reference-space light direction (a flat
// field's cells all do); each light has its own tables, at most kMaxSlotsPerLight directions of
// it (the first cells', in primitive order), so that what one light's shadows are does not depend
// on the other lights. Values are computed on first use, each a function of its voxel alone, so
// whichever thread writes one writes the same value: images do not depend on the tiles' order.
// Levels up to kMaxLevel (32³ voxels, 3.8 MiB a table); finer queries march.
#pragma once

#include <vtex/render/texel_march.h>

#include "frame.h"
#include "light_cache.h"
#include "march.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace vtex::render::detail {

/// A shadow query's share in the voxel of `grid` (level `level`) it starts in: from p0 (tiled
/// reference space) along lr (unit; `inverse` its per-component reciprocal) to the face it leaves
/// by, at most maxStep. The near shadow table and the field's volume table both take it exactly:
/// a lit voxel's own density is what its query must see exactly. `ownFactor` scales that
/// density: a camera march's query takes off the share of the piece it lights
/// (TexelRuntime::ownDepthFactor), other queries 1.
struct OwnVoxel {
    double exit = 0;      ///< how far along lr the query leaves its voxel, in [0, maxStep]
    int face = -1;        ///< the axis of the face it leaves by (−1: lr is 0)
    double f[3] = {};     ///< the voxel's coordinates, unwrapped
    std::uint32_t idx[3] = {};  ///< the voxel in the grid
    double depth = 0;     ///< the optical depth over [0, exit]
};
inline OwnVoxel ownVoxel(const MarchVolume& volume, const LevelGrid& grid, double tau, int level, const Vec3& p0,
                         const Vec3& lr, const Vec3& inverse, double maxStep, double ownFactor = 1) {
    OwnVoxel o;
    const double n = double(grid.n), invN = 1 / n;
    // Located a hair along the ray, as the march locates a point on a voxel face: octree::voxelExit's
    // rule, written out here for the face it leaves by and with lr's reciprocal kept (every camera
    // march's shadow query on a flat field comes through here).
    const Vec3 p = p0 + (1e-7 * invN) * lr;
    double exit = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        o.f[a] = clampedFloor(p[a] * n);
        if (lr[a] == 0) continue;
        const double e = ((lr[a] > 0 ? o.f[a] + 1 : o.f[a]) * invN - p0[a]) * inverse[a];
        if (e < exit) {
            exit = e;
            o.face = a;
        }
    }
    const std::uint32_t mask = grid.n - 1;
    o.idx[0] = std::uint32_t(std::int64_t(o.f[0]) & mask);
    o.idx[1] = std::uint32_t(std::int64_t(o.f[1]) & mask);
    o.idx[2] = std::uint32_t(std::clamp(o.f[2], 0.0, n - 1));
    o.exit = std::clamp(exit, 0.0, maxStep);
    const std::uint32_t cell = grid.cell(o.idx[0], o.idx[1], o.idx[2]);
    if (!(cell & LevelGrid::kEmpty)) {
        const GridVoxel& v = grid.voxels[cell];
        o.depth = ownFactor * v.extinction(tau, lr) * o.exit * ProfileFactor(volume, level, p0, lr)(0, o.exit);
    }
    return o;
}

class NearShadowTable {
public:
    static constexpr int kMaxLevel = 5;
    /// Distinct (texel, direction) pairs one light keeps tables for; cells beyond march.
    static constexpr int kMaxSlotsPerLight = 4;
    /// A query's reference-space light direction is the table's when within this (per component).
    static constexpr double kSameDirection = 1e-9;
    /// The marches an entry holds per face: kSide × kSide, at the middles of a kSide × kSide
    /// division of the face.
    static constexpr int kSide = 3;
    /// Per face: the end's extinction, then the marches' transmittances; three faces a voxel.
    static constexpr int kPerFace = 1 + kSide * kSide, kPerVoxel = 3 * kPerFace;

    /// The slot's texel and light direction; tables are allocated per level on first use.
    struct Slot {
        int texel = -1;
        int light = -1;  ///< LightTransmittanceCache slot
        Vec3 lr = Vec3::Zero();
        Vec3 inverse = Vec3::Zero();  ///< 1 / lr, per component (∞ for 0)
        mutable std::array<std::atomic<std::atomic<float>*>, kMaxLevel + 1> levels{};
    };

    NearShadowTable() = default;
    ~NearShadowTable() {
        for (auto& s : mSlots)
            for (auto& l : s->levels) delete[] l.load();
    }
    NearShadowTable(const NearShadowTable&) = delete;
    NearShadowTable& operator=(const NearShadowTable&) = delete;

    /// Whether a cell with map `map` shows exactly one whole tile (its sides are the tile's).
    static bool showsOneTile(const CellMap& map) {
        Eigen::Vector2d lo, hi;
        map.bounds(lo, hi);
        return (hi - lo).isApprox(Eigen::Vector2d(1, 1), 1e-12) && lo.x() == std::round(lo.x()) &&
               lo.y() == std::round(lo.y());
    }

    /// The memory a light's tables may take at most.
    static constexpr std::uint64_t kBytesPerLight = [] {
        std::uint64_t voxels = 0;
        for (int l = 0; l <= kMaxLevel; ++l) voxels += std::uint64_t(1) << (3 * l);
        return std::uint64_t(kMaxSlotsPerLight) * voxels * kPerVoxel * sizeof(float);
    }();

    /// The slot of (texel, light, lr), made if need be: −1 when the light has kMaxSlotsPerLight.
    /// Called before rendering, in primitive order, so that which cells have a table is fixed.
    int slotFor(int texel, int light, const Vec3& lr) {
        int ofLight = 0;
        for (std::size_t i = 0; i < mSlots.size(); ++i) {
            if (mSlots[i]->light != light) continue;
            if (mSlots[i]->texel == texel && same(mSlots[i]->lr, lr)) return int(i);
            ++ofLight;
        }
        if (ofLight >= kMaxSlotsPerLight) return -1;
        auto s = std::make_unique<Slot>();
        s->texel = texel;
        s->light = light;
        s->lr = lr;
        s->inverse = lr.cwiseInverse();
        for (auto& l : s->levels) l.store(nullptr);
        mSlots.push_back(std::move(s));
        return int(mSlots.size()) - 1;
    }

    const Slot& slot(int i) const { return *mSlots[std::size_t(i)]; }
    std::size_t slots() const { return mSlots.size(); }
    static bool same(const Vec3& a, const Vec3& b) { return (a - b).cwiseAbs().maxCoeff() <= kSameDirection; }

    /// Transmittance of the segment p0 → p0 + step·lr (tiled reference space, within one tile
    /// of a cell that shows one tile) through `volume` at `level` (≤ kMaxLevel; `grid` its
    /// grid), `maxStep` the longest such segment: the segment's share in the voxel it starts in
    /// exactly (its density times `ownFactor`, ownVoxel), up to the face it leaves by; the rest
    /// from that face's entry of the table.
    double transmittance(int slotIndex, const MarchVolume& volume, const LevelGrid& grid, double tau, int level,
                         const Vec3& p0, double step, double maxStep, double ownFactor = 1) const {
        const Slot& s = slot(slotIndex);
        const OwnVoxel o = ownVoxel(volume, grid, tau, level, p0, s.lr, s.inverse, step, ownFactor);
        const double own = o.depth, exit = o.exit;
        if (!(step > exit) || o.face < 0) return std::exp(-own);
        // The rest from where on the face the query leaves (fractions of the voxel along the
        // face's other two axes).
        const double n = double(grid.n);
        const int u = (o.face + 1) % 3, v = (o.face + 2) % 3;
        const double fu = (p0[u] + exit * s.lr[u]) * n - o.f[u], fv = (p0[v] + exit * s.lr[v]) * n - o.f[v];
        const Rest r = rest(s, volume, grid, tau, level, o.idx, o.face, step - exit, maxStep, fu, fv);
        // exp(−own) · clamp(t · exp(−depth), 0, 1), with one exponential where the clamp cannot
        // act: t · e^(−depth) ≤ 1 when t ≤ 1 and depth ≥ 0, or t ≤ 1 + depth ≤ e^depth.
        if (!(r.t > 0)) return 0;
        if (r.depth >= 0 ? r.t <= 1 : r.t <= 1 + r.depth) return r.t * std::exp(-(own + r.depth));
        return std::exp(-own) * std::min(r.t * std::exp(-r.depth), 1.0);
    }

private:
    // What rest() finds: the transmittance is t · exp(−depth), clamped to [0, 1].
    struct Rest {
        double t;      ///< the entry's marches interpolated where the query leaves
        double depth;  ///< the optical depth by which the query's length differs from the entry's
    };

    // The transmittance (as a Rest) over `length` from (fu, fv) on the face of voxel idx (in the tile
    // [0, 1]²) that is perpendicular to axis `face` and toward the light. The entry holds the
    // transmittances of the marches from kSide × kSide points of the face (the middles of its
    // division) up to maxStep or the tile's sides, top or floor: interpolated bilinearly
    // (extended to the face's edges), which keeps where on the face the query leaves — the
    // camera's queries sit on its side of a voxel, where its ray came through, and their light
    // paths share that emptier side (on the bush field's middle view, with throw-away code not
    // kept, the face's mean alone made the stretch too dark and the voxel's centre too bright). Three points a side, not two:
    // the transmittance across a face is convex, and interpolating between points that stand
    // for a quarter of it each made the stretch 0.5 % too dark on random queries in a bush
    // (the midpoint rule's bias; kSide = 2 in NearShadowTable.IsCloseToTheMarchOnAverageInABush
    // prints it), with three 0.1 %. Where the tile's sides or top end both the
    // query and the entries, their lengths agree; where maxStep does, the query's is shorter by
    // its share in its own voxel (at most a voxel's chord), taken off at the extinction where the
    // face's middle march ends.
    Rest rest(const Slot& s, const MarchVolume& volume, const LevelGrid& grid, double tau, int level,
                const std::uint32_t idx[3], int face, double length, double maxStep, double fu, double fv) const {
        const double invN = 1 / double(grid.n);
        const int u = (face + 1) % 3, v = (face + 2) % 3;
        Vec3 from(idx[0] + 0.5, idx[1] + 0.5, idx[2] + 0.5);
        from *= invN;
        from[face] += (s.lr[face] > 0 ? 0.5 : -0.5) * invN;
        std::atomic<float>* values =
            table(s, level) + kPerVoxel * ((std::size_t(idx[2]) * grid.n + idx[1]) * grid.n + idx[0]) + kPerFace * face;
        if (std::isnan(values[1].load(std::memory_order_acquire))) fill(s, volume, grid, tau, level, from, face, maxStep, values);
        // Bilinear between the nearest four march points (extended linearly to the face's edges).
        const auto cellOf = [](double f, int& i0, double& w) {
            const double g = std::clamp(f, 0.0, 1.0) * kSide - 0.5;  // in march-point units
            i0 = std::clamp(int(clampedFloor(g)), 0, kSide - 2);
            w = g - i0;
        };
        int iu, iv;
        double wu, wv;
        cellOf(fu, iu, wu);
        cellOf(fv, iv, wv);
        const std::atomic<float>* corner = values + 1 + iv * kSide + iu;
        const auto at = [&](int k) { return double(corner[k].load(std::memory_order_relaxed)); };
        double t = (1 - wu) * (1 - wv) * at(0);
        t += wu * (1 - wv) * at(1);
        t += (1 - wu) * wv * at(kSide);
        t += wu * wv * at(kSide + 1);
        // The entries' lengths, where the query leaves: the distance to the tile's sides, top or
        // floor along the light is affine in the start, so bilinear interpolation of the march
        // points' lengths is that distance at the exit point itself, capped at maxStep.
        from[u] += (fu - 0.5) * invN;
        from[v] += (fv - 0.5) * invN;
        const double entryLength = std::min(maxStep, tileExit(s, from));
        const double endSigma = double(values[0].load(std::memory_order_relaxed));
        return {t, endSigma * (length - entryLength)};
    }

    // The distance from x (in the tile [0, 1]²) along the slot's direction to the tile's sides,
    // top or floor.
    static double tileExit(const Slot& s, const Vec3& x) {
        double d = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a)
            if (s.lr[a] != 0) d = std::min(d, std::max(0.0, ((s.lr[a] > 0 ? 1.0 : 0.0) - x[a]) * s.inverse[a]));
        return d;
    }

    // An entry: the extinction where the face's middle march ends, then the transmittance of the
    // march from each point of the face (the first stored last, with release: the entry is made).
    void fill(const Slot& s, const MarchVolume& volume, const LevelGrid& grid, double tau, int level, const Vec3& from,
              int face, double maxStep, std::atomic<float>* values) const {
        const double n = double(grid.n);
        const int u = (face + 1) % 3, v = (face + 2) % 3;
        std::array<double, kSide * kSide> t;
        t.fill(1);
        double endSigma = 0;
        const double length = std::min(maxStep, tileExit(s, from));
        if (length > 0) {
            for (int b = 0; b < kSide; ++b)
                for (int a = 0; a < kSide; ++a) {
                    Vec3 start = from;
                    start[u] += ((a + 0.5) / kSide - 0.5) / n;
                    start[v] += ((b + 0.5) / kSide - 0.5) / n;
                    const double own = std::min(maxStep, tileExit(s, start));
                    t[std::size_t(b * kSide + a)] =
                        marchTransmittance(volume, tau, start, start + own * s.lr, level, kCutoff).transmittance;
                }
            const Vec3 end = from + (length - 1e-7 / n) * s.lr;
            const std::uint32_t mask = grid.n - 1;
            const std::uint32_t cell = grid.cell(std::uint32_t(std::int64_t(std::floor(end.x() * n)) & mask),
                                                 std::uint32_t(std::int64_t(std::floor(end.y() * n)) & mask),
                                                 std::uint32_t(std::clamp(std::floor(end.z() * n), 0.0, n - 1)));
            // At a profiled level, the extinction at the end point's height.
            if (!(cell & LevelGrid::kEmpty)) endSigma = grid.voxels[cell].extinction(tau, s.lr) * ProfileFactor(volume, level, end, s.lr)(0, 0);
        }
        values[0].store(float(endSigma), std::memory_order_relaxed);
        for (int k = kSide * kSide - 1; k >= 1; --k) values[1 + k].store(float(t[std::size_t(k)]), std::memory_order_relaxed);
        values[1].store(float(t[0]), std::memory_order_release);
    }

    std::atomic<float>* table(const Slot& s, int level) const {
        return claimNanBlock(s.levels[std::size_t(level)], std::size_t(kPerVoxel) << (3 * level));
    }

    // A march darker than this is as dark (the queries' own cut-off is 1e-4).
    static constexpr double kCutoff = 1e-6;
    std::vector<std::unique_ptr<Slot>> mSlots;
};

}  // namespace vtex::render::detail
