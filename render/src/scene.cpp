// scene.toml → Scene (DESIGN.md, "Scene file"), with toml++. Every value is checked for type and
// range; the error names the file and the key path (e.g. "surface[1].material.diffuse").
#include <vtex/render/scene.h>

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>
#include <vtex/core/toml_reader.h>

#include <Eigen/Geometry>
#include <toml++/toml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace vtex::render {
namespace {

// Bounds that keep every radiance a render can make within float's range, so that no image
// holds inf: at most 1e9 (light) × 1e6 (material) × (1e6 + 2)/2π (Phong's normalisation at the
// largest shininess) ≈ 1.6e20, far below 3.4e38. A light of colour 1e308 wrote inf pixels with
// exit 0 (issue 14, item 7).
constexpr double kMaxLightColor = 1e9;
constexpr double kMaxMaterial = 1e6;

std::string shortNumber(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

namespace fs = std::filesystem;

// The scene's own value kinds on top of the shared checked TOML reader.
class Reader : public TomlReader {
public:
    using TomlReader::TomlReader;

    template <int N>
    Eigen::Matrix<double, N, 1> vector(const toml::table& table, const std::string& path, std::string_view name,
                                       std::optional<Eigen::Matrix<double, N, 1>> fallback,
                                       double min = -INFINITY, double max = INFINITY) const {
        const std::string key = join(path, name);
        const toml::node* node = table.get(name);
        if (!node) {
            if (!fallback) fail(key, "missing key");
            return *fallback;
        }
        const auto array = node->as_array();
        if (!array || array->size() != std::size_t(N))
            fail(key, "must be an array of " + std::to_string(N) + " numbers");
        Eigen::Matrix<double, N, 1> out;
        for (int i = 0; i < N; ++i) {
            out[i] = number(*array->get(std::size_t(i)), key);
            if (out[i] < min) fail(key, "components must be ≥ " + std::to_string(min));
            if (out[i] > max) fail(key, "components must be ≤ " + shortNumber(max));
        }
        return out;
    }

    Material material(const toml::table& parent, const std::string& path, const Material& defaults) {
        const toml::table* t = subtable(parent, path, "material", false);
        if (!t) return defaults;
        const std::string p = join(path, "material");
        checkKeys(*t, p, {"ambient", "diffuse", "specular", "shininess"});
        Material m;
        m.ambient = vector<3>(*t, p, "ambient", defaults.ambient, 0.0, kMaxMaterial);
        m.diffuse = vector<3>(*t, p, "diffuse", defaults.diffuse, 0.0, kMaxMaterial);
        m.specular = vector<3>(*t, p, "specular", defaults.specular, 0.0, kMaxMaterial);
        m.shininess = number(*t, p, "shininess", defaults.shininess, 0, 1e6);
        return m;
    }
};

}  // namespace

Scene parseScene(std::string_view text, const std::filesystem::path& file) {
    Scene scene;
    scene.file = file;
    Reader r(file, scene.warnings);
    const toml::table root = r.parse(text);
    r.checkKeys(root, "", {"camera", "light", "texel", "surface"});

    // Camera.
    const toml::table& cam = *r.subtable(root, "", "camera", true);
    r.checkKeys(cam, "camera", {"position", "look_at", "up", "fov_y", "width", "height"});
    Camera& c = scene.camera;
    c.position = r.vector<3>(cam, "camera", "position", std::nullopt);
    c.lookAt = r.vector<3>(cam, "camera", "look_at", std::nullopt);
    c.up = r.vector<3>(cam, "camera", "up", Eigen::Vector3d(0, 0, 1));
    c.fovY = r.number(cam, "camera", "fov_y", 40.0, 0, 179, true);
    c.width = r.integer(cam, "camera", "width", 768, 1, 16384);
    c.height = r.integer(cam, "camera", "height", 576, 1, 16384);
    const Eigen::Vector3d forward = c.lookAt - c.position;
    if (!(forward.norm() > 0)) r.fail("camera.look_at", "must differ from camera.position");
    if (!(forward.normalized().cross(c.up).norm() > 1e-9 * c.up.norm()) || !(c.up.norm() > 0))
        r.fail("camera.up", "must not be zero or parallel to the viewing direction");

    // Lights.
    const auto lights = r.arrayOfTables(root, "light");
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const toml::table& t = *lights[i];
        const std::string p = "light[" + std::to_string(i) + "]";
        r.checkKeys(t, p, {"type", "direction", "position", "color"});
        Light light;
        const std::string type = r.string(t, p, "type", std::nullopt);
        light.color = r.vector<3>(t, p, "color", Color(1, 1, 1), 0.0, kMaxLightColor);
        if (type == "directional") {
            light.type = LightType::Directional;
            const Eigen::Vector3d d = r.vector<3>(t, p, "direction", std::nullopt);
            // [0, 0, -1e308] passed the zero test with a norm that overflowed to inf, and
            // normalized() made it (-0, 0, -0): a light that lit nothing, exit 0 (found by
            // fuzz_scene). Such a direction, or one whose squared norm underflows, is scaled by
            // its largest component first; any other is normalised as it always was.
            const Eigen::Vector3d scaled = std::isfinite(d.norm()) && d.norm() > 0 ? d : d / d.cwiseAbs().maxCoeff();
            if (!(scaled.norm() > 0)) r.fail(p + ".direction", "must not be zero");
            light.direction = scaled.normalized();
        } else if (type == "point") {
            light.type = LightType::Point;
            light.position = r.vector<3>(t, p, "position", std::nullopt);
        } else {
            r.fail(p + ".type", "must be \"directional\" or \"point\", got \"" + type + "\"");
        }
        scene.lights.push_back(light);
    }

    // Texels.
    const auto texels = r.arrayOfTables(root, "texel");
    std::set<std::string> names;
    for (std::size_t i = 0; i < texels.size(); ++i) {
        const toml::table& t = *texels[i];
        const std::string p = "texel[" + std::to_string(i) + "]";
        r.checkKeys(t, p, {"name", "volume", "source", "tau", "material"});
        TexelDef texel;
        texel.name = r.string(t, p, "name", std::nullopt);
        if (!names.insert(texel.name).second) r.fail(p + ".name", "duplicate texel name '" + texel.name + "'");
        texel.volume = r.resolve(p + ".volume", r.string(t, p, "volume", std::nullopt));
        const std::string source = r.string(t, p, "source", std::string());
        if (!source.empty()) texel.source = r.resolve(p + ".source", source);
        texel.tau = r.number(t, p, "tau", 1.0, 0, 1e12);
        texel.material = r.material(t, p, texel.material);
        scene.texels.push_back(std::move(texel));
    }

    // Surfaces.
    const auto surfaces = r.arrayOfTables(root, "surface");
    for (std::size_t i = 0; i < surfaces.size(); ++i) {
        const toml::table& t = *surfaces[i];
        const std::string p = "surface[" + std::to_string(i) + "]";
        r.checkKeys(t, p, {"mesh", "texel", "height", "placement", "repeat", "material"});
        SurfaceDef s;
        s.mesh = r.resolve(p + ".mesh", r.string(t, p, "mesh", std::nullopt));
        if (t.get("texel")) {
            const std::string name = r.string(t, p, "texel", std::nullopt);
            for (std::size_t k = 0; k < scene.texels.size(); ++k)
                if (scene.texels[k].name == name) s.texel = k;
            if (!s.texel) r.fail(p + ".texel", "no [[texel]] is named '" + name + "'");
        }
        s.height = r.number(t, p, "height", 0.1, 0, 1e30, true);
        const std::string placement = r.string(t, p, "placement", std::string("on"));
        if (placement == "on") s.placement = Placement::On;
        else if (placement == "under") s.placement = Placement::Under;
        else r.fail(p + ".placement", "must be \"on\" or \"under\", got \"" + placement + "\"");
        const Eigen::Vector2d repeat = r.vector<2>(t, p, "repeat", Eigen::Vector2d(1, 1));
        for (int k = 0; k < 2; ++k)
            if (!(repeat[k] > 0 && repeat[k] <= 1e6)) r.fail(p + ".repeat", "components must be in (0, 1e6]");
        s.repeat = {repeat[0], repeat[1]};
        s.material = r.material(t, p, Material{});
        if (!s.texel && (t.get("height") || t.get("placement") || t.get("repeat")))
            scene.warnings.push_back(file.string() + ": " + p +
                                     ": height/placement/repeat ignored on a surface without a texel");
        scene.surfaces.push_back(std::move(s));
    }
    return scene;
}

Scene loadScene(const std::filesystem::path& file) {
    return parseScene(readInputFile(file, std::uint64_t(64) << 20, "scene file"), file);
}

std::vector<std::filesystem::path> sceneFiles(const Scene& scene) {
    std::vector<std::filesystem::path> files = {scene.file};
    for (const SurfaceDef& surface : scene.surfaces) files.push_back(surface.mesh);
    for (const TexelDef& texel : scene.texels) {
        files.push_back(texel.volume);
        files.push_back(texel.source);
    }
    std::erase_if(files, [](const std::filesystem::path& file) { return file.empty(); });
    return files;
}

}  // namespace vtex::render
