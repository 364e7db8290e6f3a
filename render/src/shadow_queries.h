// How the texel renderer answers "how much light reaches this point from that light"
// (docs/render.md, "Shadows"): an exact shadow ray walked through the cells (volume marches, or
// the source mesh where the hybrid takes it), or for directional lights the short exact march
// and the per-cell transmittance lattice. One object per render, shared by all threads.
#pragma once

#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>
#include <vtex/render/texel_march.h>

#include "cell_adjacency.h"
#include "floor_shadow_table.h"
#include "frame.h"
#include "light_cache.h"
#include "near_shadow_table.h"
#include "texel_runtime.h"
#include "tracer.h"

#include <Eigen/Dense>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace vtex::render::detail {

inline constexpr double kTransmittanceCutoff = 1e-4;
// Lattice steps marched exactly from a shadow query before the lattice is looked up.
inline constexpr double kExactLatticeSteps = 4.0;

class ShadowQueries {
public:
    ShadowQueries(const Scene& scene, const RenderOptions& options, const Tracer& tracer,
                  const std::vector<SurfaceRuntime>& surfaces, const std::vector<TexelRuntime>& texels)
        : mScene(scene), mOptions(options), mTracer(tracer), mSurfaces(surfaces), mTexels(texels) {}

    // Transmittance from o toward the light along the unit direction l, up to tMax: opaque
    // faces and cell floors block, texel cells attenuate at the level of the cone `width`
    // (world units, held constant along the shadow ray).
    // `hint`: the cell o lies in, at cell coordinates hintR, when the caller knows it.
    // `litVoxel`: o is a camera march's voxel, lit by this query, in the hint's cell: its own
    // voxel's density is taken times TexelRuntime::ownDepthFactor (the piece it lights does not
    // shadow it).
    double shadowTransmittance(const Vec3& o, const Vec3& l, double tMax, double width, const Prim* hint,
                               const Vec3& hintR, Counters& counters, bool litVoxel = false) const {
        const int hintPrim = hint ? hint->index : -1;
        if (const int slot = latticeSlot(l, tMax, hintPrim); slot >= 0)
            return nearAndCachedShadow(slot, *hint, hintR, l, width, counters, nullptr, litVoxel);
        return tracedShadow(o, l, tMax, width, hintPrim, hintR, counters, false, 0, litVoxel);
    }

    // The slot of the transmittance lattice that answers a shadow query toward l (up to tMax)
    // from inside primitive `prim` (−1: none): a directional light and a point inside a texel
    // cell that has a lattice.
    int latticeSlot(const Vec3& l, double tMax, int prim) const {
        if (mOptions.approximations.shadowCacheResolution <= 0 || !std::isinf(tMax) || prim < 0) return -1;
        const int slot = mLightCache.slot(l);  // −1 also when there is no lattice at all
        return slot >= 0 && mLightCache.grid(prim).nw > 0 ? slot : -1;
    }

    // A query at cell coordinates r: the exact transmittance over the first kExactLatticeSteps
    // lattice steps toward the light (marched in the cell's texel at the query's own level: the
    // voxels next to the point, which a lit voxel's own column or leaf makes darker than the
    // lattice nodes around it), times the lattice's value where that march ends. The march stops
    // at the cell's sides, so that the lattice looked up is the right one. Four steps (issue 12;
    // two before): on the bush field, with the lattice interpolating optical depth, the image mean
    // against exact shadow rays moved by −0.9 % (far) and −0.6 % (mid) at two steps, −0.3 % at
    // four, for no measurable time (docs/render.md, "Shadows").
    //
    // `span`, when the query comes from a camera march: the reference-space light direction and
    // the local scale the march took at its span's middle, used instead of the query point's
    // own (the mild-deformation assumption the march itself makes; it saves a Jacobian, its
    // inverse and a cube root per query). `litVoxel`: the query lights a camera march's voxel
    // (shadowTransmittance).
    struct SpanFrame {
        Vec3 light;  ///< unit, tiled reference space
        double scale;  ///< the local scale at the span's middle
        int level = -1;  ///< the shadow level when the caller knows it (−1: chosen from width)
    };
    double nearAndCachedShadow(int slot, const Prim& prim, const Vec3& r, const Vec3& l, double width,
                               Counters& counters, const SpanFrame* span = nullptr, bool litVoxel = false) const {
        ++counters.shadow;
        const int primIndex = prim.index;
        const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        Vec3 lr;
        if (span) {
            lr = span->light;
        } else {
            lr = tiledJacobianInverse(prim, r) * l;
            const double len = lr.norm();
            if (!(len > 0) || !std::isfinite(len)) return cachedShadow(slot, primIndex, r, l, 0, &prim);
            lr /= len;
        }
        const int level =
            span && span->level >= 0 ? span->level : shadowLevel(texel, width / (span ? span->scale : localScale(prim, r)));
        const double own = litVoxel ? texel.ownDepthFactor(level) : 1.0;
        // A flat field with nothing above it: the query's own voxel and a look-up of the rest.
        if (mFieldAlone && level <= FloorShadowTable::kMaxVolumeLevel &&
            mFloorCells[std::size_t(primIndex) * mLightCache.lights() + std::size_t(slot)]) {
            const int table = mNearSlots[std::size_t(primIndex) * mLightCache.lights() + std::size_t(slot)];
            if (const LevelGrid* grid = texel.volume->grid(level))
                return mFloorTable.inside(table, *texel.volume, *grid, texel.tauAt(level), level, mNearTable.slot(table).lr,
                                          mNearTable.slot(table).inverse, tile(r, prim), own);
        }
        const double maxStep = kExactLatticeSteps / double(mLightCache.grid(primIndex).nw);
        const CellSegment near = segmentInCell(prim, r, lr, maxStep);
        if (near.exitFace == 0) return 0;  // the base surface blocks
        double transmittance;
        const LevelGrid* grid = nullptr;
        if (const int table = nearTableSlot(slot, primIndex, texel, lr, level, grid); table >= 0) {
            transmittance = mNearTable.transmittance(table, *texel.volume, *grid, texel.tauAt(level), level, near.p0,
                                                     near.step, maxStep, own);
        } else {
            const SegmentTransmittance seg = marchTransmittance(*texel.volume, texel.tauAt(level), near.p0,
                                                                near.p0 + near.step * lr, level, kTransmittanceCutoff, own);
            counters.voxels += seg.blocks;
            transmittance = seg.transmittance;
        }
        if (transmittance <= kTransmittanceCutoff) return 0;
        return transmittance * cachedShadow(slot, primIndex, near.end, l, 0, &prim);
    }

    // The near table's slot for a query from primitive `primIndex` toward lattice slot `slot`
    // along reference direction lr at `level`, −1 when the query marches (NearShadowTable).
    // `grid`: the level's grid, when there is a slot.
    int nearTableSlot(int slot, int primIndex, const TexelRuntime& texel, const Vec3& lr, int level,
                      const LevelGrid*& grid) const {
        if (mNearSlots.empty() || !mOptions.approximations.nearShadowTable || level > NearShadowTable::kMaxLevel) return -1;
        const int table = mNearSlots[std::size_t(primIndex) * mLightCache.lights() + std::size_t(slot)];
        if (table < 0 || !NearShadowTable::same(mNearTable.slot(table).lr, lr)) return -1;
        grid = texel.volume->grid(level);
        return grid ? table : -1;
    }

    // The lattice's value at cell coordinates r of primitive `primIndex`. Node values are shared
    // by all pixels, so their work is not counted in any tile's statistics (which would then
    // depend on which tile came first). `depth`: how many cells a node's chain has crossed.
    // `known`: the primitive, when the caller has it; otherwise it is put together only if a
    // node is missing (prim_table.h).
    double cachedShadow(int slot, int primIndex, const Vec3& r, const Vec3& l, int depth = 0,
                        const Prim* known = nullptr) const {
        // Two paths, so that the common one (a camera march's query, which has its primitive)
        // does not carry a 560-byte std::optional<Prim> through every look-up: that cost 2 % of
        // the bush field's middle view.
        if (known)
            return mLightCache.lookup(slot, primIndex, r, [&](const Vec3& node) { return nodeAt(slot, *known, node, l, depth); });
        return cachedShadowBuildingPrim(slot, primIndex, r, l, depth);
    }

    [[gnu::noinline]] double cachedShadowBuildingPrim(int slot, int primIndex, const Vec3& r, const Vec3& l, int depth) const {
        std::optional<Prim> scratch;
        const Prim* prim = nullptr;
        return mLightCache.lookup(slot, primIndex, r, [&](const Vec3& node) {
            if (!prim) prim = &mTracer.prims().at(std::size_t(primIndex), scratch);
            return nodeAt(slot, *prim, node, l, depth);
        });
    }

    double nodeAt(int slot, const Prim& prim, const Vec3& node, const Vec3& l, int depth) const {
        // Nodes on the cell's faces move in by a hair, so that the ray starts inside.
        const Vec3 rn = node.cwiseMax(Vec3::Constant(1e-4)).cwiseMin(Vec3::Constant(1 - 1e-4));
        return nodeTransmittance(slot, prim, rn, l, depth);
    }

    // A lattice node's transmittance toward the light, chained through the cells (issue 12): the
    // march through its own cell, at the level of the lattice's spacing, up to where the light
    // ray leaves the cell, times what lies beyond: the neighbour's lattice looked up on the shared
    // face when the ray leaves through a side into a cell that has one (its face nodes, chained
    // the same way), otherwise one exact shadow ray from the exit point. A node thus costs one
    // cell's march instead of a ray walked through the BVH cell by cell (on the bush field's far
    // view node rays were a third of the render). An approximation on top of the lattice: the
    // face's bilinear interpolation between its nodes, once per cell crossed. Chains longer than
    // kMaxChain cells (a grazing light over cells much smaller than their shell), nodes where
    // the hybrid would trace the mesh, and every node when ApproximationBudget::chainLatticeNodes
    // is off take the exact ray from the node itself. Which node of a chain that long gets the
    // exact ray depends on where the chain began, so only there could an image depend on the
    // order of the tiles (a node's value is otherwise a function of the node alone).
    double nodeTransmittance(int slot, const Prim& prim, const Vec3& rn, const Vec3& l, int depth) const {
        const int primIndex = prim.index;
        const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        const double spacing = 1.0 / double(mLightCache.grid(primIndex).nw);
        Counters uncounted;
        const auto exactFrom = [&](const Vec3& r) {
            return tracedShadow(prim.cell.map(r), l, std::numeric_limits<double>::infinity(),
                                localScale(prim, r) * spacing, primIndex, r, uncounted);
        };
        const LevelChoice choice = chooseLevel(spacing, mOptions.lodBias, texel.volume->maxLevel());
        // The one place a pixel can depend on the others rendered: the render warns (chainCut).
        if (depth >= kMaxChain) mChainCut.store(true, std::memory_order_relaxed);
        if (depth >= kMaxChain || texel.shadowMeshWeight(choice.requested) > 0 ||
            !mOptions.approximations.chainLatticeNodes)
            return exactFrom(rn);
        Vec3 lr = tiledJacobianInverse(prim, rn) * l;
        const double len = lr.norm();
        if (!(len > 0) || !std::isfinite(len)) return exactFrom(rn);
        lr /= len;
        const CellMarch m = marchInCell(texel, prim, rn, lr, std::numeric_limits<double>::infinity(),
                                        shadowLevel(texel, choice));
        if (m.exitFace == 0 || m.transmittance <= kTransmittanceCutoff) return 0;
        const CellNeighbour& next = m.exitFace >= 2 ? mAdjacency.across(primIndex, m.exitFace) : CellNeighbour{};
        if (next.prim < 0 || mLightCache.grid(next.prim).nw <= 0) return m.transmittance * exactFrom(m.end);
        return m.transmittance *
               cachedShadow(slot, next.prim, CellAdjacency::toNeighbour(next, m.exitFace, m.end), l, depth + 1);
    }

    // Whether some lattice chain was cut at kMaxChain cells (nodeTransmittance): then the image
    // may depend on the order of the tiles and on which rows were rendered.
    bool chainCut() const { return mChainCut.load(std::memory_order_relaxed); }

    // The exact path: one ray toward the light. `fromSourceHit`: the ray leaves a point of a
    // texel's source mesh (the hybrid's mesh span), and every texel with a source is then tested
    // against its mesh alone, whatever the cone's width: the volume around the hit holds the lit
    // leaf's own density and would shadow the leaf (the self-shadowing of issue 12). Its first
    // segment skips the self-intersection gap even without a hint (a hit of a segment offset
    // across the footprint may lie past the cell's side, where the caller has no cell for it).
    // `litVoxel`: o is a camera march's voxel in the hint's cell (shadowTransmittance).
    double tracedShadow(const Vec3& o, const Vec3& l, double tMax, double width, int hintPrim, const Vec3& hintR,
                        Counters& counters, bool fromSourceHit = false, double tStart = 0, bool litVoxel = false) const {
        ++counters.shadow;
        bool first = true;
        return walkShadowRay(
            mTracer, mSurfaces, o, l, tMax, hintPrim, hintR, kTransmittanceCutoff,
            [&](const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, bool startsAtHint,
                double transmittance) {
                const bool leavesHit = startsAtHint || (fromSourceHit && first);
                first = false;
                const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
                const Vec3 p0 = tile(rIn, prim), p1 = tile(rOut, prim);
                const LevelChoice choice = chooseLevel(width / localScale(prim, 0.5 * (rIn + rOut)),
                                                       mOptions.lodBias, texel.volume->maxLevel());
                // The hybrid's rule for shadows too: the source mesh where the footprint is finer
                // than the volume is faithful, blended over the next level with the volume at a
                // level no finer than the mesh level (TexelRuntime::shadowMeshWeight, shadowLevelFor).
                const double meshWeight =
                    fromSourceHit && texel.source ? 1.0 : texel.shadowMeshWeight(choice.requested);
                double result = 0;
                if (meshWeight < 1) {
                    const int level = shadowLevel(texel, choice);
                    const double own = litVoxel && startsAtHint ? texel.ownDepthFactor(level) : 1.0;
                    const SegmentTransmittance seg = marchTransmittance(*texel.volume, texel.tauAt(level), p0, p1, level,
                                                                        kTransmittanceCutoff / transmittance, own);
                    counters.voxels += seg.blocks;
                    result = (1 - meshWeight) * seg.transmittance;
                }
                if (meshWeight > 0 && !texel.source->occludedLeaving(p0, p1, leavesHit)) result += meshWeight;
                return result;
            },
            tStart);
    }

    // A floor point's shadow: at cell coordinates r (w = 0) of `prim`, the shadow ray leaving
    // from o (world). The floor table where the cell may take it (FloorShadowTable: a flat
    // field's light lines through the tiled texel, then the exact walk from where the line leaves
    // the shell's top); otherwise, for a floor seen through less than exactFloorShadowAbove
    // (`dim`), the cell's lattice from just above the floor (the hint is what lets a query use
    // it), and else the exact ray.
    double floorShadow(const Prim& prim, const Vec3& r, const Vec3& o, const Vec3& l, double tMax, double width,
                       bool dim, Counters& counters) const {
        const int slot = mFloorCells.empty() || !mOptions.approximations.floorShadowTable ? -1 : latticeSlot(l, tMax, prim.index);
        if (slot >= 0 && mFloorCells[std::size_t(prim.index) * mLightCache.lights() + std::size_t(slot)]) {
            const TexelRuntime& texel = mTexels[std::size_t(mSurfaces[std::size_t(prim.surface)].texel)];
            const LevelChoice choice = chooseLevel(width / localScale(prim, r), mOptions.lodBias, texel.volume->maxLevel());
            const int level = shadowLevel(texel, choice);
            if (texel.shadowMeshWeight(choice.requested) <= 0 && level <= FloorShadowTable::kMaxLevel) {
                const int table = mNearSlots[std::size_t(prim.index) * mLightCache.lights() + std::size_t(slot)];
                const Vec3& lr = mNearTable.slot(table).lr;
                const Vec3 p = tile(Vec3(r.x(), r.y(), 0), prim);
                const double t =
                    mFloorTable.transmittance(table, *texel.volume, texel.tauAt(level), level, lr, p.x(), p.y());
                if (t <= kTransmittanceCutoff) {
                    ++counters.shadow;
                    return 0;
                }
                // The line leaves the top (z = 1) after 1/lr.z reference units, 1/(J⁻¹l).z along
                // l in the world (J: the tiled map's Jacobian, constant over a flat field).
                const double zRate = (tiledJacobianInverse(prim, r) * l).z();
                if (zRate > 0 && std::isfinite(zRate))
                    return t * tracedShadow(o, l, tMax, width, -1, Vec3::Zero(), counters, false, (1 + 1e-9) / zRate);
            }
        }
        if (dim) return shadowTransmittance(o, l, tMax, width, &prim, Vec3(r.x(), r.y(), 1e-4), counters);
        return shadowTransmittance(o, l, tMax, width, nullptr, Vec3::Zero(), counters);
    }

    // A shadow march takes a single level (shadows are not blended): the one nearest the cone's
    // width (reference units), never coarser than the texel's coarsest faithful level, or with the
    // levels fitted the level measured for that width (TexelRuntime::shadowLevels).
    int shadowLevel(const TexelRuntime& texel, double width) const {
        return texel.shadowLevelFor(shadowFootprint(texel, width));
    }
    static int shadowLevel(const TexelRuntime& texel, const LevelChoice& choice) {
        return texel.shadowLevelFor(footprintOf(choice));
    }
    // The level a shadow cone of `width` asks for, before the texel's rule: the single level
    // nearest it (monotone in the width).
    int shadowFootprint(const TexelRuntime& texel, double width) const {
        return footprintOf(chooseLevel(width, mOptions.lodBias, texel.volume->maxLevel()));
    }
    static int footprintOf(const LevelChoice& choice) { return choice.fineWeight < 0.5 ? choice.coarse : choice.fine; }

    // A march from cell coordinates r along the unit reference direction lr, at most `maxStep`
    // far (reference units) and not past the cell's sides, top or floor: its transmittance, where
    // it ends (cell coordinates) and the face it stopped on (TrilinearCell numbering; −1 when
    // maxStep ended it inside). The sides are u, v = 0 and 1 in cell coordinates, whatever the
    // face's CellMap (its quarter turns, mirrors, shifts and sub-rectangle). Straight in
    // reference space: the mild-deformation assumption of the march.
    struct CellMarch {
        double transmittance = 1;
        Vec3 end;
        int exitFace = -1;
        std::uint64_t blocks = 0;
    };
    CellMarch marchInCell(const TexelRuntime& texel, const Prim& prim, const Vec3& r, const Vec3& lr, double maxStep,
                          int level) const {
        const CellSegment segment = segmentInCell(prim, r, lr, maxStep);
        const SegmentTransmittance seg = marchTransmittance(*texel.volume, texel.tauAt(level), segment.p0,
                                                            segment.p0 + segment.step * lr, level, kTransmittanceCutoff);
        return {seg.transmittance, segment.end, segment.exitFace, seg.blocks};
    }

    // The straight segment marchInCell marches: from p0 (tiled reference space, the point r)
    // `step` along lr, ending at `end` (cell coordinates) on face exitFace (−1: inside).
    struct CellSegment {
        Vec3 p0;
        double step;
        int exitFace = -1;
        Vec3 end;
    };
    static CellSegment segmentInCell(const Prim& prim, const Vec3& r, const Vec3& lr, double maxStep) {
        CellSegment m;
        double step = maxStep;
        const Vec3 p0 = tile(r, prim);
        const Vec3 lc = prim.map.linearInverse() * lr;
        for (int a = 0; a < 2; ++a) {
            double s = std::numeric_limits<double>::infinity();
            if (lc[a] > 0) s = std::max(0.0, (1 - r[a]) / lc[a]);
            else if (lc[a] < 0) s = std::max(0.0, -r[a] / lc[a]);
            if (s < step) {
                step = s;
                m.exitFace = 2 + 2 * a + (lc[a] > 0 ? 1 : 0);
            }
        }
        if (p0.z() + step * lr.z() > 1) {
            step = std::max(0.0, (1 - p0.z()) / lr.z());
            m.exitFace = 1;
        }
        if (p0.z() + step * lr.z() < 0) {
            step = std::max(0.0, -p0.z() / lr.z());
            m.exitFace = 0;  // the base surface, which blocks
        }
        m.p0 = p0;
        m.step = step;
        m.end = prim.map.toCell(p0 + step * lr);
        // The face it stopped on exactly, not a rounding away from it: the neighbour's lattice is
        // looked up there.
        if (m.exitFace >= 2) m.end[(m.exitFace - 2) / 2] = double(m.exitFace % 2);
        return m;
    }

private:
    static constexpr int kMaxChain = 256;
    // The near tables' slots, fixed before any pixel (in primitive order, so that which cells
    // have one does not depend on the tiles'): cells with a lattice that show one tile of their
    // texel, by texel and reference-space light direction at the cell's centre. The floor tables
    // take the same slots.
    std::vector<int> makeNearSlots() {
        const ApproximationBudget& a = mOptions.approximations;
        if (mLightCache.empty() || !(a.nearShadowTable || a.floorShadowTable || a.fieldShadowVolume))
            return {};
        const std::size_t lights = mLightCache.lights();
        std::vector<int> slots(mTracer.prims().size() * lights, -1);
        for (std::size_t i = 0; i < mTracer.prims().size(); ++i) {
            if (!mTracer.prims().textured(i) || mLightCache.grid(int(i)).nw <= 0) continue;
            const Prim prim = mTracer.prims()[i];
            if (!NearShadowTable::showsOneTile(prim.map)) continue;
            const Mat3 inverse = tiledJacobianInverse(prim, Vec3::Constant(0.5));
            for (std::size_t k = 0; k < lights; ++k) {
                const Vec3 lr = inverse * mLightCache.direction(int(k));
                const double len = lr.norm();
                if (!(len > 0) || !std::isfinite(len)) continue;
                slots[i * lights + k] = mNearTable.slotFor(mSurfaces[std::size_t(prim.surface)].texel, int(k), lr / len);
            }
        }
        return slots;
    }

    LightTransmittanceCache makeLightCache() const {
        const int n = std::min(mOptions.approximations.shadowCacheResolution, 256);
        if (n <= 0) return {};
        std::vector<Vec3> directions;
        for (const Light& light : mScene.lights)
            if (light.type == LightType::Directional &&
                std::find(directions.begin(), directions.end(), Vec3(-light.direction)) == directions.end())
                directions.push_back(-light.direction);
        std::vector<LightTransmittanceCache::Grid> grids(mTracer.prims().size());
        // Node blocks are allocated as cells are first queried; the lattice is used only when
        // all of them together would fit in kMaxNodes (a decision taken here, before any
        // pixel, so that it does not depend on the order of the tiles), otherwise every query
        // casts its ray. Beyond 4 tiles of the texel across a cell, the lattice gets coarser
        // than 8 steps per tile.
        double total = 0;
        if (!directions.empty())
            for (std::size_t i = 0; i < grids.size(); ++i) {
                if (!mTracer.prims().textured(i)) continue;
                // Tiles of the texel along the cell's u and v: the lengths of the CellMap's columns.
                const auto across = [&](double tiles) { return n * int(std::clamp(std::ceil(tiles), 1.0, 4.0)); };
                const CellMap map = mTracer.prims().map(i);
                grids[i] = {across(map.a.col(0).norm()), across(map.a.col(1).norm()), n};
                total += double(grids[i].nodes()) * double(directions.size());
            }
        if (total > LightTransmittanceCache::kMaxNodes) return {};
        return LightTransmittanceCache(std::move(directions), std::move(grids));
    }

    const Scene& mScene;
    const RenderOptions& mOptions;
    const Tracer& mTracer;
    const std::vector<SurfaceRuntime>& mSurfaces;
    const std::vector<TexelRuntime>& mTexels;
    LightTransmittanceCache mLightCache = makeLightCache();
    CellAdjacency mAdjacency = mLightCache.empty() ? CellAdjacency() : CellAdjacency(mTracer.prims());
    NearShadowTable mNearTable;
    // Per primitive and lattice slot, the near table's slot (−1: march); empty: no tables.
    std::vector<int> mNearSlots = makeNearSlots();
    // Per primitive and lattice slot, whether its floor takes the floor table (and its voxels the
    // volume table, in a scene of that field alone); empty: none does.
    std::vector<bool> mFloorCells = mOptions.approximations.floorShadowTable || mOptions.approximations.fieldShadowVolume
                                        ? floorTableCells(mTracer.prims(), mAdjacency, mSurfaces, mNearSlots,
                                                          mLightCache.lights(), mNearTable)
                                        : std::vector<bool>{};
    FloorShadowTable mFloorTable{mNearTable.slots()};
    // Whether voxel queries in the floor table's cells take its volume table: a scene of one field.
    bool mFieldAlone = mOptions.approximations.fieldShadowVolume && !mFloorCells.empty() && oneSurfaceOnly(mTracer.prims());
    mutable std::atomic<bool> mChainCut{false};
};

}  // namespace vtex::render::detail
