// Tracer (render/src/tracer.h): Embree's float BVH finds candidates, the double-precision cell
// and patch tests decide, a ray's span cache spares repeated cell tests, and a ray that is inside
// the primitives' bounds for no more than a hair past tNear is answered without Embree. Whatever
// the shortcuts, a trace must find what testing every primitive finds.
#include "fixtures.h"
#include "../../render/src/frame.h"

#include <gtest/gtest.h>

#include <random>

namespace vtex::render::test {
namespace {

// A twisted, sheared 3×3 grid of cells (no two alike) under a shell of 0.7, and a plain face
// beside it, higher up.
Scene tracerScene() {
    Scene scene = baseScene(Eigen::Vector3d(2, -6, 4), Eigen::Vector3d(2, 2, 0));
    const std::size_t texel = addTexel(scene, makeOctree(2, [](int x, int y, int z) {
        return (x + y + z) % 2 == 0 ? std::optional(sphereVoxel(2)) : std::nullopt;
    }));
    auto grid = gridMesh(0, 0, 3, 3, 0, 3);
    for (std::size_t v = 0; v < grid->positions.size(); ++v) grid->positions[v].z() = 0.1f * float(v % 5);
    addSurface(scene, grid, texel, 0.7, {1, 1});
    addSurface(scene, gridMesh(3, 0, 4, 1, 0.9), std::nullopt);
    return scene;
}

struct Found {
    int prim = -1;
    double t = 0, tOut = 0;  ///< tOut: where a cell's span ends
};

// Every primitive tested, the nearest kept: a cell by its first span that ends past tNear
// (entered at max(tIn, tNear)), a patch by its nearest hit past tNear.
Found bruteForce(const detail::PrimTable& prims, const Vec3& o, const Vec3& d, double tNear) {
    Found best;
    best.t = INFINITY;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (prims.textured(i)) {
            std::array<CellSpan, 4> spans;
            const int n = cellSpans(prims.cell(i), o, d, spans);
            for (int k = 0; k < n; ++k) {
                if (!(spans[std::size_t(k)].tOut > tNear)) continue;
                const double t = std::max(spans[std::size_t(k)].tIn, tNear);
                if (t < best.t) best = {int(i), t, spans[std::size_t(k)].tOut};
                break;
            }
        } else {
            const auto p = prims.patch(i);
            if (const auto h = intersectBilinearPatch(o, d, p[0], p[1], p[2], p[3], tNear, best.t))
                if (h->t < best.t) best = {int(i), h->t, h->t};
        }
    }
    return best;
}

// Rays of every kind (from far outside, from inside the shells, from the tops of the shells up
// toward a light, grazing), each walked from primitive to primitive as the renderers walk it,
// with its span cache: every step finds what testing every primitive finds, at the same t.
TEST(Tracer, EveryTraceFindsWhatTestingEveryPrimitiveFinds) {
    const Scene scene = tracerScene();
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene, false);
    const detail::Tracer& tracer = *geometry.tracer;
    const detail::PrimTable& prims = tracer.prims();
    std::mt19937_64 rng(12);
    std::uniform_real_distribution<double> u(0, 1);
    const auto unit = [&] {
        const double z = 2 * u(rng) - 1, phi = 2 * M_PI * u(rng), r = std::sqrt(1 - z * z);
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    int steps = 0, hits = 0, skippedHairs = 0;
    for (int ray = 0; ray < 3000; ++ray) {
        Vec3 o, d = unit();
        switch (ray % 3) {
            case 0: o = Vec3(-2 + 8 * u(rng), -2 + 7 * u(rng), -1 + 3 * u(rng)); break;  // anywhere
            case 1: {  // inside a cell
                const detail::Prim prim = prims[std::min<std::size_t>(8, std::size_t(9 * u(rng)))];
                o = prim.cell.map(Vec3(u(rng), u(rng), u(rng)));
                break;
            }
            default: {  // on the top of a cell's shell, up toward a light above
                const detail::Prim prim = prims[std::min<std::size_t>(8, std::size_t(9 * u(rng)))];
                o = prim.cell.map(Vec3(u(rng), u(rng), 1));
                d = Vec3(d.x(), d.y(), 0.2 + std::abs(d.z())).normalized();
            }
        }
        detail::SpanCache cache;
        double tNear = 0;
        for (int step = 0; step < 64; ++step) {
            ++steps;
            const auto hit = tracer.trace(o, d, tNear, INFINITY, &cache);
            const Found want = bruteForce(prims, o, d, tNear);
            if (!hit) {
                // Answered without Embree only where what is left of the ray inside the bounds
                // is a hair: a span that ends within 1e-9 of the scene's size past tNear.
                if (want.prim >= 0) {
                    EXPECT_LE(want.tOut - tNear, 1e-8) << "ray " << ray << " step " << step << " missed primitive " << want.prim;
                    ++skippedHairs;
                }
                break;
            }
            ++hits;
            ASSERT_GE(want.prim, 0) << "ray " << ray << " step " << step << " hit primitive " << hit->prim << " that is not there";
            EXPECT_NEAR(hit->t, want.t, 1e-12 * (1 + want.t)) << "ray " << ray << " step " << step;
            if (hit->prim != want.prim) {
                EXPECT_NEAR(hit->t, want.t, 1e-12) << "a different primitive, not at a tie";
            }
            if (!prims.textured(std::size_t(hit->prim))) break;  // opaque
            EXPECT_NEAR(hit->span.tOut, want.tOut, 1e-12 * (1 + want.tOut));
            tNear = hit->span.tOut;
        }
    }
    // Many hits, and walks across several cells.
    EXPECT_GT(hits, 2000);
    EXPECT_GT(steps, 4000);
    std::printf("%d traces, %d hits, %d answered without Embree where a hair of a span was left\n", steps, hits,
                skippedHairs);
}

}  // namespace
}  // namespace vtex::render::test
