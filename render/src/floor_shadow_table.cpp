// See floor_shadow_table.h: which cells may take the floor table.
#include "floor_shadow_table.h"

#include <cmath>
#include <cstddef>
#include <optional>

namespace vtex::render::detail {
namespace {

// The opposite side face (TrilinearCell numbering: 2 ↔ 3, u = 0 and 1; 4 ↔ 5, v = 0 and 1).
int opposite(int face) { return face ^ 1; }

// The cell across side `face` of `prim` when the step keeps the field's tiling: the neighbour
// meets it face to face without flips or swaps, and the shared face's middle has the same tiled
// reference x and y in both cells up to whole tiles (the line goes on through the same texel).
// −1 otherwise.
int stepAcross(const PrimTable& prims, const CellAdjacency& adjacency, int prim, int face) {
    const CellNeighbour& n = adjacency.across(prim, face);
    if (n.prim < 0 || n.face != opposite(face) || n.flipA || n.flipB || n.swap) return -1;
    Vec3 middle(0.5, 0.5, 0.5);
    middle[(face - 2) / 2] = double(face % 2);
    const Vec3 here = prims.map(std::size_t(prim)).toReference(middle);
    const Vec3 there = prims.map(std::size_t(n.prim)).toReference(CellAdjacency::toNeighbour(n, face, middle));
    const Vec3 d = there - here;
    const auto whole = [](double x) { return std::abs(x - std::round(x)) <= 1e-9; };
    return whole(d.x()) && whole(d.y()) && std::abs(d.z()) <= 1e-9 ? n.prim : -1;
}

// The cell `steps` cells along u (`face` 2 or 3 by the sign), then along v; −1 where the tiling
// stops.
int walk(const PrimTable& prims, const CellAdjacency& adjacency, int prim, int du, int dv, bool uFirst) {
    const auto along = [&](int p, int steps, int minus, int plus) {
        for (int k = 0; k < std::abs(steps) && p >= 0; ++k) p = stepAcross(prims, adjacency, p, steps > 0 ? plus : minus);
        return p;
    };
    if (uFirst) return along(along(prim, du, 2, 3), dv, 4, 5);
    return along(along(prim, dv, 4, 5), du, 2, 3);
}

// Whether every textured cell of surface `surface` is a translate of the first by whole steps
// of its base edges (a flat, regular field; the steps in the base plane), and no primitive of
// another surface reaches into the field's bounds.
bool flatField(const PrimTable& prims, int surface, const std::vector<int>& surfaceOf) {
    std::optional<TrilinearCell> first;
    double tolerance = 0;
    Vec3 lo = Vec3::Constant(INFINITY), hi = -lo;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (surfaceOf[i] != surface) continue;
        const TrilinearCell cell = prims.cell(i);
        const auto& c = cell.corners();
        for (const Vec3& p : c) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
        if (!first) {
            first = cell;
            tolerance = 1e-9 * cell.size();
            continue;
        }
        const auto& f = first->corners();
        const Vec3 t = c[0] - f[0];
        for (int k = 1; k < 8; ++k)
            if ((c[std::size_t(k)] - f[std::size_t(k)] - t).cwiseAbs().maxCoeff() > tolerance) return false;
        // Corners 0, 1, 2: (0,0,0), (1,0,0), (0,1,0) (TrilinearCell numbering).
        Eigen::Matrix<double, 3, 2> edges;
        edges << f[1] - f[0], f[2] - f[0];
        const Eigen::Vector2d steps = edges.colPivHouseholderQr().solve(t);
        if ((edges * steps - t).cwiseAbs().maxCoeff() > tolerance ||
            (steps - steps.array().round().matrix()).cwiseAbs().maxCoeff() > 1e-9)
            return false;
    }
    if (!first) return false;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (surfaceOf[i] == surface) continue;
        Vec3 plo = Vec3::Constant(INFINITY), phi = -plo;
        const auto include = [&](const auto& corners) {
            for (const Vec3& p : corners) {
                plo = plo.cwiseMin(p);
                phi = phi.cwiseMax(p);
            }
        };
        if (prims.textured(i)) include(prims.cell(i).corners());
        else include(prims.patch(i));
        if ((plo.array() <= hi.array()).all() && (phi.array() >= lo.array()).all()) return false;
    }
    return true;
}

}  // namespace

bool oneSurfaceOnly(const PrimTable& prims) {
    std::optional<int> surface;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        std::optional<Prim> scratch;
        const Prim& prim = prims.at(i, scratch);
        if (!prim.textured || (surface && *surface != prim.surface)) return false;
        surface = prim.surface;
    }
    return surface.has_value();
}

std::vector<bool> floorTableCells(const PrimTable& prims, const CellAdjacency& adjacency,
                                  const std::vector<SurfaceRuntime>& surfaces, const std::vector<int>& nearSlots,
                                  std::size_t lights, const NearShadowTable& near) {
    std::vector<bool> out(prims.size() * lights, false);
    if (nearSlots.empty() || lights == 0) return out;
    std::vector<int> surfaceOf(prims.size(), -1);
    for (std::size_t i = 0; i < prims.size(); ++i) {
        std::optional<Prim> scratch;
        surfaceOf[i] = prims.at(i, scratch).surface;
    }
    std::vector<int> flat(surfaces.size(), -1);  // −1 not decided, 0 no, 1 yes
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (!prims.textured(i)) continue;
        const int surface = surfaceOf[i];
        if (surfaces[std::size_t(surface)].under) continue;
        for (std::size_t k = 0; k < lights; ++k) {
            const int slot = nearSlots[i * lights + k];
            if (slot < 0) continue;
            const Vec3 lc = prims.map(i).linearInverse() * near.slot(slot).lr;
            if (!(lc.z() > 1e-6)) continue;
            const Eigen::Vector2d reach = lc.head<2>() / lc.z();
            if (!(reach.cwiseAbs().maxCoeff() <= FloorShadowTable::kMaxReach)) continue;
            if (flat[std::size_t(surface)] < 0) flat[std::size_t(surface)] = flatField(prims, surface, surfaceOf) ? 1 : 0;
            if (!flat[std::size_t(surface)]) continue;
            // The cells a line from the floor can cross before the top: offsets over
            // [min(0, reach), max(1, 1 + reach)) along u and along v.
            const int u0 = int(std::floor(std::min(0.0, reach.x()))), u1 = int(std::ceil(std::max(1.0, 1 + reach.x()))) - 1;
            const int v0 = int(std::floor(std::min(0.0, reach.y()))), v1 = int(std::ceil(std::max(1.0, 1 + reach.y()))) - 1;
            bool ok = true;
            for (int du = u0; du <= u1 && ok; ++du)
                for (int dv = v0; dv <= v1 && ok; ++dv) {
                    const int p = walk(prims, adjacency, int(i), du, dv, true);
                    ok = p >= 0 && p == walk(prims, adjacency, int(i), du, dv, false) &&
                         nearSlots[std::size_t(p) * lights + k] == slot;
                }
            out[i * lights + k] = ok;
        }
    }
    return out;
}

}  // namespace vtex::render::detail
