// Cost per voxel of the renderer's shading inputs: the S matrix a voxel stores, and the fast
// micro-primitive reflectance. Inputs are drawn as in render_reflectance_error (σ ratios over
// four decades, random light and view) and cycled through 1024 of them, so branches and the
// specular cut-off see a realistic mix rather than one repeated case.
#include <vtex/octree/voxel.h>
#include <vtex/primitive/reflectance_kernel.h>

#include "bush_voxels.h"
#include "fibre_specular.h"

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

namespace {

using namespace vtex::primitive;

constexpr std::size_t kCases = 1024, kSegment = 8;

struct Cases {
    std::vector<vtex::octree::VoxelData> voxels;
    std::vector<SggxMatrix> s;
    std::vector<Eigen::Vector3d> light, view;
};

const Cases& cases() {
    static const Cases c = [] {
        Cases out;
        std::mt19937 rng(1);
        std::normal_distribution<double> n;
        std::uniform_real_distribution<double> logRatio(-4, 0);
        for (std::size_t k = 0; k < kCases; ++k) {
            const Eigen::Matrix3d r = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
            const Eigen::Vector3d sigma(std::pow(10.0, logRatio(rng)), std::pow(10.0, logRatio(rng)), 1.0);
            vtex::octree::VoxelData voxel;
            voxel.density = 1;
            vtex::octree::packEllipsoid(vtex::octree::Ellipsoid::fromAxes(r, sigma), voxel);
            out.voxels.push_back(voxel);
            out.s.push_back(vtex::octree::unpackS(voxel));
            // As along a ray segment through a cell: l and v change every kSegment voxels.
            if (k % kSegment == 0) {
                out.light.push_back(Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized());
                out.view.push_back(Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized());
            } else {
                out.light.push_back(out.light.back());
                out.view.push_back(out.view.back());
            }
        }
        return out;
    }();
    return c;
}

// The same light and view sequence over the S of a bush's stored voxels (bench/bush_voxels.h):
// what a render of the bush shades, where the random mix above is mostly needles and discs.
const Cases& bushCases() {
    static const Cases c = [] {
        Cases out = cases();
        std::mt19937 rng(1);
        const std::vector<Eigen::Matrix3d> shapes = vtex::bench::bushVoxels(rng, int(kCases));
        out.s.clear();
        for (std::size_t k = 0; k < kCases; ++k) out.s.push_back(SggxMatrix::fromUpper(shapes[k % shapes.size()]));
        out.voxels.clear();
        return out;
    }();
    return c;
}

void BM_UnpackS(benchmark::State& state) {
    const Cases& c = cases();
    std::size_t i = 0;
    for (auto _ : state) benchmark::DoNotOptimize(vtex::octree::unpackS(c.voxels[i++ & (kCases - 1)]));
}
BENCHMARK(BM_UnpackS);

// Everything per call: the basis around v and the light in it are rebuilt each time.
void fastOn(benchmark::State& state, const Cases& c) {
    const double shininess = double(state.range(0)) / 2;
    std::size_t i = 0;
    for (auto _ : state) {
        const std::size_t k = i++ & (kCases - 1);
        benchmark::DoNotOptimize(reflectanceFast(c.s[k], c.light[k], c.view[k], shininess));
    }
}
void BM_ReflectanceFast(benchmark::State& state) { fastOn(state, cases()); }
// Shininess 20 (the scene default) and 7.5; 100 and 1000, where the band rule takes the thick
// needles (primitive/src/band_specular.h).
BENCHMARK(BM_ReflectanceFast)->Arg(40)->Arg(15)->Arg(200)->Arg(2000);

// The bush's voxels at shininess 20 (the scene default) and 100.
void BM_ReflectanceFastBush(benchmark::State& state) { fastOn(state, bushCases()); }
BENCHMARK(BM_ReflectanceFastBush)->Arg(40)->Arg(200);

// A material without specular colour (the default): the kernel skips the Phong lobe's points
// and the fibre, so this must cost what the lattice alone did.
void BM_ReflectanceFastDiffuse(benchmark::State& state) {
    const Cases& c = cases();
    const double shininess = double(state.range(0)) / 2;
    std::size_t i = 0;
    for (auto _ : state) {
        const std::size_t k = i++ & (kCases - 1);
        benchmark::DoNotOptimize(reflectanceFast(c.s[k], c.light[k], c.view[k], shininess, 16, false));
    }
}
BENCHMARK(BM_ReflectanceFastDiffuse)->Arg(40);

// The renderer's case: one kernel per (l, v) along a ray segment, only S changes per call. The
// same 1024 (S, l, v) as above, with the kernels built before timing.
void kernelOn(benchmark::State& state, const Cases& c) {
    const double shininess = double(state.range(0)) / 2;
    std::vector<ReflectanceKernel> kernels;
    for (std::size_t k = 0; k < kCases; k += kSegment) kernels.emplace_back(c.light[k], c.view[k], shininess);
    std::size_t i = 0;
    for (auto _ : state) {
        const std::size_t k = i++ & (kCases - 1);
        benchmark::DoNotOptimize(kernels[k / kSegment](c.s[k]));
    }
}
void BM_ReflectanceKernel(benchmark::State& state) { kernelOn(state, cases()); }
BENCHMARK(BM_ReflectanceKernel)->Arg(40)->Arg(15);
void BM_ReflectanceKernelBush(benchmark::State& state) { kernelOn(state, bushCases()); }
BENCHMARK(BM_ReflectanceKernelBush)->Arg(40)->Arg(200);

// The random mix split by the fibre limit's gate at shininess 20 (the kernel's own test,
// detail::takesFibreLimit): needles on the fibre limit (477 of the 1024) and the rest, to see
// where the mix's time goes (docs/micro-primitive.md). Each set keeps its cases' order.
const Cases& splitCases(bool needles) {
    static const std::array<Cases, 2> split = [] {
        std::array<Cases, 2> out;
        const Cases& all = cases();
        const double gate = vtex::primitive::detail::fibreEigenRatioGate(20);
        for (std::size_t k = 0; k < kCases; ++k) {
            const Eigen::Matrix3d m = all.s[k].matrix();
            const bool needle = vtex::primitive::detail::takesFibreLimit(
                m.trace(), vtex::primitive::detail::adjugate(m).trace(), m.determinant(), gate);
            Cases& c = out[needle ? 1 : 0];
            c.s.push_back(all.s[k]);
            c.light.push_back(all.light[k]);
            c.view.push_back(all.view[k]);
        }
        return out;
    }();
    return split[needles ? 1 : 0];
}
// One kernel per case, built before timing (the cases' l and v no longer come in runs of eight).
void splitKernelOn(benchmark::State& state, bool needles) {
    const Cases& c = splitCases(needles);
    std::vector<ReflectanceKernel> kernels;
    for (std::size_t k = 0; k < c.s.size(); ++k) kernels.emplace_back(c.light[k], c.view[k], 20);
    std::size_t i = 0;
    for (auto _ : state) {
        const std::size_t k = i++ % c.s.size();
        benchmark::DoNotOptimize(kernels[k](c.s[k]));
    }
    state.counters["cases"] = double(c.s.size());
}
void BM_ReflectanceKernelNeedles(benchmark::State& state) { splitKernelOn(state, true); }
BENCHMARK(BM_ReflectanceKernelNeedles);
void BM_ReflectanceKernelNotNeedles(benchmark::State& state) { splitKernelOn(state, false); }
BENCHMARK(BM_ReflectanceKernelNotNeedles);

// What a ray segment pays once per light before its voxels: building the kernel.
void BM_ReflectanceKernelSetup(benchmark::State& state) {
    const Cases& c = cases();
    std::size_t i = 0;
    for (auto _ : state) {
        const std::size_t k = i++ & (kCases - 1);
        benchmark::DoNotOptimize(ReflectanceKernel(c.light[k], c.view[k], 20));
    }
}
BENCHMARK(BM_ReflectanceKernelSetup);

}  // namespace
