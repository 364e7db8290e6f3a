// Lighting measured at load (texel_runtime.cpp, measureLighting): with the levels fitted, a dense
// texel's shadows are not forced onto the fine levels where its voxels darken the leaves they
// stand for, and the hybrid's mesh takes over where those levels would light what is seen too
// little.
#include "bush_field.h"

#include <vtex/render/source_visibility.h>

#include <vtex/core/progress.h>
#include <vtex/render/reference.h>
#include <vtex/render/renderer.h>

#include <gtest/gtest.h>

#include <iostream>

namespace vtex::render::test {
namespace {

// A 4×4 field of the dense bush seen from `distance` along the benchmark's middle direction, lit,
// its ground black: the image is the leaves' light alone.
Scene denseBushField(const SourcedTexel& bush, double distance) {
    Scene scene = baseScene(Eigen::Vector3d(0.5, 0.5, 0.4) + distance * Eigen::Vector3d(0.43, -0.75, 0.5).normalized(),
                            Eigen::Vector3d(0.5, 0.5, 0.4), 40, 96);
    scene.lights[0].direction = Eigen::Vector3d(-1, -0.5, -1).normalized();
    const auto texel = addSourcedTexel(scene, bush);
    scene.texels[texel].material.specular = Color::Zero();
    addSurface(scene, gridMesh(-1.5, -1.5, 2.5, 2.5, 0, 4), texel, 1.0);
    scene.surfaces.back().material.diffuse = Color::Zero();
    scene.surfaces.back().material.specular = Color::Zero();
    return scene;
}

// The dense bush (8 000 leaves at 64³: a fine voxel holds several overlapping leaves), built once.
const SourcedTexel& denseBush() {
    static const SourcedTexel bush = makeBush(8000, 64);
    return bush;
}

// The texel render at 4 spp and its leaves' light against the reference's (64 spp), as the green
// channel's relative bias.
struct LeavesRender {
    RenderResult render;
    double bias = 0;
};
LeavesRender renderLeaves(const Scene& scene) {
    RenderOptions options;
    options.spp = 4;
    LeavesRender out{renderQuiet(scene, options), 0.0};
    ReferenceOptions referenceOptions;
    referenceOptions.spp = 64;
    vtex::NullProgress progress;
    const Image reference = renderReference(scene, referenceOptions, progress).image;
    out.bias = imageMean(out.render.image)[1] / imageMean(reference)[1] - 1;
    return out;
}

// A 4×4 field of a dense bush (8 000 leaves at 64³: a fine voxel holds several overlapping
// leaves), lit, its ground black: the image is the leaves' light alone. The rule without the fit
// keeps shadows at the coarsest level whose mean density lets through what the mesh does, here
// level 5 of 0–6, where every lit voxel shadows its own leaves: −16.9 % against the reference
// (4 spp texel, 64 spp reference; measured by forcing that rule in a throw-away build). The
// measured shadow levels (5 5 4 4 4 for footprint levels 0–4; the camera's mean level is 4.2)
// light the leaves within 10 % (measured −2.1 %).
TEST(ShadowLevels, ADenseBushIsLitAsItsMeshWhenItsShadowsAreMeasured) {
    const auto [texelRender, bias] = renderLeaves(denseBushField(denseBush(), 14));
    ASSERT_EQ(texelRender.stats.shadowLevels.size(), 1u);
    const std::vector<int>& levels = texelRender.stats.shadowLevels[0];
    std::cout << "leaves' light " << bias * 100 << " % (mean level " << texelRender.stats.meanLevel() << ", shadow levels";
    for (int l : levels) std::cout << " " << l;
    std::cout << ")\n";
    // One level per footprint level below the coarsest faithful one, each between the
    // footprint's level and that one.
    ASSERT_FALSE(levels.empty());
    for (std::size_t f = 0; f < levels.size(); ++f) {
        EXPECT_GE(levels[f], int(f));
        EXPECT_LE(levels[f], int(levels.size()));
    }
    EXPECT_LT(std::abs(bias), 0.10);
}

// The hybrid's mesh level from the lighting (texel_runtime.cpp, meshLevelFrom). The same dense
// bush's faithful levels are 5 and 6 (chord errors −0.015, −0.002), so the rule by chords alone
// would march level 6 before the mesh; but camera level 6, lit through shadow level 5, is lit
// 0.036 less often than the mesh (of 0.44: −8 %) where level 5 is within 0.005, so the mesh takes
// over from level 5. Near (a cell ≈ 33 px, footprint levels ≈ 5–6), the leaves' light is within
// 3 % of the reference's (4 spp against 64; measured −0.1 %), where the mesh level 6 of the chords
// alone gives −10.2 % (measured by forcing it in a throw-away build).
TEST(ShadowLevels, TheMeshTakesOverWhereAFinerLevelLightsTheLeavesTooLittle) {
    const SourcedTexel& bush = denseBush();
    const SourceVisibility visibility(*bush.mesh, bush.tree->info.source);
    const auto visible = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return visibility.visible(a, b); };
    const FaithfulLevels faithful =
        faithfulLevels(octree::measureChordTransmittance(*bush.tree, visible), RenderOptions{}.hybridTolerance);
    const auto [texelRender, bias] = renderLeaves(denseBushField(bush, 4));
    ASSERT_EQ(texelRender.stats.meshLevels.size(), 1u);
    std::cout << "near: leaves' light " << bias * 100 << " % (mean level " << texelRender.stats.meanLevel()
              << ", mesh level " << texelRender.stats.meshLevels[0] << ", faithful levels " << faithful.coarsest << "–"
              << faithful.finest << ", mesh share " << texelRender.stats.meshSegments << ")\n";
    EXPECT_LT(texelRender.stats.meshLevels[0], double(faithful.finest));
    EXPECT_GE(texelRender.stats.meshLevels[0], double(faithful.coarsest) - 1);
    EXPECT_LT(std::abs(bias), 0.03);
}

}  // namespace
}  // namespace vtex::render::test
