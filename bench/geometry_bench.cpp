// Cost of the exact ray tests the texel renderer runs behind Embree's boxes: one ray against a
// bilinear patch, and against the six faces of a trilinear cell (cellSpans).
#include <vtex/render/geometry.h>

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace {

using namespace vtex::render;

Vec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<double> gauss;
    return Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
}

// Cells like the forest benchmark's: a unit face on a gently sloped, slightly bumpy hill, a shell
// as high as the face is wide, vertex normals tilted a little against each other.
TrilinearCell forestCell(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(-1, 1);
    const Vec3 slope(0.3 * u(rng), 0.3 * u(rng), 0);
    std::array<Vec3, 4> p = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
    std::array<Vec3, 4> n;
    for (std::size_t i = 0; i < 4; ++i) {
        p[i].z() = slope.x() * p[i].x() + slope.y() * p[i].y() + 0.05 * u(rng);
        n[i] = Vec3(-slope.x() + 0.1 * u(rng), -slope.y() + 0.1 * u(rng), 1).normalized();
    }
    return TrilinearCell(p, n, 1.0, false);
}

struct RayCase {
    TrilinearCell cell;
    Vec3 o, d;
};

// Rays from ~20 units away aimed at points of a box 20 % larger than the cell's: the cell is
// hit or narrowly missed, as for the cells whose Embree box a ray enters.
std::vector<RayCase> rayCases(std::size_t count) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u01(0, 1);
    std::vector<RayCase> cases;
    for (std::size_t k = 0; k < count; ++k) {
        RayCase c{forestCell(rng), {}, {}};
        Vec3 lo = c.cell.corners()[0], hi = lo;
        for (const Vec3& x : c.cell.corners()) {
            lo = lo.cwiseMin(x);
            hi = hi.cwiseMax(x);
        }
        const Vec3 mid = 0.5 * (lo + hi), half = 0.6 * (hi - lo);
        const Vec3 target = mid + Vec3((2 * u01(rng) - 1) * half.x(), (2 * u01(rng) - 1) * half.y(),
                                       (2 * u01(rng) - 1) * half.z());
        Vec3 away = randomUnit(rng);
        away.z() = std::abs(away.z()) + 0.2;  // from above the hill, like the camera and the light
        c.o = target + 20 * away.normalized();
        c.d = (target - c.o).normalized();
        cases.push_back(c);
    }
    return cases;
}

void BM_CellSpans(benchmark::State& state) {
    const auto cases = rayCases(1024);
    std::array<CellSpan, 4> spans;
    std::size_t i = 0;
    for (auto _ : state) {
        const RayCase& c = cases[i++ & 1023];
        benchmark::DoNotOptimize(cellSpans(c.cell, c.o, c.d, spans));
        benchmark::DoNotOptimize(spans);
    }
}
BENCHMARK(BM_CellSpans);

void BM_BilinearPatch(benchmark::State& state) {
    const auto cases = rayCases(1024);
    std::array<PatchHit, 2> hits;
    std::size_t i = 0;
    for (auto _ : state) {
        const RayCase& c = cases[i++ & 1023];
        const auto& x = c.cell.corners();
        benchmark::DoNotOptimize(
            intersectBilinearPatchAll(c.o, c.d, x[4], x[5], x[6], x[7], 0, 1e30, hits));
        benchmark::DoNotOptimize(hits);
    }
}
BENCHMARK(BM_BilinearPatch);

}  // namespace
