// Cost of the micro-primitive's operations: A(ω) and f(N) run per voxel per ray step in the
// renderer, filtering per octree node, reflectance per shaded voxel.
#include <vtex/octree/filtering.h>
#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/reflectance.h>

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace {

using namespace vtex::octree;
using namespace vtex::primitive;

std::vector<Vec3> randomDirections(std::size_t count, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> gauss;
    std::vector<Vec3> directions(count);
    for (auto& d : directions) d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    return directions;
}

Ellipsoid randomEllipsoid(std::mt19937& rng) {
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> axis(0.01, 1.0);
    const Mat3 R = Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized().toRotationMatrix();
    return Ellipsoid::fromAxes(R, Vec3(axis(rng), axis(rng), axis(rng)));
}

// A per-direction evaluation of one primitive, over 1024 precomputed directions.
template <double (Ellipsoid::*evaluate)(const Vec3&) const>
void BM_EvaluateDirection(benchmark::State& state) {
    std::mt19937 rng(1);
    const Ellipsoid e = randomEllipsoid(rng);
    const auto directions = randomDirections(1024, 2);
    std::size_t i = 0;
    for (auto _ : state) benchmark::DoNotOptimize((e.*evaluate)(directions[i++ & 1023]));
}
BENCHMARK_TEMPLATE(BM_EvaluateDirection, &Ellipsoid::projectedArea)->Name("BM_ProjectedArea");
BENCHMARK_TEMPLATE(BM_EvaluateDirection, &Ellipsoid::normalDistribution)->Name("BM_NormalDistribution");

void BM_ConstructFromS(benchmark::State& state) {
    std::mt19937 rng(4);
    const Mat3 S = randomEllipsoid(rng).S();
    for (auto _ : state) benchmark::DoNotOptimize(Ellipsoid::fromS(S));
}
BENCHMARK(BM_ConstructFromS);

void BM_Filter8Children(benchmark::State& state) {
    std::mt19937 rng(5);
    std::vector<Ellipsoid> children;
    std::vector<double> weights;
    std::uniform_real_distribution<double> weight(0.1, 1.0);
    for (int k = 0; k < 8; ++k) {
        children.push_back(randomEllipsoid(rng));
        weights.push_back(weight(rng));
    }
    const auto rule = state.range(0) == 0 ? FilterRule::Neyret : FilterRule::Sggx;
    state.SetLabel(rule == FilterRule::Neyret ? "neyret" : "sggx");
    for (auto _ : state) benchmark::DoNotOptimize(filterEllipsoids(children, weights, rule));
}
BENCHMARK(BM_Filter8Children)->Arg(0)->Arg(1);

void BM_FilterError8Children(benchmark::State& state) {
    std::mt19937 rng(6);
    std::vector<Ellipsoid> children;
    std::vector<double> weights(8, 1.0);
    for (int k = 0; k < 8; ++k) children.push_back(randomEllipsoid(rng));
    const Ellipsoid result = *filterEllipsoids(children, weights, FilterRule::Sggx);
    for (auto _ : state) benchmark::DoNotOptimize(filterError(result, children, weights));
}
BENCHMARK(BM_FilterError8Children);

void BM_ReflectanceApparentEllipse(benchmark::State& state) {
    std::mt19937 rng(7);
    const Ellipsoid e = randomEllipsoid(rng);
    const auto d = randomDirections(2, 8);
    const int samples = int(state.range(0));
    for (auto _ : state)
        benchmark::DoNotOptimize(phongReflectanceApparentEllipse(e, d[0], d[1], 20, samples));
}
BENCHMARK(BM_ReflectanceApparentEllipse)->Arg(8)->Arg(16)->Arg(32)->Arg(64);

void BM_ReflectanceNormalQuadrature(benchmark::State& state) {
    std::mt19937 rng(7);
    const Ellipsoid e = randomEllipsoid(rng);
    const auto d = randomDirections(2, 8);
    const int rings = int(state.range(0));
    for (auto _ : state)
        benchmark::DoNotOptimize(phongReflectanceNormalQuadrature(e, d[0], d[1], 20, rings));
}
BENCHMARK(BM_ReflectanceNormalQuadrature)->Arg(8)->Arg(16)->Arg(32)->Arg(64);

}  // namespace
