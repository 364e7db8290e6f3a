// The robustness tests' extreme scenes (fixtures.h, extremeScenes) measured against the
// explicit geometry (issue 15, "stability"): each drawn by the texel renderer with its defaults
// and by `vtex reference`, with a texel that has its source mesh, the error stated and bounded.
// render_test.cpp and reference_test.cpp check that the same scenes stay finite.
//
// The yardstick is the reference itself: a 64-spp reference is the truth, and the texel render
// at 4 spp should be about as close to it as the 4-spp reference is. All renders are
// deterministic, so the bounds sit a little above the measured values.
#include "bush_field.h"

#include <vtex/render/compare.h>
#include <vtex/render/reference.h>

#include <gtest/gtest.h>

#include <iostream>
#include <map>
#include <string>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

constexpr int kSize = 96;

struct Measured {
    double rmse = 0;         ///< the texel render at 4 spp against the 64-spp reference
    double reference4 = 0;   ///< the 4-spp reference against the 64-spp one
    double meanRatio = 1;    ///< mean radiance, texel render over the 64-spp reference
};

Measured measure(const Scene& scene) {
    vtex::NullProgress progress;
    ReferenceOptions reference;
    reference.spp = 64;
    const Image truth = renderReference(scene, reference, progress).image;
    reference.spp = 4;
    const Image quick = renderReference(scene, reference, progress).image;
    RenderOptions options;
    options.spp = 4;
    const Image texel = renderQuiet(scene, options).image;
    const ImageComparison c = compareImages(texel, truth);
    const double texelMean = c.meanA[0] + c.meanA[1] + c.meanA[2], truthMean = c.meanB[0] + c.meanB[1] + c.meanB[2];
    return {c.rmse, compareImages(quick, truth).rmse, texelMean / truthMean};
}

struct Bound {
    double rmseOverReference4;  ///< texel RMSE ≤ this × the 4-spp reference's
    double meanLow, meanHigh;   ///< the texel's mean over the reference's
};

}  // namespace

// Every case of extremeScenes with the small bush (its leaves are discs at the axis-ratio floor
// at the finest levels), τ = 1e6, and needles under a grazing light. Measured (RMSE / the 4-spp
// reference's RMSE, mean ratio):
//   grazing camera 0.79, 0.93; shell 1e-6 2.31, 0.82; shell 1e3 1.21, 0.92; collapsed edge 0.76,
//   0.99; twisted patch (opposite edges 80° apart) 0.81, 1.00; coordinates near 1e6 0.69, 1.00;
//   lights in the face's plane and inside the shell 0.68, 0.99; τ = 1e6 0.74, 0.99; needles under
//   a grazing light 0.31, 0.92 (collapsed edge 0.85, coordinates 0.87 before the mesh spans took
//   2 × 2 rays up to the finest faithful level + 1, 5 for this bush, whose mesh level is 4).
// τ = 1e6 was 1.92, 0.77 (2.31, 0.71 before the hybrid's camera blend over half a level and the
// mesh's shadows of its own hits) until the hybrid marched no level finer than
// kFinestMarchedLevel: no level lets through what the mesh does at that τ (the level fit's factor
// is clamped at 1/64, octree::fitShellChords), so the mesh level was the level of least error, 6,
// and the footprints coarser than that marched voxels that hide the gaps the mesh lets light
// and sight through; now the mesh, which τ does not touch, takes them.
// Bounds: RMSE ≤ 1.5× the 4-spp reference's and the mean within 12 %, except the case a texel
// cannot draw accurately, bounded by what it measures and why: a shell 1e-6 of its face, where
// every world ray crosses reference space vertically, so camera and light rays are parallel
// there: the camera sees exactly the leaves the light reaches (the hot spot). The mesh draws them
// lit; the volume darkens each by the extinction in front of it along the same path (volumetric
// self-shadowing at its largest).
TEST(ExtremeAccuracy, TexelRenderAgainstTheReferenceInExtremeScenes) {
    const SourcedTexel& bush = smallBush();
    // 150 `fur` hairs sampled at 32³: voxels of needles at the axis-ratio floor.
    const SourcedTexel fur = makeSourcedTexel("fur", 150, 32);
    auto cases = extremeScenes([&](Scene& s, std::shared_ptr<vtex::ingest::QuadMesh> m, double h) {
        addSurface(s, std::move(m), addSourcedTexel(s, bush), h);
    }, kSize);
    cases.emplace_back("tau 1e6", [&] {
        Scene s = baseScene(Eigen::Vector3d(0.5, -2, 1.5), Eigen::Vector3d(0.5, 0.5, 0), 40, kSize);
        addSurface(s, gridMesh(0, 0, 1, 1, 0), addSourcedTexel(s, bush, 1e6), 0.6);
        return s;
    });
    cases.emplace_back("needles under a grazing light", [&] {
        Scene s = baseScene(Eigen::Vector3d(0.5, -2, 1.5), Eigen::Vector3d(0.5, 0.5, 0), 40, kSize);
        s.lights[0].direction = Eigen::Vector3d(-1, 0.3, -0.15).normalized();
        addSurface(s, gridMesh(0, 0, 1, 1, 0, 2), addSourcedTexel(s, fur), 0.4, {2, 2});
        return s;
    });
    const Bound usual{1.5, 0.88, 1.12};
    const std::map<std::string, Bound> special = {{"shell 1e-6 of the face", {3.0, 0.72, 0.85}}};
    ASSERT_EQ(cases.size(), 9u);
    for (const auto& [name, make] : cases) {
        const Measured m = measure(make());
        const auto found = special.find(name);
        const Bound& b = found == special.end() ? usual : found->second;
        std::cout << name << ": RMSE " << m.rmse << " (4-spp reference " << m.reference4 << ", ratio " << m.rmse / m.reference4
                  << "), mean ratio " << m.meanRatio << "\n";
        EXPECT_LE(m.rmse, b.rmseOverReference4 * m.reference4) << name;
        EXPECT_GE(m.meanRatio, b.meanLow) << name;
        EXPECT_LE(m.meanRatio, b.meanHigh) << name;
    }
}
