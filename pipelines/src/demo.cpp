#include <vtex/pipelines/demo.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace vtex::pipelines {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// The base surface of the demo scenes: a grid of `cells`² bilinear quads over [-1, 1]², lifted
// into a round hill, faces counter-clockwise seen from above so that their normals point up.
void writeHillObj(const std::filesystem::path& file, int cells) {
    std::ostringstream obj;
    obj << "# vtex demo: a hill of " << cells * cells << " bilinear faces\n";
    for (int j = 0; j <= cells; ++j)
        for (int i = 0; i <= cells; ++i) {
            const double x = -1 + 2.0 * i / cells, y = -1 + 2.0 * j / cells;
            const double z = 0.35 * std::exp(-2.5 * (x * x + y * y));
            obj << "v " << x << ' ' << y << ' ' << z << '\n';
        }
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            const int a = j * (cells + 1) + i + 1;  // OBJ indices start at 1
            obj << "f " << a << ' ' << a + 1 << ' ' << a + cells + 2 << ' ' << a + cells + 1 << '\n';
        }
    writeFileAtomically(file, obj.str());
}

// A scene that covers the hill with one texel, lit by a low sun; paths relative to the scene.
void writeHillScene(const std::filesystem::path& file, const std::string& texel, const std::string& volume,
                    const std::string& source, double shellHeight, bool cyclic) {
    std::ostringstream toml;
    toml << "# vtex demo: the hill covered with the " << texel << " texel\n"
         << "[camera]\nposition = [0.0, -3.2, 1.6]\nlook_at = [0.0, 0.0, 0.1]\nup = [0.0, 0.0, 1.0]\n"
         << "fov_y = 38.0\nwidth = 384\nheight = 288\n\n"
         << "[[light]]\ntype = \"directional\"\ndirection = [-1.0, 0.6, -0.8]\ncolor = [2.6, 2.5, 2.3]\n\n"
         << "[[texel]]\nname = \"" << texel << "\"\nvolume = \"" << volume << "\"\nsource = \"" << source
         << "\"\ntau = 1.0\n"
         << "material = { diffuse = [1.0, 1.0, 1.0], specular = [0.05, 0.05, 0.05], shininess = 20.0, "
            "ambient = [0.03, 0.035, 0.04] }\n\n"
         << "[[surface]]\nmesh = \"hill.obj\"\ntexel = \"" << texel << "\"\nheight = " << shellHeight
         << "\nplacement = \"on\"\nrepeat = " << (cyclic ? "[2.0, 2.0]" : "[1.0, 1.0]") << "\n"
         << "material = { diffuse = [0.32, 0.26, 0.18], ambient = [0.02, 0.02, 0.02] }\n";
    writeFileAtomically(file, toml.str());
}

nlohmann::json toJson(const DemoReport& report) {
    nlohmann::json patterns = nlohmann::json::array();
    for (const DemoPattern& p : report.patterns) {
        nlohmann::json levels = nlohmann::json::array();
        for (const DemoLevel& l : p.levels)
            levels.push_back({{"level", l.level},
                              {"stored_nodes", l.storedNodes},
                              {"mean_density", l.meanDensity},
                              {"filter_error_neyret", l.filterErrorNeyret},
                              {"filter_error_sggx", l.filterErrorSggx}});
        nlohmann::json files = nlohmann::json::array();
        for (const auto& f : p.files) files.push_back(f.filename().string());
        patterns.push_back({{"name", p.name},
                            {"triangles", p.triangles},
                            {"source_area", p.sourceArea},
                            {"occupied_voxels", p.occupiedVoxels},
                            {"fit_error_mean", p.fitErrorMean},
                            {"compression_neyret", p.compressionNeyret},
                            {"compression_sggx", p.compressionSggx},
                            {"levels", levels},
                            {"seconds", {{"pattern", p.secondsPattern},
                                         {"ingest", p.secondsIngest},
                                         {"sample", p.secondsSample},
                                         {"build", p.secondsBuild},
                                         {"render", p.secondsRender}}},
                            {"render", {{"seconds", p.secondsRender},
                                        {"mean_level", p.meanLevel},
                                        {"rays", p.rays}}},
                            {"files", files}});
    }
    return {{"vtex_version", kVersion},
            {"resolution", report.options.resolution},
            {"seed", report.options.seed},
            {"seconds", report.seconds},
            {"patterns", patterns}};
}

}  // namespace

DemoReport runDemo(const DemoOptions& options, Progress& progress) {
    const auto start = Clock::now();
    DemoReport report;
    report.options = options;
    const std::vector<std::string> names =
        options.patterns.empty() ? sampler::patternNames() : options.patterns;
    for (const auto& name : names) {
        bool known = false;
        for (const auto& n : sampler::patternNames()) known |= (n == name);
        if (!known) throw std::invalid_argument("unknown pattern '" + name + "'");
    }

    std::error_code error;
    std::filesystem::create_directories(options.outputDirectory, error);
    if (error) throw IoError(options.outputDirectory, "cannot create the output directory: " + error.message());

    constexpr int kHillCells = 12;
    writeHillObj(options.outputDirectory / "hill.obj", kHillCells);
    report.hillFaces = kHillCells * kHillCells;

    for (const std::string& name : names) {
        DemoPattern result;
        result.name = name;
        const std::filesystem::path stem = options.outputDirectory / name;

        auto t = Clock::now();
        sampler::PatternOptions patternOptions;
        patternOptions.seed = options.seed;
        const ingest::TriangleMesh generated = sampler::makePattern(name, patternOptions);
        ingest::writeMeshGlb(generated, stem.string() + ".glb");
        result.files.push_back(stem.string() + ".glb");
        result.secondsPattern = secondsSince(t);

        // Read the pattern back as a user's file: the demo exercises the same path.
        t = Clock::now();
        const ingest::TriangleMesh mesh = ingest::loadMesh(stem.string() + ".glb");
        result.triangles = mesh.triangles.size();
        result.secondsIngest = secondsSince(t);

        t = Clock::now();
        sampler::SampleOptions sampleOptions;
        sampleOptions.resolution = options.resolution;
        sampleOptions.cyclic = sampler::isCyclicPattern(name);
        const octree::SparseVolume volume = sampler::sampleMesh(mesh, sampleOptions, progress);
        octree::writeVtl(volume, stem.string() + ".vtl");
        result.files.push_back(stem.string() + ".vtl");
        result.sourceArea = volume.info.sourceArea;
        result.occupiedVoxels = volume.blocks.size();
        result.fitErrorMean = volume.info.fitError.mean;
        result.secondsSample = secondsSince(t);

        t = Clock::now();
        octree::BuildOptions buildOptions;
        buildOptions.rule = octree::FilterRule::Neyret;
        const octree::Octree neyret = octree::buildOctree(volume, buildOptions, progress);
        buildOptions.rule = octree::FilterRule::Sggx;
        const octree::Octree sggx = octree::buildOctree(volume, buildOptions, progress);
        octree::writeVto(neyret, stem.string() + "-neyret.vto");
        octree::writeVto(sggx, stem.string() + "-sggx.vto");
        result.files.push_back(stem.string() + "-neyret.vto");
        result.files.push_back(stem.string() + "-sggx.vto");
        result.secondsBuild = secondsSince(t);

        // Cover the hill with the texel and render it (one ray per pixel, the fast shading).
        t = Clock::now();
        const std::filesystem::path scene = options.outputDirectory / (name + "-hill.toml");
        const double faceWidth = 2.0 / kHillCells;
        writeHillScene(scene, name, name + "-sggx.vto", name + ".glb", 0.6 * faceWidth,
                       sampleOptions.cyclic);
        render::RenderOptions renderOptions;
        const render::RenderResult rendered = render::renderScene(render::loadScene(scene), renderOptions, progress);
        render::writeExr(rendered.image, stem.string() + "-hill.exr");
        render::writePng(rendered.image, stem.string() + "-hill.png");
        render::writeStatsJson(rendered.stats, stem.string() + "-hill-stats.json");
        for (const char* suffix : {"-hill.toml", "-hill.exr", "-hill.png", "-hill-stats.json"})
            result.files.push_back(stem.string() + suffix);
        result.secondsRender = secondsSince(t);
        result.meanLevel = rendered.stats.meanLevel();
        result.rays = rendered.stats.primaryRays + rendered.stats.shadowRays;

        result.compressionNeyret = neyret.compression();
        result.compressionSggx = sggx.compression();
        for (std::uint32_t level = 0; level < sggx.levelCount(); ++level) {
            DemoLevel l;
            l.level = level;
            l.storedNodes = sggx.stats[level].storedNodes;
            l.meanDensity = sggx.stats[level].meanDensity;
            l.filterErrorNeyret = neyret.stats[level].filterErrorMean;
            l.filterErrorSggx = sggx.stats[level].filterErrorMean;
            result.levels.push_back(l);
        }
        report.patterns.push_back(std::move(result));
    }

    report.seconds = secondsSince(start);
    report.summaryFile = options.outputDirectory / "demo.json";
    writeFileAtomically(report.summaryFile, toJson(report).dump(2) + "\n");
    return report;
}

std::string formatDemoReport(const DemoReport& report) {
    std::ostringstream out;
    char line[256];
    std::snprintf(line, sizeof line, "vtex demo: %zu patterns sampled at %u³, built with both filter rules\n\n",
                  report.patterns.size(), report.options.resolution);
    out << line;
    std::snprintf(line, sizeof line, "%-8s %9s %10s %9s %11s %11s %14s %8s\n", "pattern", "triangles",
                  "voxels", "fit err", "compr neyr", "compr sggx", "lvl0 err n/s", "seconds");
    out << line;
    for (const DemoPattern& p : report.patterns) {
        const DemoLevel& root = p.levels.front();
        std::snprintf(line, sizeof line, "%-8s %9llu %10llu %9.4f %10.2f%% %10.2f%% %6.3f/%-6.3f %8.2f\n",
                      p.name.c_str(), (unsigned long long)p.triangles, (unsigned long long)p.occupiedVoxels,
                      p.fitErrorMean, 100 * p.compressionNeyret, 100 * p.compressionSggx,
                      root.filterErrorNeyret, root.filterErrorSggx,
                      p.secondsPattern + p.secondsIngest + p.secondsSample + p.secondsBuild + p.secondsRender);
        out << line;
    }
    out << "\nFilter error per level (mean over the level's nodes; neyret / sggx):\n";
    for (const DemoPattern& p : report.patterns) {
        out << "  " << p.name << ":";
        for (const DemoLevel& l : p.levels) {
            std::snprintf(line, sizeof line, " L%u %.3f/%.3f", l.level, l.filterErrorNeyret, l.filterErrorSggx);
            out << line;
        }
        out << "\n";
    }
    out << "\nRenders of the hill (" << report.hillFaces << " faces) covered with each texel, 384x288, 1 ray per pixel:\n";
    for (const DemoPattern& p : report.patterns) {
        std::snprintf(line, sizeof line, "  %-8s %6.2f s  mean octree level %.2f  %llu rays  -> %s-hill.png\n",
                      p.name.c_str(), p.secondsRender, p.meanLevel, (unsigned long long)p.rays, p.name.c_str());
        out << line;
    }
    std::snprintf(line, sizeof line, "\nWrote %zu files to %s (summary: %s) in %.1f s.\n",
                  [&] {
                      std::size_t n = 2;  // demo.json and hill.obj
                      for (const auto& p : report.patterns) n += p.files.size();
                      return n;
                  }(),
                  report.options.outputDirectory.string().c_str(), report.summaryFile.string().c_str(),
                  report.seconds);
    out << line;
    out << "Not yet part of the demo: the explicit-geometry reference renders and the error-against-run-time "
           "report (the reference renderer is not built yet).\n";
    return out.str();
}

}  // namespace vtex::pipelines
