// scene.toml parsing: values, defaults, relative paths, errors naming file and key, warnings.
#include <vtex/core/error.h>
#include <vtex/render/scene.h>

#include <gtest/gtest.h>

using namespace vtex::render;

namespace {

const char* kGood = R"(
[camera]
position = [0, -6, 3]
look_at  = [0, 0, 0]
up       = [0, 0, 1]
fov_y    = 40
width    = 64
height   = 48

[[light]]
type      = "directional"
direction = [-1, -0.5, -1]
color     = [3, 3, 3]

[[light]]
type     = "point"
position = [1, 2, 3]

[[texel]]
name   = "grass"
volume = "grass.vto"
source = "grass.glb"
tau    = 2.5
material = { diffuse = [1, 1, 1], specular = [0.1, 0.1, 0.1], shininess = 20, ambient = [0.02, 0.02, 0.02] }

[[surface]]
mesh      = "meshes/hill.obj"
texel     = "grass"
height    = 0.2
placement = "under"
repeat    = [2, 3]
material  = { diffuse = [0.3, 0.25, 0.2] }

[[surface]]
mesh = "/abs/rock.obj"
)";

std::string errorOf(const std::string& text) {
    try {
        parseScene(text, "/scenes/s.toml");
    } catch (const vtex::InputError& e) {
        return e.what();
    }
    return "no error";
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    return text;
}

}  // namespace

TEST(Scene, ParsesTheDesignSketch) {
    const Scene s = parseScene(kGood, "/scenes/s.toml");
    EXPECT_EQ(s.camera.width, 64);
    EXPECT_EQ(s.camera.height, 48);
    EXPECT_DOUBLE_EQ(s.camera.fovY, 40);
    ASSERT_EQ(s.lights.size(), 2u);
    EXPECT_EQ(s.lights[0].type, LightType::Directional);
    EXPECT_NEAR(s.lights[0].direction.norm(), 1, 1e-12);
    EXPECT_EQ(s.lights[1].type, LightType::Point);
    EXPECT_EQ(s.lights[1].color, Color(1, 1, 1));
    ASSERT_EQ(s.texels.size(), 1u);
    EXPECT_EQ(s.texels[0].volume, std::filesystem::path("/scenes/grass.vto"));
    EXPECT_DOUBLE_EQ(s.texels[0].tau, 2.5);
    EXPECT_DOUBLE_EQ(s.texels[0].material.shininess, 20);
    ASSERT_EQ(s.surfaces.size(), 2u);
    EXPECT_EQ(s.surfaces[0].mesh, std::filesystem::path("/scenes/meshes/hill.obj"));
    EXPECT_EQ(s.surfaces[0].texel, std::optional<std::size_t>(0));
    EXPECT_EQ(s.surfaces[0].placement, Placement::Under);
    EXPECT_DOUBLE_EQ(s.surfaces[0].repeat[1], 3);
    EXPECT_EQ(s.surfaces[0].material.diffuse, Color(0.3, 0.25, 0.2));
    EXPECT_EQ(s.surfaces[1].mesh, std::filesystem::path("/abs/rock.obj"));
    EXPECT_FALSE(s.surfaces[1].texel);
    EXPECT_TRUE(s.warnings.empty());
}

TEST(Scene, MissingAndWrongKeysNameFileAndKey) {
    EXPECT_EQ(errorOf(replace(kGood, "look_at  = [0, 0, 0]", "")), "/scenes/s.toml: camera.look_at: missing key");
    EXPECT_NE(errorOf(replace(kGood, "fov_y    = 40", "fov_y = \"wide\"")).find("camera.fov_y: must be a number"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "fov_y    = 40", "fov_y = 190")).find("camera.fov_y"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "width    = 64", "width = 6.5")).find("camera.width: must be an integer"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "color     = [3, 3, 3]", "color = [3, 3]")).find("light[0].color"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "color     = [3, 3, 3]", "color = [3, -3, 3]")).find("light[0].color"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "type     = \"point\"", "type = \"spot\"")).find("light[1].type"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "texel     = \"grass\"", "texel = \"moss\"")).find("surface[0].texel: no [[texel]] is named 'moss'"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "height    = 0.2", "height = 0")).find("surface[0].height"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "placement = \"under\"", "placement = \"over\"")).find("surface[0].placement"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "repeat    = [2, 3]", "repeat = [2, 0]")).find("surface[0].repeat"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "shininess = 20", "shininess = nan")).find("texel[0].material.shininess"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "mesh = \"/abs/rock.obj\"", "")).find("surface[1].mesh: missing key"), std::string::npos);
    EXPECT_NE(errorOf(replace(kGood, "look_at  = [0, 0, 0]", "look_at = [0, -6, 3]")).find("camera.look_at"), std::string::npos);
    EXPECT_NE(errorOf("[camera\nposition = 1").find("TOML syntax error"), std::string::npos);
    EXPECT_NE(errorOf("").find("camera: missing table"), std::string::npos);
    EXPECT_NE(errorOf(std::string(kGood) + "\n[[texel]]\nname = \"grass\"\nvolume = \"b.vto\"\n").find("duplicate texel name"), std::string::npos);
}

TEST(Scene, UnknownKeysAreWarnings) {
    const Scene s = parseScene(replace(replace(kGood, "fov_y    = 40", "fov_y = 40\nfocal = 3"), "tau    = 2.5", "tau = 2.5\ncolour = 1"),
                               "/scenes/s.toml");
    ASSERT_EQ(s.warnings.size(), 2u);
    EXPECT_NE(s.warnings[0].find("camera.focal"), std::string::npos);
    EXPECT_NE(s.warnings[1].find("texel[0].colour"), std::string::npos);
}

// Found by fuzz_scene (fuzz/corpus-scene/regression_1): a path holding a NUL was accepted, and
// the system then opened the path only up to the NUL — "hill\0.obj" read the file "hill".
TEST(Scene, FuzzAPathHoldingANulIsRefusedNamingTheKey) {
    EXPECT_EQ(errorOf(replace(kGood, "mesh = \"/abs/rock.obj\"", "mesh = \"/abs/rock\\u0000.obj\"")),
              "/scenes/s.toml: surface[1].mesh: a path may not hold a NUL character");
    EXPECT_EQ(errorOf(replace(kGood, "volume = \"grass.vto\"", "volume = \"grass\\u0000.vto\"")),
              "/scenes/s.toml: texel[0].volume: a path may not hold a NUL character");
    EXPECT_EQ(errorOf(replace(kGood, "source = \"grass.glb\"", "source = \"\\u0000\"")),
              "/scenes/s.toml: texel[0].source: a path may not hold a NUL character");
}

// Found by fuzz_scene (fuzz/corpus-scene/regression_2): a directional light's direction of
// [-0.6, 0.5, -1e308] — straight down — has a norm that overflows, and was stored as (-0, 0, -0):
// the light lit nothing and the render was black, exit 0. Only the direction matters, not its
// length, however large or small.
TEST(Scene, FuzzAHugeOrTinyLightDirectionIsNormalisedNotLost) {
    for (const char* direction : {"[-0.6, 0.5, -1e308]", "[0, 0, -1e308]", "[1e-200, 0, -1e-200]"}) {
        const Scene s = parseScene(replace(kGood, "direction = [-1, -0.5, -1]", std::string("direction = ") + direction),
                                   "/scenes/s.toml");
        EXPECT_NEAR(s.lights[0].direction.norm(), 1, 1e-12) << direction;
    }
    const Scene down = parseScene(replace(kGood, "direction = [-1, -0.5, -1]", "direction = [-0.6, 0.5, -1e308]"),
                                  "/scenes/s.toml");
    EXPECT_LT((down.lights[0].direction - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
    EXPECT_NE(errorOf(replace(kGood, "direction = [-1, -0.5, -1]", "direction = [0, 0, 0]")).find("light[0].direction: must not be zero"),
              std::string::npos);
}

// A warning quotes the unknown key, which TOML lets hold a newline ("a\nb" = 1): it is one line
// too, written like an error message (vtex::oneLine).
TEST(Scene, AWarningIsOneLineWhateverTheKeyHolds) {
    const Scene s = parseScene(replace(kGood, "fov_y    = 40", "fov_y = 40\n\"a\\nb\" = 1"), "/scenes/s.toml");
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_EQ(s.warnings[0], "/scenes/s.toml: unknown key 'camera.a b' ignored");
}

// A texel per face, the sub-rectangle and the perturbation (issue 16): their keys parse into the
// surface, entries default to the surface's placing, and a bad value names its key.
TEST(Scene, PerFaceTexelsSubrectAndPerturbation) {
    const std::string keys = "repeat    = [2, 3]\n"
                             "texels = { bush = \"grass\", moss = { texel = \"grass\", height = 0.5, subrect = [0, 0, 0.5, 0.5] } }\n"
                             "perturb = { seed = 7, rotate = true, shift = true }";
    const Scene s = parseScene(replace(kGood, "repeat    = [2, 3]", keys), "/scenes/s.toml");
    const SurfaceDef& d = s.surfaces[0];
    ASSERT_EQ(d.texels.size(), 2u);
    EXPECT_EQ(d.texels[0].name, "bush");
    EXPECT_EQ(d.texels[0].placing.texel, 0u);
    EXPECT_DOUBLE_EQ(d.texels[0].placing.height, 0.2);  // the surface's
    EXPECT_EQ(d.texels[0].placing.placement, Placement::Under);
    EXPECT_EQ(d.texels[0].placing.repeat, (std::array<double, 2>{2, 3}));
    EXPECT_DOUBLE_EQ(d.texels[1].placing.height, 0.5);
    ASSERT_TRUE(d.texels[1].placing.subrect.has_value());
    EXPECT_EQ(*d.texels[1].placing.subrect, (std::array<double, 4>{0, 0, 0.5, 0.5}));
    EXPECT_EQ(d.perturb.seed, 7u);
    EXPECT_TRUE(d.perturb.rotate);
    EXPECT_FALSE(d.perturb.mirror);
    EXPECT_TRUE(d.perturb.shift);
    EXPECT_EQ(d.placingCount(), 3u);
    EXPECT_EQ(d.texels[0].placing.perturb.seed, 7u);  // entries take the surface's perturbation
    EXPECT_TRUE(d.texels[0].placing.perturb.shift);
    // An entry's own perturbation replaces it (a cyclic texel's faces shifted, another's not).
    const Scene own = parseScene(replace(kGood, "repeat    = [2, 3]",
                                         "perturb = { seed = 3, shift = true }\n"
                                         "texels = { bush = { texel = \"grass\", perturb = { seed = 5, rotate = true } } }"),
                                 "/scenes/s.toml");
    EXPECT_EQ(own.surfaces[0].texels[0].placing.perturb.seed, 5u);
    EXPECT_TRUE(own.surfaces[0].texels[0].placing.perturb.rotate);
    EXPECT_FALSE(own.surfaces[0].texels[0].placing.perturb.shift);
    EXPECT_TRUE(own.surfaces[0].placing(0).perturb.shift);

    const auto withKeys = [&](const std::string& k) { return errorOf(replace(kGood, "repeat    = [2, 3]", k)); };
    EXPECT_EQ(withKeys("texels = { bush = \"hedge\" }"), "/scenes/s.toml: surface[0].texels.bush: no [[texel]] is named 'hedge'");
    EXPECT_NE(withKeys("texels = { bush = 3 }").find("surface[0].texels.bush: must be a texel name"), std::string::npos);
    EXPECT_NE(withKeys("texels = { bush = { height = 1 } }").find("surface[0].texels.bush.texel: missing key"), std::string::npos);
    EXPECT_NE(withKeys("texels = { bush = { texel = \"grass\", placement = \"over\" } }").find("surface[0].texels.bush.placement"),
              std::string::npos);
    EXPECT_NE(withKeys("repeat = [2, 3]\nsubrect = [0, 0, 1, 1]").find("surface[0].subrect: give repeat or subrect, not both"),
              std::string::npos);
    EXPECT_NE(withKeys("subrect = [0.5, 0, 0.25, 1]").find("surface[0].subrect: must be [x0, y0, x1, y1]"), std::string::npos);
    EXPECT_NE(withKeys("perturb = { seed = -1 }").find("surface[0].perturb.seed"), std::string::npos);
    EXPECT_NE(withKeys("perturb = { rotate = 1 }").find("surface[0].perturb.rotate: must be true or false"), std::string::npos);
}
