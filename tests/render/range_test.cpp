// Scenes beyond the renderers' exact range (frame.h, kMaxSceneCoordinate) are refused naming the
// key or the mesh, never handed to Embree (which asserts past ±1.84e18): issue 14, item 1.
#include "fixtures.h"

#include <vtex/core/error.h>
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
