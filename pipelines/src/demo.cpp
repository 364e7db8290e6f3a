#include <vtex/pipelines/demo.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace vtex::pipelines {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
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
                                         {"build", p.secondsBuild}}},
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
                      p.secondsPattern + p.secondsIngest + p.secondsSample + p.secondsBuild);
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
    std::snprintf(line, sizeof line, "\nWrote %zu files to %s (summary: %s) in %.1f s.\n",
                  [&] {
                      std::size_t n = 1;
                      for (const auto& p : report.patterns) n += p.files.size();
                      return n;
                  }(),
                  report.options.outputDirectory.string().c_str(), report.summaryFile.string().c_str(),
                  report.seconds);
    out << line;
    out << "Not yet part of the demo: rendering, the reference renderer and the error-against-run-time "
           "report (their stages are not built yet).\n";
    return out.str();
}

}  // namespace vtex::pipelines
