// Row ranges (ImageOptions::rowBegin, issue 18): a render split into row ranges rendered apart
// stacks into the whole render float for float, AOVs included, for the texel renderer (with and
// without the shadow lattice, the hybrid and the fitted levels) and the reference renderer; bad
// ranges are refused.
#include "bush_field.h"
#include "fixtures.h"

#include <vtex/render/reference.h>

#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <set>
#include <stdexcept>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

// Row cuts that are not multiples of the renderers' 16-pixel tiles, in an image whose height
// and width are not either: a range that reused the whole image's tile grid, or sampled rows
// relative to the range, would show.
constexpr int kWidth = 47, kHeight = 61;
constexpr int kCuts[] = {0, 13, 38, kHeight};

using Renderer = std::function<RenderResult(int rowBegin, int rowEnd)>;

// The ranges' images stacked top to bottom.
Image stack(const std::vector<Image>& parts) {
    Image whole;
    whole.width = parts.at(0).width;
    for (const Image& part : parts) {
        EXPECT_EQ(part.width, whole.width);
        whole.height += part.height;
        whole.rgba.insert(whole.rgba.end(), part.rgba.begin(), part.rgba.end());
        whole.depth.insert(whole.depth.end(), part.depth.begin(), part.depth.end());
        whole.level.insert(whole.level.end(), part.level.begin(), part.level.end());
    }
    return whole;
}

bool sameFloats(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Renders the whole image and the ranges of kCuts, and checks that the ranges' images have their
// rows only and stack into the whole one exactly, and that their counters (all per pixel) add
// up to the whole render's.
void expectRangesStackIntoTheWhole(const Renderer& render) {
    const RenderResult whole = render(0, 0);
    ASSERT_EQ(whole.image.width, kWidth);
    ASSERT_EQ(whole.image.height, kHeight);
    ASSERT_TRUE(whole.image.hasAovs());
    // Rows that differ from one another (the scene is seen, lit and shadowed), so that a range
    // rendered at the wrong rows would show.
    EXPECT_GT(std::set<float>(whole.image.rgba.begin(), whole.image.rgba.end()).size(), 500u);
    std::vector<Image> parts;
    std::uint64_t primary = 0, shadow = 0, voxels = 0;
    for (std::size_t i = 0; i + 1 < std::size(kCuts); ++i) {
        RenderResult part = render(kCuts[i], kCuts[i + 1]);
        EXPECT_EQ(part.image.height, kCuts[i + 1] - kCuts[i]);
        EXPECT_EQ(part.stats.height, kHeight);  // the full image's size, and the range rendered
        EXPECT_EQ(part.stats.rowBegin, kCuts[i]);
        EXPECT_EQ(part.stats.rowEnd, kCuts[i + 1]);
        primary += part.stats.primaryRays;
        shadow += part.stats.shadowRays;
        voxels += part.stats.voxelsVisited;
        parts.push_back(std::move(part.image));
    }
    const Image stacked = stack(parts);
    EXPECT_EQ(stacked.height, kHeight);
    EXPECT_TRUE(sameFloats(stacked.rgba, whole.image.rgba));
    EXPECT_TRUE(sameFloats(stacked.depth, whole.image.depth));
    EXPECT_TRUE(sameFloats(stacked.level, whole.image.level));
    EXPECT_EQ(primary, whole.stats.primaryRays);
    EXPECT_EQ(shadow, whole.stats.shadowRays);
    EXPECT_EQ(voxels, whole.stats.voxelsVisited);
}

// A texel of spheres on two faces beside a plain one, lit by a point light only (no lattice).
Scene pointLitTexels() {
    Scene scene = baseScene(Eigen::Vector3d(0.9, -1.6, 1.4), Eigen::Vector3d(0.9, 0.5, 0.1), 45);
    scene.lights[0].type = LightType::Point;
    scene.lights[0].position = Eigen::Vector3d(0.3, -0.4, 2.5);
    const auto tree = makeOctree(4, [](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        if ((x + 2 * y + 3 * z) % 5 != 0 || z > 9) return std::nullopt;
        return sphereVoxel(6.0f, {0.7f, 0.5f, 0.3f});
    });
    addSurface(scene, gridMesh(0, 0, 1.2, 1, 0, 2), addTexel(scene, tree), 0.4);
    addSurface(scene, gridMesh(1.2, 0, 2, 1, 0), std::nullopt);
    return scene;
}

Scene sized(Scene scene) {
    scene.camera.width = kWidth;
    scene.camera.height = kHeight;
    return scene;
}

RenderResult texelRender(const Scene& scene, RenderOptions options, int rowBegin, int rowEnd) {
    options.aovs = true;
    options.threads = 2;
    options.rowBegin = rowBegin;
    options.rowEnd = rowEnd;
    return renderQuiet(scene, options);
}

RenderResult referenceRender(const Scene& scene, ReferenceOptions options, int rowBegin, int rowEnd) {
    options.aovs = true;
    options.threads = 2;
    options.rowBegin = rowBegin;
    options.rowEnd = rowEnd;
    vtex::NullProgress progress;
    return renderReference(scene, options, progress);
}

}  // namespace

TEST(RowRange, TexelRenderRangesStackIntoTheWholeRender) {
    const Scene scene = sized(pointLitTexels());
    RenderOptions options;
    options.spp = 4;
    expectRangesStackIntoTheWhole([&](int b, int e) { return texelRender(scene, options, b, e); });
}

// The bush field under its directional light: the shadow lattice (nodes filled by whichever
// pixel needs them first), the hybrid's mesh and the fitted levels (measured at load) all take
// part, and none may make a pixel depend on which others were rendered. (From nearer, (0.5, −1.2,
// 1.6), the mesh, which lights its own hits through the mesh, takes nearly every span and the
// lattice no longer shows.)
TEST(RowRange, ShadowLatticeHybridAndFittedLevelsStackIntoTheWholeRender) {
    const Scene scene = sized(bushField(Eigen::Vector3d(0.5, -1.8, 2.0)));
    const RenderOptions options;
    const RenderResult lattice = texelRender(scene, options, 0, 0);
    RenderOptions rays = options;
    rays.approximations.shadowCacheResolution = 0;
    // The lattice, the mesh and the fit are in use here: a test of them, not of their absence.
    EXPECT_FALSE(sameFloats(lattice.image.rgba, texelRender(scene, rays, 0, 0).image.rgba));
    EXPECT_GT(lattice.stats.meshSegments, 0);
    ASSERT_EQ(lattice.stats.levelScales.size(), 1u);
    EXPECT_FALSE(lattice.stats.levelScales[0].empty());
    expectRangesStackIntoTheWhole([&](int b, int e) { return texelRender(scene, options, b, e); });
}

TEST(RowRange, ReferenceRangesStackIntoTheWholeRender) {
    const Scene scene = sized(bushField(Eigen::Vector3d(0.5, -1.2, 1.6)));
    ReferenceOptions options;
    options.spp = 4;  // jittered: each sample's position hashes the pixel's own (x, y)
    expectRangesStackIntoTheWhole([&](int b, int e) { return referenceRender(scene, options, b, e); });
    options.mode = ReferenceMode::Deformed;
    options.spp = 1;
    expectRangesStackIntoTheWhole([&](int b, int e) { return referenceRender(scene, options, b, e); });
}

TEST(RowRange, BadRangesAreRefused) {
    ImageOptions options;
    EXPECT_EQ(imageRows(options, kHeight), std::make_pair(0, kHeight));
    options.rowBegin = 5;
    options.rowEnd = kHeight;
    EXPECT_EQ(imageRows(options, kHeight), std::make_pair(5, kHeight));
    const Scene scene = sized(pointLitTexels());
    for (const auto& [b, e] : {std::pair{-1, 5}, {5, 5}, {6, 5}, {0, kHeight + 1}, {3, 0}, {kHeight, kHeight + 1}}) {
        options.rowBegin = b;
        options.rowEnd = e;
        EXPECT_THROW(imageRows(options, kHeight), std::invalid_argument) << b << ":" << e;
        EXPECT_THROW(texelRender(scene, {}, b, e), std::invalid_argument) << b << ":" << e;
        EXPECT_THROW(referenceRender(scene, {}, b, e), std::invalid_argument) << b << ":" << e;
    }
}
