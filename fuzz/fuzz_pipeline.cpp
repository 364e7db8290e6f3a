// libFuzzer target for pipeline files (vtex::pipelines::loadPipeline). The reader takes a path
// and reads the scenes and checks the mesh files it names, so every process works in a scratch
// folder of its own (in /dev/shm when there is one) that holds small fixtures a pipeline can
// name: meshes (hill.obj, cross.obj, tiny.glb), scenes (hill.toml and the demo's scene names,
// all with a texel "cover"), and what no reader may hang on or accept: a FIFO (fifo.toml,
// fifo.obj), a directory (dir.toml), links to /dev/zero and /dev/null, a link loop.
//
// The input is the pipeline file, p.toml. When it holds a line "#%f.toml", what follows that
// line is written to f.toml instead, a scene of the fuzzer's own that the pipeline can name.
//
// Oracles beyond "no crash, no UB, no leak":
// - a refused file throws vtex::InputError (the CLI's exit 3) with a one-line message that
//   begins with the file it names; any other exception escapes and is a finding (the CLI would
//   exit 1 for bad input);
// - an accepted pipeline holds only what loadPipeline promises (pipelines/pipeline.h): usable
//   unique names, every reference resolved (texel → source, binding → texel and scene texel,
//   compare → render), exactly one of pattern and file, files that are regular files, values in
//   range, scenes that load;
// - reading changes nothing: the fixtures stay as they were and no file appears in the folder.
#include <vtex/core/error.h>
#include <vtex/pipelines/pipeline.h>
#include <vtex/render/scene.h>
#include <vtex/sampler/patterns.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using namespace vtex::pipelines;

fs::path gDir;  // the scratch folder
// Every fixture's (type, size, mtime) as it was made: reading must change none.
std::map<std::string, std::string> gFixtures;

[[noreturn]] void broken(const std::string& what) {
    std::fprintf(stderr, "fuzz_pipeline: oracle failed: %s\n", what.c_str());
    std::abort();
}

void check(bool ok, const std::string& what) {
    if (!ok) broken(what);
}

void writeText(const fs::path& file, std::string_view text) {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(text.data(), std::streamsize(text.size()));
    if (!out) broken("cannot write " + file.string());
}

constexpr char kHill[] = R"(v -1 -1 0
v 1 -1 0
v 1 1 0.2
v -1 1 0
f 1 2 3 4
)";

constexpr char kCross[] = "v 0.1 0.5 0.1\nv 0.9 0.5 0.1\nv 0.9 0.5 0.9\nv 0.1 0.5 0.9\n"
                          "v 0.5 0.1 0.1\nv 0.5 0.9 0.1\nv 0.5 0.9 0.9\nv 0.5 0.1 0.9\nf 1 2 3 4\nf 5 6 7 8\n";

constexpr char kScene[] = R"([camera]
position = [0.0, -3.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
width = 48
height = 36

[[light]]
type = "directional"
direction = [-1.0, 0.5, -1.0]
color = [3.0, 3.0, 3.0]

[[texel]]
name = "cover"
volume = "bound-by-the-pipeline.vto"
source = "cross.obj"

[[surface]]
mesh = "hill.obj"
texel = "cover"
height = 0.25
)";

// A glTF binary header and nothing else: loadPipeline only checks that a source file is a
// regular file; ingest reads it later.
constexpr char kTinyGlb[] = "glTF\x02\0\0\0\x0c\0\0\0";

std::string describe(const fs::path& p) {
    struct stat s {};
    if (::lstat(p.c_str(), &s) != 0) return "missing";
    return std::to_string(s.st_mode) + " " + std::to_string(s.st_size) + " " + std::to_string(s.st_mtim.tv_sec) +
           "." + std::to_string(s.st_mtim.tv_nsec);
}

// Every entry under `dir` (not following links: the folder holds a link loop), relative names.
void walk(const fs::path& dir, std::vector<fs::path>& out) {
    for (const auto& entry : fs::directory_iterator(dir)) {
        out.push_back(entry.path());
        if (entry.symlink_status().type() == fs::file_type::directory) walk(entry.path(), out);
    }
}

std::vector<fs::path> entries() {
    std::vector<fs::path> out;
    walk(gDir, out);
    return out;
}

void removeScratch() {
    std::error_code ignored;
    if (!gDir.empty()) fs::remove_all(gDir, ignored);
}

void makeScratch() {
    const fs::path base = fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    gDir = base / ("vtex-fuzz-pipeline-" + std::to_string(::getpid()));
    fs::remove_all(gDir);
    fs::create_directories(gDir / "meshes");
    fs::create_directories(gDir / "dir.toml");
    writeText(gDir / "hill.obj", kHill);
    writeText(gDir / "cross.obj", kCross);
    writeText(gDir / "meshes" / "tree.glb", std::string_view(kTinyGlb, sizeof kTinyGlb - 1));
    writeText(gDir / "tiny.glb", std::string_view(kTinyGlb, sizeof kTinyGlb - 1));
    for (const char* scene : {"hill.toml", "scene.toml", "fig7-grass-hill.toml", "fig6-bush-field.toml",
                              "fig10-fur-torus.toml", "fig9-forest-hill.toml", "fig11-blocks.toml", "fig1-brushed.toml",
                              "fig8-velvet.toml", "study-forest.toml", "fig4-bush.toml"})
        writeText(gDir / scene, kScene);
    if (::mkfifo((gDir / "fifo.toml").c_str(), 0600) != 0 || ::mkfifo((gDir / "fifo.obj").c_str(), 0600) != 0)
        broken("mkfifo");
    fs::create_symlink("/dev/zero", gDir / "zero.toml");
    fs::create_symlink("/dev/zero", gDir / "zero.obj");
    fs::create_symlink("/dev/null", gDir / "null.toml");
    fs::create_symlink("loop-b", gDir / "loop-a");
    fs::create_symlink("loop-a", gDir / "loop-b");
    fs::create_symlink("hill.toml", gDir / "link.toml");
    for (const fs::path& entry : entries()) gFixtures[entry.lexically_relative(gDir).string()] = describe(entry);
    std::atexit(removeScratch);
}

bool usableName(const std::string& n) {
    return !n.empty() && n.size() <= 100 && n.find_first_of(std::string("/\\\0", 3)) == std::string::npos &&
           n.front() != '.';
}

void checkNames(const std::vector<std::string>& names, const char* kind) {
    std::set<std::string> seen;
    for (const std::string& n : names) {
        check(usableName(n), std::string(kind) + " name '" + n + "' accepted");
        check(seen.insert(n).second, std::string("duplicate ") + kind + " name '" + n + "' accepted");
    }
}

template <class Step>
std::vector<std::string> namesOf(const std::vector<Step>& steps) {
    std::vector<std::string> names;
    for (const Step& s : steps) names.push_back(s.name);
    return names;
}

bool contains(const std::vector<std::string>& names, const std::string& n) {
    return std::find(names.begin(), names.end(), n) != names.end();
}

// A path holding a NUL names a file no system call can open: the OS would read the path up to
// the NUL, another file than the one written.
// The value is one its table names (a parsed enum can hold no other).
template <class Enum, std::size_t N>
bool named(Enum value, const vtex::EnumNames<Enum, N>& names) {
    return names.parse(names.name(value)) == value;
}

void checkPath(const fs::path& path, const std::string& what) {
    check(path.string().find('\0') == std::string::npos, what + " holding a NUL accepted: " + path.string());
}

void checkAccepted(const Pipeline& p, const fs::path& file) {
    check(p.file == file, "Pipeline::file differs from the path read");
    checkPath(p.output, "output");
    check(!p.output.empty(), "empty output directory");
    const auto sources = namesOf(p.sources), texels = namesOf(p.texels), renders = namesOf(p.renders);
    checkNames(sources, "source");
    checkNames(texels, "texel");
    checkNames(renders, "render");
    checkNames(namesOf(p.compares), "compare");
    const auto& patterns = vtex::sampler::patternNames();
    for (const SourceStep& s : p.sources) {
        check(s.pattern.empty() != s.file.empty(), "source with both or neither of pattern and file");
        if (!s.pattern.empty()) check(contains(patterns, s.pattern), "unknown pattern accepted");
        checkPath(s.file, "source file");
        if (!s.file.empty()) check(fs::is_regular_file(s.file), "source file " + s.file.string() + " not a regular file");
        check(s.count >= 0 && s.count <= 1'000'000, "count out of range");
        check(std::isfinite(s.fluctuation) && s.fluctuation >= -1 && s.fluctuation <= 3.2, "fluctuation out of range");
        check(std::isfinite(s.leanDegrees) && std::abs(s.leanDegrees) <= 89, "lean out of range");
    }
    for (const TexelStep& t : p.texels) {
        check(contains(sources, t.source), "texel of an unknown source accepted");
        check(t.resolution >= 1 && t.resolution <= 4096 && (t.resolution & (t.resolution - 1)) == 0,
              "resolution not a power of two in [1, 4096]");
        check(named(t.solid, vtex::sampler::kSolidModeNames), "solid");
        check(named(t.filter, vtex::octree::kFilterRuleNames), "filter");
        check(std::isfinite(t.tolerance) && t.tolerance >= 0 && t.tolerance <= 1e6, "tolerance out of range");
    }
    for (const RenderStep& r : p.renders) {
        checkPath(r.scene, "scene");
        check(fs::is_regular_file(r.scene), "scene " + r.scene.string() + " not a regular file");
        const vtex::render::Scene scene = vtex::render::loadScene(r.scene);  // must load: it was checked
        for (const auto& binding : r.texels) {
            const std::string& sceneTexel = binding.first;
            check(contains(texels, binding.second), "binding to an unknown texel accepted");
            check(std::any_of(scene.texels.begin(), scene.texels.end(),
                              [&](const auto& t) { return t.name == sceneTexel; }),
                  "binding of a texel the scene does not define accepted");
        }
        check(r.width >= 0 && r.width <= 16384 && r.height >= 0 && r.height <= 16384, "image size out of range");
        check(r.spp >= 1 && r.spp <= 65536, "spp out of range");
        check(std::isfinite(r.lodBias) && std::abs(r.lodBias) <= 16, "lod_bias out of range");
        check(named(r.renderer, vtex::pipelines::kRendererNames), "renderer");
        check(named(r.mode, vtex::render::kReferenceModeNames), "mode");
        check(named(r.shading, vtex::render::kShadingModeNames), "shading");
        check(named(r.approximations, vtex::pipelines::kApproximationsNames), "approximations");
        check(r.tiles >= 1 && r.tiles <= RenderStep::kMaxTiles, "tiles out of range");
    }
    for (const CompareStep& c : p.compares)
        check(contains(renders, c.a) && contains(renders, c.b), "compare of an unknown render accepted");
    for (const std::string& w : p.warnings) check(w.find('\n') == std::string::npos, "warning of several lines");
    check(p.slurm.cpus >= 1 && p.slurm.cpus <= 4096, "slurm.cpus out of range");
    for (const std::string& a : p.slurm.sbatchArguments) check(!a.empty() && a.find('\n') == std::string::npos, "sbatch argument");
}

void checkFolderUnchanged() {
    std::size_t seen = 0;
    for (const fs::path& entry : entries()) {
        const std::string name = entry.lexically_relative(gDir).string();
        if (name == "p.toml" || name == "f.toml") continue;
        const auto found = gFixtures.find(name);
        check(found != gFixtures.end(), "reading the pipeline made " + name);
        check(found->second == describe(entry), "reading the pipeline changed " + name);
        ++seen;
    }
    check(seen == gFixtures.size(), "reading the pipeline removed a fixture");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    makeScratch();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::string_view text(reinterpret_cast<const char*>(data), size);
    std::string_view scene;
    const std::string_view marker = "#%f.toml\n";
    if (const auto at = text.find(marker); at != std::string_view::npos) {
        scene = text.substr(at + marker.size());
        text = text.substr(0, at);
    }
    const fs::path file = gDir / "p.toml";
    writeText(file, text);
    writeText(gDir / "f.toml", scene);
    try {
        checkAccepted(loadPipeline(file), file);
        if (std::getenv("VTEX_FUZZ_ECHO")) std::fprintf(stderr, "accepted\n");
    } catch (const vtex::InputError& e) {
        // Refused: the CLI prints what() as its one line, exit 3.
        const std::string message = e.what();
        if (std::getenv("VTEX_FUZZ_ECHO")) std::fprintf(stderr, "refused: %s\n", message.c_str());
        check(message.find('\n') == std::string::npos && message.find('\r') == std::string::npos,
              "error message of several lines: " + message);
        // The file as the message writes it (control characters and NUL as \xHH).
        std::string named = vtex::InputError(e.file(), "").what();
        named.resize(named.size() - 1);  // "<file>: "
        check(!e.file().empty() && message.rfind(named, 0) == 0, "error message does not begin with the file: " + message);
    }
    checkFolderUnchanged();
    return 0;
}
