// scene.toml → Scene (DESIGN.md, "Scene file"), with toml++. Every value is checked for type and
// range; the error names the file and the key path (e.g. "surface[1].material.diffuse").
#include <vtex/render/scene.h>

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>
#include <vtex/core/toml_reader.h>

#include <Eigen/Geometry>
#include <toml++/toml.h>

#include <cmath>
#include <limits>
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
    Reader(const fs::path& file, std::vector<std::string>& warnings) : TomlReader(file, warnings), mSceneWarnings(warnings) {}

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

    // The height, placement and repeat or sub-rectangle of `t` (a surface or one of its `texels`
    // entries), each defaulting to `base`'s.
    TexelPlacing placing(const toml::table& t, const std::string& p, TexelPlacing base) {
        base.height = number(t, p, "height", base.height, 0, 1e30, true);
        const std::string placement = choice(t, p, "placement", std::string(base.placement == Placement::Under ? "under" : "on"),
                                             {"on", "under"});
        base.placement = placement == "under" ? Placement::Under : Placement::On;
        if (t.get("repeat") && t.get("subrect")) fail(join(p, "subrect"), "give repeat or subrect, not both");
        if (t.get("repeat")) {
            const Eigen::Vector2d repeat = vector<2>(t, p, "repeat", std::nullopt);
            for (int k = 0; k < 2; ++k)
                if (!(repeat[k] > 0 && repeat[k] <= 1e6)) fail(join(p, "repeat"), "components must be in (0, 1e6]");
            base.repeat = {repeat[0], repeat[1]};
            base.subrect.reset();
        }
        if (t.get("subrect")) {
            // [x0, y0, x1, y1] in reference units; whether it may leave the unit square depends
            // on the texel (cyclic or not), checked where the volume is known (cell_map.h).
            const Eigen::Vector4d r = vector<4>(t, p, "subrect", std::nullopt, -1e6, 1e6);
            if (!(r[2] > r[0] && r[3] > r[1])) fail(join(p, "subrect"), "must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0");
            base.subrect = std::array<double, 4>{r[0], r[1], r[2], r[3]};
            base.repeat = {1, 1};
        }
        if (t.get("perturb")) base.perturb = perturbation(t, p);
        return base;
    }

    std::size_t texelIndex(const Scene& scene, const std::string& key, const std::string& name) const {
        for (std::size_t k = 0; k < scene.texels.size(); ++k)
            if (scene.texels[k].name == name) return k;
        fail(key, "no [[texel]] is named '" + name + "'");
    }

    // `texels = { name = "texel" | { texel = "…", height, placement, repeat, subrect } }`: the
    // faces of a material or group, each entry defaulting to the surface's own placing.
    std::vector<NamedPlacing> namedPlacings(const Scene& scene, const toml::table& t, const std::string& p,
                                            const TexelPlacing& own) {
        std::vector<NamedPlacing> out;
        const toml::table* map = subtable(t, p, "texels", false);
        if (!map) return out;
        for (const auto& [name, node] : *map) {
            const std::string key = join(join(p, "texels"), name.str());
            NamedPlacing entry{std::string(name.str()), own};
            if (const auto* texel = node.as_string()) {
                entry.placing.texel = texelIndex(scene, key, texel->get());
            } else if (const auto* table = node.as_table()) {
                checkKeys(*table, key, {"texel", "height", "placement", "repeat", "subrect", "perturb"});
                entry.placing = placing(*table, key, own);
                entry.placing.texel = texelIndex(scene, join(key, "texel"), string(*table, key, "texel", std::nullopt));
            } else {
                fail(key, "must be a texel name or a table with a 'texel' key");
            }
            out.push_back(std::move(entry));
        }
        return out;
    }

    Perturbation perturbation(const toml::table& t, const std::string& p) {
        Perturbation out;
        const toml::table* q = subtable(t, p, "perturb", false);
        if (!q) return out;
        const std::string pp = join(p, "perturb");
        checkKeys(*q, pp, {"seed", "rotate", "mirror", "shift"});
        out.seed = std::uint64_t(integer(*q, pp, "seed", 0, 0, std::numeric_limits<long long>::max()));
        out.rotate = boolean(*q, pp, "rotate", false);
        out.mirror = boolean(*q, pp, "mirror", false);
        out.shift = boolean(*q, pp, "shift", false);
        return out;
    }

    SurfaceDef surface(const Scene& scene, const toml::table& t, const std::string& p) {
        checkKeys(t, p, {"mesh", "texel", "height", "placement", "repeat", "subrect", "texels", "perturb", "material"});
        SurfaceDef s;
        s.mesh = resolve(p + ".mesh", string(t, p, "mesh", std::nullopt));
        if (t.get("texel")) s.texel = texelIndex(scene, p + ".texel", string(t, p, "texel", std::nullopt));
        const TexelPlacing own = placing(t, p, s.placing(0));
        s.height = own.height;
        s.placement = own.placement;
        s.repeat = own.repeat;
        s.subrect = own.subrect;
        s.perturb = own.perturb;
        s.texels = namedPlacings(scene, t, p, own);
        s.material = material(t, p, Material{});
        if (!s.texel && s.texels.empty() &&
            (t.get("height") || t.get("placement") || t.get("repeat") || t.get("subrect") || t.get("perturb")))
            warn(p + ": height/placement/repeat/subrect/perturb ignored on a surface without a texel");
        return s;
    }

    void warn(const std::string& what) { mSceneWarnings.push_back(file().string() + ": " + what); }

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

private:
    std::vector<std::string>& mSceneWarnings;
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
    for (std::size_t i = 0; i < surfaces.size(); ++i)
        scene.surfaces.push_back(r.surface(scene, *surfaces[i], "surface[" + std::to_string(i) + "]"));
    return scene;
}

Scene loadScene(const std::filesystem::path& file) {
    return parseScene(readInputFile(file, std::uint64_t(64) << 20, "scene file"), file);
}

std::vector<std::size_t> usedTexels(const Scene& scene) {
    std::set<std::size_t> used;
    for (const SurfaceDef& s : scene.surfaces)
        for (std::size_t k = 0; k < s.placingCount(); ++k)
            if (const auto texel = s.placing(k).texel) used.insert(*texel);
    return {used.begin(), used.end()};
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
