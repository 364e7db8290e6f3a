// Shadows at the level that lights what is seen (texel_runtime.cpp, measuredShadowLevels): with
// the levels fitted, a dense texel's shadows are not forced onto the fine levels where its
// voxels darken the leaves they stand for.
#include "bush_field.h"

#include <vtex/core/progress.h>
#include <vtex/render/reference.h>
#include <vtex/render/renderer.h>

#include <gtest/gtest.h>

#include <iostream>

namespace vtex::render::test {
namespace {

// A 4×4 field of a dense bush (8 000 leaves at 64³: a fine voxel holds several overlapping
// leaves), lit, its ground black: the image is the leaves' light alone. The rule without the fit
// keeps shadows at the coarsest level whose mean density lets through what the mesh does, here
// level 5 of 0–6, where every lit voxel shadows its own leaves: −16.9 % against the reference
// (4 spp texel, 64 spp reference; measured by forcing that rule in a throw-away build). The
// measured shadow levels (5 5 4 4 4 for footprint levels 0–4; the camera's mean level is 4.2)
// light the leaves within 10 % (measured −2.1 %).
TEST(ShadowLevels, ADenseBushIsLitAsItsMeshWhenItsShadowsAreMeasured) {
    const SourcedTexel bush = makeBush(8000, 64);
    Scene scene = baseScene(Eigen::Vector3d(0.5, 0.5, 0.4) + 14 * Eigen::Vector3d(0.43, -0.75, 0.5).normalized(),
                            Eigen::Vector3d(0.5, 0.5, 0.4), 40, 96);
    scene.lights[0].direction = Eigen::Vector3d(-1, -0.5, -1).normalized();
    const auto texel = addSourcedTexel(scene, bush);
    scene.texels[texel].material.specular = Color::Zero();
    addSurface(scene, gridMesh(-1.5, -1.5, 2.5, 2.5, 0, 4), texel, 1.0);
    scene.surfaces.back().material.diffuse = Color::Zero();
    scene.surfaces.back().material.specular = Color::Zero();
    RenderOptions options;
    options.spp = 4;
    const RenderResult texelRender = renderQuiet(scene, options);
    ReferenceOptions referenceOptions;
    referenceOptions.spp = 64;
    vtex::NullProgress progress;
    const Image reference = renderReference(scene, referenceOptions, progress).image;
    const double bias = imageMean(texelRender.image)[1] / imageMean(reference)[1] - 1;
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

}  // namespace
}  // namespace vtex::render::test
