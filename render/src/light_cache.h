// A per-cell cache of the transmittance toward a directional light (docs/render.md, "Shadows").
//
// For a directional light the transmittance toward it, T(x), depends on the point x only, not
// on the ray that needs it: every texel cell gets a lattice of nodes in its cell coordinates
// (u, v, w), each holding T at the node (one exact shadow ray, cast the first time a query
// needs it), and a query interpolates the optical depth −ln T of the eight nodes around it
// trilinearly (the renderer marches the first four lattice steps from the query point exactly, within the cell, and looks
// the lattice up where that march ends). An approximation, bounded against the exact shadow rays by the test
// CachedShadowsMatchShadowRays.
//
// A node's value is a function of the node alone, so whichever thread fills it first writes
// the same value: images do not depend on the thread count or on the order of the tiles. Node
// blocks are allocated on a cell's first query; a race allocates twice and keeps one.
#pragma once

#include <vtex/render/geometry.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <vector>

namespace vtex::render::detail {

/// The block of `count` atomic floats in `entry`, allocated on first use with every value NaN
/// ("not computed yet"): a race allocates twice and keeps the first, so all threads see one block.
/// Shared by the lattice's node blocks and the near shadow table's levels.
inline std::atomic<float>* claimNanBlock(std::atomic<std::atomic<float>*>& entry, std::size_t count) {
    std::atomic<float>* values = entry.load(std::memory_order_acquire);
    if (values) return values;
    auto* fresh = new std::atomic<float>[count];
    for (std::size_t i = 0; i < count; ++i) fresh[i].store(std::numeric_limits<float>::quiet_NaN(), std::memory_order_relaxed);
    if (entry.compare_exchange_strong(values, fresh, std::memory_order_acq_rel, std::memory_order_acquire)) return fresh;
    delete[] fresh;  // another thread was first
    return values;
}

class LightTransmittanceCache {
public:
    /// Nodes darker than this count as this dark: the optical depth stays finite (13.8).
    static constexpr double kDarkest = 1e-6;
    /// The lattices of one render hold at most this many nodes together (256 MiB of floats);
    /// a render whose cells would need more uses none (ShadowQueries decides before any pixel).
    static constexpr double kMaxNodes = double(1 << 26);
    struct Grid {
        int nu = 0, nv = 0, nw = 0;  ///< lattice cells per axis; nw = 0: no grid (plain face)
        std::size_t nodes() const { return std::size_t(nu + 1) * std::size_t(nv + 1) * std::size_t(nw + 1); }
    };

    LightTransmittanceCache() = default;
    /// `directions`: the distinct unit directions toward the directional lights; `grids`: one
    /// per primitive.
    LightTransmittanceCache(std::vector<Vec3> directions, std::vector<Grid> grids)
        : mDirections(std::move(directions)), mGrids(std::move(grids)),
          mBlocks(std::make_unique<std::atomic<std::atomic<float>*>[]>(mDirections.size() * mGrids.size())) {
        for (std::size_t i = 0; i < mDirections.size() * mGrids.size(); ++i) mBlocks[i].store(nullptr);
    }
    ~LightTransmittanceCache() {
        for (std::size_t i = 0; i < mDirections.size() * mGrids.size(); ++i) delete[] mBlocks[i].load();
    }
    LightTransmittanceCache(const LightTransmittanceCache&) = delete;
    LightTransmittanceCache& operator=(const LightTransmittanceCache&) = delete;

    /// The slot of the light whose direction is exactly l, −1 when there is none.
    int slot(const Vec3& l) const {
        for (std::size_t i = 0; i < mDirections.size(); ++i)
            if (mDirections[i] == l) return int(i);
        return -1;
    }
    const Grid& grid(int prim) const { return mGrids[std::size_t(prim)]; }
    /// The lights' slots: their number and each one's unit direction toward the light.
    std::size_t lights() const { return mDirections.size(); }
    const Vec3& direction(int slot) const { return mDirections[std::size_t(slot)]; }
    /// No lattice at all (no directional light, or too many nodes).
    bool empty() const { return mDirections.empty(); }

    /// T at cell coordinates r (clamped to [0,1]³) of primitive `prim` (which must have a
    /// grid), interpolated from the nodes; fill(node r) computes a missing node.
    template <class Fill>
    double lookup(int slot, int prim, const Vec3& r, Fill&& fill) const {
        const Grid& g = mGrids[std::size_t(prim)];
        std::atomic<float>* values = block(slot, prim);
        const double gu = std::clamp(r.x(), 0.0, 1.0) * g.nu, gv = std::clamp(r.y(), 0.0, 1.0) * g.nv,
                     gw = std::clamp(r.z(), 0.0, 1.0) * g.nw;
        const int iu = std::min(int(gu), g.nu - 1), iv = std::min(int(gv), g.nv - 1), iw = std::min(int(gw), g.nw - 1);
        const double wu[2] = {1 - (gu - iu), gu - iu}, wv[2] = {1 - (gv - iv), gv - iv}, ww[2] = {1 - (gw - iw), gw - iw};
        const std::size_t strideV = std::size_t(g.nu + 1), strideW = strideV * std::size_t(g.nv + 1);
        const std::size_t base = std::size_t(iw) * strideW + std::size_t(iv) * strideV + std::size_t(iu);
        const std::size_t offset[8] = {0, 1, strideV, strideV + 1, strideW, strideW + 1, strideW + strideV, strideW + strideV + 1};
        double weight[8];
        for (int c = 0; c < 8; ++c) weight[c] = wu[c & 1] * wv[(c >> 1) & 1] * ww[c >> 2];
        // A node holds the optical depth −ln T toward the light, and that is what is
        // interpolated: along the light a bush's transmittance falls exponentially, a convex
        // function that linear interpolation of T would overestimate everywhere between the
        // nodes (on the bush field +1 % in the mean). A node whose weight is 0 does not count and
        // is not computed; missing nodes are filled first, then the sum is taken in one order.
        const auto sum = [&](bool& missing) {
            double out = 0;
            for (int c = 0; c < 8; ++c) {
                if (!(weight[c] > 0)) continue;
                const float depth = values[base + offset[c]].load(std::memory_order_relaxed);
                missing |= std::isnan(depth);
                out += weight[c] * double(depth);
            }
            return out;
        };
        bool missing = false;
        double out = sum(missing);
        if (missing) [[unlikely]] {
            for (int c = 0; c < 8; ++c) {
                if (!(weight[c] > 0) || !std::isnan(values[base + offset[c]].load(std::memory_order_relaxed))) continue;
                const int du = c & 1, dv = (c >> 1) & 1, dw = c >> 2;
                const double t = fill(Vec3(double(iu + du) / g.nu, double(iv + dv) / g.nv, double(iw + dw) / g.nw));
                values[base + offset[c]].store(float(-std::log(std::max(t, kDarkest))), std::memory_order_relaxed);
            }
            out = sum(missing);
        }
        return std::exp(-out);
    }

private:
    std::atomic<float>* block(int slot, int prim) const {
        return claimNanBlock(mBlocks[std::size_t(slot) * mGrids.size() + std::size_t(prim)],
                             mGrids[std::size_t(prim)].nodes());
    }

    std::vector<Vec3> mDirections;
    std::vector<Grid> mGrids;
    std::unique_ptr<std::atomic<std::atomic<float>*>[]> mBlocks;
};

}  // namespace vtex::render::detail
