// Scenes beyond the renderers' exact range (frame.h, kMaxSceneCoordinate) are refused naming the
// key or the mesh, never handed to Embree (which asserts past ±1.84e18): issue 14, item 1.
#include "fixtures.h"

#include <vtex/core/error.h>
#include <vtex/render/compare.h>
#include <vtex/render/reference.h>

#include <gtest/gtest.h>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

Scene plainScene() {
    Scene scene = baseScene(Eigen::Vector3d(0, -3, 2), Eigen::Vector3d(0, 0, 0), 40, 16);
    scene.file = "range.toml";
    addSurface(scene, gridMesh(-1, -1, 1, 1, 0), std::nullopt);
    return scene;
}

// The message of the InputError `render` throws, or "" when it throws none.
template <class Render>
std::string refusal(Render&& render) {
    try {
        render();
    } catch (const vtex::InputError& e) {
        return e.what();
    }
    return "";
}

std::string refusedBothWays(const Scene& scene) {
    vtex::NullProgress progress;
    const std::string texel = refusal([&] { renderScene(scene, {}, progress); });
    const std::string reference = refusal([&] { renderReference(scene, {}, progress); });
    EXPECT_EQ(texel, reference);
    return texel;
}

}  // namespace

TEST(Range, ACameraBeyondTheExactRangeIsRefusedNamingTheKey) {
    Scene scene = plainScene();
    EXPECT_EQ(refusedBothWays(scene), "") << "the plain scene renders";
    scene.camera.position = Eigen::Vector3d(0, -2e18, 0.5);  // past Embree's FLT_LARGE: it used to abort
    EXPECT_NE(refusedBothWays(scene).find("camera.position"), std::string::npos);
    scene.camera.position = Eigen::Vector3d(0, -1.01e12, 0.5);
    EXPECT_NE(refusedBothWays(scene).find("camera.position"), std::string::npos);
    scene.camera.position = Eigen::Vector3d(0, -0.99e12, 0.5);  // just inside: renders
    EXPECT_EQ(refusedBothWays(scene), "");
    scene = plainScene();
    scene.camera.lookAt = Eigen::Vector3d(3e18, 0, 0);
    EXPECT_NE(refusedBothWays(scene).find("camera.look_at"), std::string::npos);
    scene = plainScene();
    Light point;
    point.type = LightType::Point;
    point.position = Eigen::Vector3d(0, 0, 1e19);
    scene.lights.push_back(point);
    EXPECT_NE(refusedBothWays(scene).find("light[1].position"), std::string::npos);
}

TEST(Range, AMeshOrShellBeyondTheExactRangeIsRefusedNamingTheMesh) {
    Scene scene = plainScene();
    scene.surfaces[0].mesh = "huge.obj";
    scene.surfaces[0].meshData = gridMesh(-1e19, -1e19, 1e19, 1e19, 0);  // used to render nothing, exit 0
    EXPECT_NE(refusedBothWays(scene).find("huge.obj"), std::string::npos);
    scene = plainScene();
    const auto texel = addTexel(scene, makeOctree(1, [](int, int, int) { return std::optional(sphereVoxel(1)); }));
    addSurface(scene, gridMesh(0, 0, 1, 1, 0), texel, 2e12);  // a shell 2e12 high
    scene.surfaces.back().mesh = "tall.obj";
    vtex::NullProgress progress;
    EXPECT_NE(refusal([&] { renderScene(scene, {}, progress); }).find("tall.obj"), std::string::npos);
}

// Radiance never leaves float's range (issue 14, item 7): a light or a material past its bound
// is refused naming the key (a light of 1e308 wrote inf pixels with exit 0), a pixel that would
// still overflow is clamped and counted, and `vtex compare` refuses an image it cannot measure.
TEST(Range, RadianceBeyondFloatIsRefusedOrClampedNeverWritten) {
    const std::string light = "[camera]\nposition = [0, -3, 2]\nlook_at = [0, 0, 0]\n"
                              "[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\ncolor = [1e308, 1, 1]\n"
                              "[[surface]]\nmesh = \"plane.obj\"\n";
    EXPECT_NE(refusal([&] { parseScene(light, "hot.toml"); }).find("light[0].color"), std::string::npos);
    const std::string material = "[camera]\nposition = [0, -3, 2]\nlook_at = [0, 0, 0]\n"
                                 "[[surface]]\nmesh = \"plane.obj\"\nmaterial = { specular = [1e300, 0, 0] }\n";
    EXPECT_NE(refusal([&] { parseScene(material, "shiny.toml"); }).find("material.specular"), std::string::npos);
    // A scene built in memory skips the file's bounds: its pixels are clamped, counted and warned.
    Scene scene = plainScene();
    scene.lights[0].color = Color(1e300, 1e300, 1e300);
    const RenderResult r = renderQuiet(scene);
    for (float v : r.image.rgba) EXPECT_TRUE(std::isfinite(v));
    ASSERT_FALSE(r.warnings.empty());
    EXPECT_NE(r.warnings.back().find("clamped"), std::string::npos) << r.warnings.back();
    EXPECT_TRUE(firstUnmeasurablePixel(r.image).has_value());
    EXPECT_FALSE(firstUnmeasurablePixel(renderQuiet(plainScene()).image).has_value());
}
