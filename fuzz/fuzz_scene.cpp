// libFuzzer target for scene.toml (vtex::render::parseScene): the whole input is the file.
// Oracles beyond "no crash, no UB, no leak": a refused scene throws InputError whose message is
// one line and begins with the file's name; an accepted scene holds only what the reader
// promises (render/scene.h, DESIGN.md "Scene file") — finite numbers within their stated
// bounds, a usable camera, unit light directions, surfaces that name existing texels, unique
// texel names. fuzz_formats mode 4 reads scenes too (its corpus keeps working); this target has
// its own seeds (corpus-scene/) and the oracles.
#include <vtex/core/error.h>
#include <vtex/render/scene.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <string_view>

namespace {

using namespace vtex::render;

constexpr char kFile[] = "fuzz/scene.toml";

[[noreturn]] void broken(const char* what) {
    std::fprintf(stderr, "fuzz_scene: oracle failed: %s\n", what);
    std::abort();
}

void check(bool ok, const char* what) {
    if (!ok) broken(what);
}

template <class V>
bool within(const V& v, double lo, double hi) {
    for (int i = 0; i < v.size(); ++i)
        if (!(std::isfinite(v[i]) && v[i] >= lo && v[i] <= hi)) return false;
    return true;
}

// A path holding a NUL names a file no system call can open: the OS would read the path up to
// the NUL, another file than the one written.
bool hasNul(const std::filesystem::path& p) { return p.string().find('\0') != std::string::npos; }

void checkMaterial(const Material& m) {
    check(within(m.ambient, 0, 1e6) && within(m.diffuse, 0, 1e6) && within(m.specular, 0, 1e6),
          "material colour outside [0, 1e6]");
    check(std::isfinite(m.shininess) && m.shininess >= 0 && m.shininess <= 1e6, "shininess outside [0, 1e6]");
}

void checkAccepted(const Scene& s) {
    const Camera& c = s.camera;
    check(c.position.allFinite() && c.lookAt.allFinite() && c.up.allFinite(), "camera vector not finite");
    check(c.fovY > 0 && c.fovY <= 179, "fov_y outside (0, 179]");
    check(c.width >= 1 && c.width <= 16384 && c.height >= 1 && c.height <= 16384, "camera size outside [1, 16384]");
    const Eigen::Vector3d forward = c.lookAt - c.position;
    check(forward.norm() > 0 && std::isfinite(forward.norm()), "camera looks nowhere (or at infinity)");
    check(c.up.norm() > 0, "camera up is zero");
    // The camera's basis as CameraRays (render/src/frame.cpp) makes it.
    const Eigen::Vector3d right = forward.normalized().cross(c.up).normalized();
    check(right.allFinite() && std::abs(right.norm() - 1) < 1e-6, "camera basis not computable");
    for (const Light& l : s.lights) {
        check(within(l.color, 0, 1e9), "light colour outside [0, 1e9]");
        if (l.type == LightType::Directional)
            check(l.direction.allFinite() && std::abs(l.direction.norm() - 1) < 1e-9, "light direction not unit");
        else
            check(l.position.allFinite(), "light position not finite");
    }
    std::set<std::string> names;
    for (const TexelDef& t : s.texels) {
        check(names.insert(t.name).second, "duplicate texel name accepted");
        check(std::isfinite(t.tau) && t.tau >= 0 && t.tau <= 1e12, "tau outside [0, 1e12]");
        check(!t.volume.empty(), "texel without volume");
        check(!hasNul(t.volume) && !hasNul(t.source), "texel path holding a NUL accepted");
        checkMaterial(t.material);
    }
    for (const SurfaceDef& f : s.surfaces) {
        check(!f.mesh.empty(), "surface without mesh");
        check(!hasNul(f.mesh), "mesh path holding a NUL accepted");
        check(!f.texel || *f.texel < s.texels.size(), "surface names a texel out of range");
        check(std::isfinite(f.height) && f.height > 0 && f.height <= 1e30, "height outside (0, 1e30]");
        for (double r : f.repeat) check(r > 0 && r <= 1e6, "repeat outside (0, 1e6]");
        checkMaterial(f.material);
    }
    for (const std::string& w : s.warnings) check(w.find('\n') == std::string::npos, "warning of several lines");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        checkAccepted(parseScene(text, kFile));
        if (std::getenv("VTEX_FUZZ_ECHO")) std::fprintf(stderr, "accepted\n");
    } catch (const vtex::InputError& e) {
        // Refused: the expected outcome for most inputs; the CLI prints what() as its one line.
        const std::string message = e.what();
        if (std::getenv("VTEX_FUZZ_ECHO")) std::fprintf(stderr, "refused: %s\n", message.c_str());
        check(message.find('\n') == std::string::npos && message.find('\r') == std::string::npos,
              "error message of several lines");
        check(message.rfind(std::string(kFile) + ": ", 0) == 0, "error message does not begin with the file");
        check(message.find('\0') == std::string::npos, "error message holds a NUL");
    }
    return 0;
}
