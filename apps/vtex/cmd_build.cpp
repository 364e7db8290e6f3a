// `vtex build leaves.vtl -o texel.vto [--filter neyret|sggx] [--tolerance E]`: every level,
// filtered and compressed (octree library).
#include "cli.h"
#include "fidelity_report.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/memory_budget.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/render/source_visibility.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>

namespace vtex::cli {
namespace {

const bool registered = registerCommand(30, [](CLI::App& app) -> Action {
    app.name("build");
    app.description(
        "Build the octree of a sampled volume (.vtl → .vto): all levels, filtered (the paper's rule "
        "or SGGX), compressed within a tolerance");
    struct Flags {
        std::string input;
        std::string output;
        std::string filter = "sggx";
        double tolerance = 0;
        std::uint64_t filterErrorSamples = 4096;
        std::uint64_t maxMemory = 0;
        int threads = 0;
        std::string source;
    };
    auto flags = std::make_shared<Flags>();
    app.add_option("VOLUME", flags->input, "Sampled volume (.vtl)")->required();
    app.add_option("-o,--output", flags->output, "Octree to write (.vto)")->required();
    app.add_option("--filter", flags->filter,
                   "Filter rule: neyret (mean of normalised M, the paper's) or sggx (mean of S)")
        ->capture_default_str()
        ->check(CLI::IsMember({"neyret", "sggx"}));
    app.add_option("--tolerance", flags->tolerance,
                   "Drop children a parent can stand for within this: the largest change of the transmittance "
                   "along any chord of the parent (per unit tau), and of the ellipsoid's entries and the albedo; "
                   "0 keeps only exactly constant regions")
        ->check(finiteNumber())
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e6));
    app.add_option("--filter-error-samples", flags->filterErrorSamples,
                   "Nodes per level on which the filter error is measured (0 = all)")
        ->check(wholeNumber(0, ~std::uint64_t(0)))
        ->capture_default_str();
    addMaxMemoryOption(app, flags->maxMemory, "reading the volume and building its octree");
    addThreadsOption(app, flags->threads);
    app.add_option("--source", flags->source,
                   "The mesh the volume was sampled from: report each level's transmittance against it along "
                   "chords of the texel and over beams of the level (as vtex inspect --source)");
    return [flags](const GlobalOptions& global) {
        const ThreadLimit threadLimit(flags->threads);
        checkOutputPath(flags->output, {flags->input, flags->source});  // before any work (atomic_file.h)
        checkMemoryEstimate(flags->input, "building its octree", octree::estimateBuildMemory(flags->input),
                            flags->maxMemory);
        // The source is loaded before the build, quiet or not: a bad --source fails (exit 3,
        // naming it) before any work and leaves no .vto.
        std::optional<ingest::TriangleMesh> source;
        if (!flags->source.empty()) source = ingest::loadMesh(flags->source);
        const auto start = std::chrono::steady_clock::now();
        octree::SparseVolume volume = octree::readVtl(flags->input);
        octree::BuildOptions options;
        options.rule = *octree::parseFilterRule(flags->filter);
        options.tolerance = flags->tolerance;
        options.filterErrorSamples = flags->filterErrorSamples;
        TerminalProgress progress(global);
        const octree::Octree tree = octree::buildOctree(std::move(volume), options, progress);
        octree::writeVto(tree, flags->output);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        char line[512];
        std::snprintf(line, sizeof line, "%s: %u levels, %llu stored nodes, compression %.2f%%, %.2f s -> %s",
                      flags->input.c_str(), tree.levelCount(), (unsigned long long)tree.storedNodes(),
                      100.0 * tree.compression(), seconds, flags->output.c_str());
        status(global, line);
        if (source && global.verbosity() != Verbosity::Quiet)
            printFidelity(render::measureSourceFidelity(tree, *source), flags->source, std::cerr);
    };
});

}  // namespace
}  // namespace vtex::cli
