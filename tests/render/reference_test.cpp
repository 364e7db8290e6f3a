// The explicit-geometry reference renderer (`vtex reference`): golden values derived by hand,
// its two modes against each other, and the texel renderer against it on opaque cubes.
#include "fixtures.h"

#include <vtex/core/error.h>
#include <vtex/core/memory_budget.h>
#include <vtex/octree/octree.h>
#include <vtex/render/compare.h>
#include <vtex/render/reference.h>
#include <vtex/sampler/sampler.h>

#include <gtest/gtest.h>

#include <numbers>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

std::shared_ptr<vtex::ingest::TriangleMesh> meshOf(const std::vector<Eigen::Vector3f>& positions,
                                                   const std::vector<std::array<std::uint32_t, 3>>& triangles) {
    auto mesh = std::make_shared<vtex::ingest::TriangleMesh>();
    mesh->positions = positions;
    mesh->normals.assign(positions.size(), Eigen::Vector3f(0, 0, 1));
    mesh->triangles = triangles;
    mesh->materials.emplace_back();
    return mesh;
}

// The plane z = a·x + b over the unit square, as two triangles.
std::shared_ptr<vtex::ingest::TriangleMesh> sheet(float a, float b) {
    return meshOf({{0, 0, b}, {1, 0, a + b}, {1, 1, a + b}, {0, 1, b}}, {{0, 1, 2}, {0, 2, 3}});
}

// The closed box [lo, hi]³, outward-facing.
std::shared_ptr<vtex::ingest::TriangleMesh> box(float lo, float hi) {
    std::vector<Eigen::Vector3f> p;
    for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? hi : lo, i & 2 ? hi : lo, i & 4 ? hi : lo);
    auto mesh = meshOf(p, {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                           {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}});
    mesh->closed = true;
    return mesh;
}

// An octree that only carries the placement of its source (identity, cyclic or not): what the
// reference renderer reads from a texel's volume.
std::shared_ptr<const vtex::octree::Octree> placementOnly(bool cyclic) {
    auto tree = std::make_shared<vtex::octree::Octree>(*makeOctree(1, [](int, int, int) { return std::nullopt; }));
    tree->info.source.cyclic = cyclic;
    return tree;
}

std::size_t addSourceTexel(Scene& scene, std::shared_ptr<const vtex::ingest::TriangleMesh> mesh,
                           std::shared_ptr<const vtex::octree::Octree> tree) {
    const std::size_t texel = addTexel(scene, std::move(tree));
    scene.texels[texel].sourceData = std::move(mesh);
    return texel;
}

RenderResult referenceQuiet(const Scene& scene, ReferenceOptions options) {
    vtex::NullProgress progress;
    return renderReference(scene, options, progress);
}

// A scene seen straight from above, lit straight from above with irradiance E = 2.
Scene topDown(int size) {
    Scene scene = baseScene(Eigen::Vector3d(0.5, 0.5, 6), Eigen::Vector3d(0.5, 0.5, 0), 8, size);
    scene.lights[0].direction = Eigen::Vector3d(0, 0, -1);
    scene.lights[0].color = Color(2, 2, 2);
    return scene;
}

Color centre(const Image& image) {
    const std::size_t i = std::size_t(image.height / 2) * std::size_t(image.width) + std::size_t(image.width / 2);
    return {image.rgba[4 * i], image.rgba[4 * i + 1], image.rgba[4 * i + 2]};
}

}  // namespace

// A horizontal source sheet in a flat cell: Lambertian radiance kd/π·E·cosθ with θ = 0.
TEST(Reference, FlatSheetHasTheLambertianRadiance) {
    Scene scene = topDown(16);
    const auto texel = addSourceTexel(scene, sheet(0, 0.5f), placementOnly(false));
    scene.texels[texel].material.diffuse = Color(0.5, 0.25, 1);
    addSurface(scene, gridMesh(0, 0, 1, 1, 0), texel, 0.3);
    for (const ReferenceMode mode : {ReferenceMode::Embedded, ReferenceMode::Deformed}) {
        ReferenceOptions options;
        options.spp = 4;
        options.mode = mode;
        const Color c = centre(referenceQuiet(scene, options).image);
        const Color expected = Color(0.5, 0.25, 1) * (2 / std::numbers::pi);
        EXPECT_NEAR(c.x(), expected.x(), 1e-5);
        EXPECT_NEAR(c.y(), expected.y(), 1e-5);
        EXPECT_NEAR(c.z(), expected.z(), 1e-5);
    }
}

// A sheet at 45° in reference space, in a cell half as high as it is wide: in the world it
// rises 1 in 2, so its normal makes cos θ = 2/√5 with the vertical light. The normal goes to
// the world through the inverse transpose of the Jacobian; the plain Jacobian would give
// another angle.
TEST(Reference, NormalsFollowTheCellsDeformation) {
    Scene scene = topDown(16);
    const auto texel = addSourceTexel(scene, sheet(1, 0), placementOnly(false));
    addSurface(scene, gridMesh(0, 0, 1, 1, 0), texel, 0.5);
    for (const ReferenceMode mode : {ReferenceMode::Embedded, ReferenceMode::Deformed}) {
        ReferenceOptions options;
        options.spp = 1;
        options.mode = mode;
        const Color c = centre(referenceQuiet(scene, options).image);
        EXPECT_NEAR(c.x(), 1 / std::numbers::pi * 2 * (2 / std::sqrt(5.0)), 1e-5);
    }
}

// Two independent routes to the same picture: carrying rays into one shared BVH (instances for
// the cyclic wrap, segments cut per repeated copy), and clipping and deforming the mesh into
// every cell. On flat, unskewed cells the map is affine and the straight segment exact, so
// they agree to the float rounding of the two BVHs.
TEST(Reference, EmbeddedAndDeformedAgreeOnFlatCells) {
    Scene scene = baseScene(Eigen::Vector3d(1.2, -2.5, 2.2), Eigen::Vector3d(1, 1, 0.2), 40, 64);
    // Slanted triangles, some sticking out of the unit square (wrapped: the volume is cyclic),
    // and a closed box.
    auto mesh = meshOf({{-0.2f, 0.1f, 0.1f}, {0.5f, 0.3f, 0.9f}, {0.3f, 0.9f, 0.4f},
                        {0.7f, 0.6f, 0.2f}, {1.3f, 0.8f, 0.6f}, {0.9f, 1.2f, 0.8f}},
                       {{0, 1, 2}, {3, 4, 5}});
    const auto cube = box(0.55f, 0.8f);
    for (const auto& p : cube->positions) mesh->positions.push_back(p - Eigen::Vector3f(0.3f, 0.4f, 0.5f));
    for (const auto& t : cube->triangles) mesh->triangles.push_back({t[0] + 6, t[1] + 6, t[2] + 6});
    mesh->normals.assign(mesh->positions.size(), Eigen::Vector3f(0, 0, 1));
    const auto texel = addSourceTexel(scene, mesh, placementOnly(true));
    scene.texels[texel].material.specular = Color(0.2, 0.2, 0.2);
    addSurface(scene, gridMesh(0, 0, 2, 2, 0, 2), texel, 0.6, {2, 1.5});
    ReferenceOptions options;
    options.spp = 4;
    const Image embedded = referenceQuiet(scene, options).image;
    options.mode = ReferenceMode::Deformed;
    const Image deformed = referenceQuiet(scene, options).image;
    const ImageComparison c = compareImages(embedded, deformed);
    // Edges sampled on either side of a float-rounded triangle boundary: a few pixels out of
    // 4096 differ by one sample of 4.
    EXPECT_LT(c.rmse, 0.01) << "worst (" << c.worstX << ", " << c.worstY << ") " << c.worstError;
    double meanLuminance = 0;
    for (std::size_t i = 0; i < embedded.pixels(); ++i) meanLuminance += embedded.rgba[4 * i + 1];
    EXPECT_GT(meanLuminance / double(embedded.pixels()), 0.05);  // the scene is not empty
}

// The test: on voxel-aligned opaque cubes, the texel render at the finest level and the
// reference agree. The cube's faces are sampled into disc primitives (the normals' fit), its
// inside into solid blocks; both renders take 16 samples per pixel.
TEST(Reference, TexelRenderOfOpaqueCubesMatchesTheReference) {
    // Voxels [2, 6) of 8³, the faces moved in by 1/1024: the sampler's voxels are half-open, so a
    // face exactly on x = 6 would be sampled into the voxel outside the cube.
    const auto cube = box(0.25f + 1.0f / 1024, 0.75f - 1.0f / 1024);
    vtex::sampler::SampleOptions sampling;
    sampling.resolution = 8;
    sampling.solid = vtex::sampler::SolidMode::On;
    vtex::NullProgress progress;
    const auto volume = vtex::sampler::sampleMesh(*cube, sampling, progress);
    const auto tree = std::make_shared<const vtex::octree::Octree>(vtex::octree::buildOctree(volume, {}, progress));

    Scene scene = baseScene(Eigen::Vector3d(-1.3, -2.4, 2.6), Eigen::Vector3d(1, 1, 0.3), 35, 64);
    const auto texel = addSourceTexel(scene, cube, tree);
    scene.texels[texel].tau = 16;  // opaque: optical depth ~8 across half a face voxel
    addSurface(scene, gridMesh(0, 0, 2, 2, 0, 2), texel, 1.0);
    RenderOptions texelOptions;
    texelOptions.spp = 16;
    texelOptions.lodBias = -8;  // the finest level everywhere
    texelOptions.hybrid = false;  // the volume against the mesh, not the mesh against itself
    const Image texelImage = renderQuiet(scene, texelOptions).image;
    ReferenceOptions referenceOptions;
    referenceOptions.spp = 16;
    const Image referenceImage = referenceQuiet(scene, referenceOptions).image;

    double coverage = 0, coverageDifference = 0, meanTexel = 0, meanReference = 0;
    for (std::size_t i = 0; i < texelImage.pixels(); ++i) {
        coverage += referenceImage.rgba[4 * i + 3];
        coverageDifference += std::abs(texelImage.rgba[4 * i + 3] - referenceImage.rgba[4 * i + 3]);
        for (std::size_t k = 0; k < 3; ++k) {
            meanTexel += texelImage.rgba[4 * i + k];
            meanReference += referenceImage.rgba[4 * i + k];
        }
    }
    ASSERT_GT(coverage, 0.25 * double(texelImage.pixels()));  // the cells fill a third of the image
    const ImageComparison c = compareImages(texelImage, referenceImage);
    std::cout << "opaque cubes: RMSE " << c.rmse << ", SSIM " << c.ssim << ", coverage difference "
              << coverageDifference / double(texelImage.pixels()) << ", mean radiance " << meanTexel / double(3 * texelImage.pixels())
              << " (texel) vs " << meanReference / double(3 * texelImage.pixels()) << " (reference)\n";
    // Tolerances (measured: coverage difference 0.21 %, RMSE 0.18, texel mean 0.56 × the
    // reference's): silhouettes within a fraction of the edge pixels (≤ 0.5 %), shading within
    // RMSE 0.2 and the mean within [0.5, 1.1] of the reference's. The shading is the texel
    // model's weak point on hard faces: a face voxel holds the face at its border but is shaded
    // and shadowed from its middle, its shadow ray counts the voxel's own extinction again
    // (docs/reference.md, "What the comparisons found"), and the voxels on the cube's edges
    // carry one disc fitted to two faces.
    EXPECT_LT(coverageDifference / double(texelImage.pixels()), 0.005);
    EXPECT_LT(c.rmse, 0.2) << "worst (" << c.worstX << ", " << c.worstY << ") " << c.worstError;
    EXPECT_GT(meanTexel / meanReference, 0.5);
    EXPECT_LT(meanTexel / meanReference, 1.1);
}

TEST(Reference, SameImageWhateverTheThreadCount) {
    Scene scene = baseScene(Eigen::Vector3d(0.5, -2, 2), Eigen::Vector3d(0.5, 0.5, 0.3), 40, 48);
    const auto texel = addSourceTexel(scene, box(0.3f, 0.7f), placementOnly(false));
    addSurface(scene, gridMesh(0, 0, 1, 1, 0), texel, 1.0);
    ReferenceOptions options;
    options.spp = 9;
    options.threads = 1;
    const Image one = referenceQuiet(scene, options).image;
    options.threads = 2;
    const Image two = referenceQuiet(scene, options).image;
    EXPECT_EQ(one.rgba, two.rgba);
}

TEST(Reference, TexelWithoutSourceIsRefused) {
    Scene scene = topDown(8);
    scene.file = "scene.toml";
    const auto texel = addTexel(scene, placementOnly(false));
    addSurface(scene, gridMesh(0, 0, 1, 1, 0), texel, 0.3);
    try {
        referenceQuiet(scene, {});
        FAIL() << "expected an InputError";
    } catch (const vtex::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("texel.source"), std::string::npos) << e.what();
    }
}

TEST(Reference, DeformedSceneOverTheMemoryLimitIsRefused) {
    Scene scene = topDown(8);
    scene.file = "scene.toml";
    const auto texel = addSourceTexel(scene, box(0.3f, 0.7f), placementOnly(false));
    addSurface(scene, gridMesh(0, 0, 1, 1, 0, 8), texel, 0.3, {100, 100});
    ReferenceOptions options;
    options.mode = ReferenceMode::Deformed;
    // 64 cells × 10⁴ copies × 12 triangles do not fit in 64 MiB; the image and the scene do.
    options.maxMemoryBytes = 64 << 20;
    try {
        referenceQuiet(scene, options);
        FAIL() << "expected a MemoryLimitError";
    } catch (const vtex::MemoryLimitError& e) {
        EXPECT_NE(std::string(e.what()).find("--mode embedded"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("triangles"), std::string::npos) << e.what();
    }
    options.mode = ReferenceMode::Embedded;  // one copy of the mesh whatever the repeat
    EXPECT_TRUE(allFinite(referenceQuiet(scene, options).image));
}

// The renderer test's extreme scenes, drawn by the reference in both modes: something drawn, no
// NaN or Inf, a coverage in [0, 1], whatever the cell (a collapsed edge, a twist, a shell 1e-6 or 1e3 times
// as high as the face), the coordinates or the lights.
TEST(Reference, ExtremeScenesStayFinite) {
    auto source = box(0.3f, 0.7f);
    for (const auto& p : std::vector<Eigen::Vector3f>{{0.05f, 0.1f, 0.1f}, {0.95f, 0.12f, 0.9f}, {0.5f, 0.11f, 0.95f}})
        source->positions.push_back(p);
    source->triangles.push_back({8, 9, 10});  // a sliver, nearly edge-on to the camera
    source->normals.assign(source->positions.size(), Eigen::Vector3f(0, 0, 1));
    const auto cases = extremeScenes([&](Scene& s, std::shared_ptr<vtex::ingest::QuadMesh> m, double h) {
        addSurface(s, std::move(m), addSourceTexel(s, source, placementOnly(false)), h);
    }, 24);
    for (const auto& [name, make] : cases)
        for (const ReferenceMode mode : {ReferenceMode::Embedded, ReferenceMode::Deformed}) {
            ReferenceOptions o;
            o.spp = 4;
            o.aovs = true;
            o.mode = mode;
            const RenderResult r = referenceQuiet(make(), o);
            const char* modeName = mode == ReferenceMode::Embedded ? "embedded" : "deformed";
            EXPECT_TRUE(allFinite(r.image)) << name << ", " << modeName;
            double coverage = 0;
            for (std::size_t i = 0; i < r.image.pixels(); ++i) coverage += r.image.rgba[4 * i + 3];
            EXPECT_GT(coverage, 0) << name << ", " << modeName << ": every case must draw something";
            for (std::size_t i = 0; i < r.image.pixels(); ++i) {
                ASSERT_TRUE(std::isfinite(r.image.depth[i])) << name << ", " << modeName;
                ASSERT_GE(r.image.rgba[4 * i + 3], 0.f) << name << ", " << modeName;
                ASSERT_LE(r.image.rgba[4 * i + 3], 1.f + 1e-6f) << name << ", " << modeName;
            }
        }
}
