// `vtex build leaves.vtl -o texel.vto [--filter neyret|sggx] [--tolerance E]
// [--update old.vto --region x0,y0,z0,x1,y1,z1]`: every level, filtered and compressed (octree
// library), or an earlier octree with only the ancestors of a region filtered again.
#include "cli.h"
#include "fidelity_report.h"
#include "huge_pages.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/memory_budget.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/render/renderer.h>
#include <vtex/render/source_visibility.h>

#include <chrono>
#include <cstdio>
#include <algorithm>
#include <iostream>
#include <limits>
#include <optional>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace vtex::cli {
namespace {

// Keeps the memory the build frees for its next allocations instead of returning it to the
// kernel. The build allocates and frees a series of arrays of millions of nodes (the file, the
// volume, each pyramid level, the stored tree); glibc unmaps every freed block above its mmap
// threshold and trims the heap's top, and the next array faults its pages in afresh. On this
// project's VMs a page fault costs some 14 µs per 4 KiB page (the 2 MiB pages of
// huge_pages.cpp cover only the aligned middle of each allocation): a 512³ bush build took
// 10,800 faults and 0.21 s of system time, 3,400 and 0.12 s with its allocations served from
// a heap that keeps what is freed (perf stat, medians of 5). Only the build asks for this: it is
// short-lived, and its peak resident memory stays the same (239 → 241 MiB).
//
// The heap is then grown by the build's estimated memory at once and advised for huge pages
// (reserveHugePageHeap), and the worker threads allocate from it too instead of from arenas of
// their own (which glibc maps apart, in 4 KiB pages): the 256³ bush build's page faults fell
// from 2,400–2,900 to 580, 470 of them the program's start, and its CPU time from 213–272 to
// 184–201 ms (perf stat -r 10, 1 and 2 threads, six rounds alternated with the build before).
// The threads allocate little (a few vectors per range of nodes), so the one arena's lock costs
// nothing measurable.
void keepFreedMemory(std::uint64_t estimate) {
#if defined(__GLIBC__)
    mallopt(M_MMAP_MAX, 0);                 // every block from the heap, so that a freed one is reused
    mallopt(M_TRIM_THRESHOLD, 0x7fffffff);  // never give the heap's top back
    mallopt(M_TOP_PAD, 64 << 20);           // grow the heap in large steps
    mallopt(M_ARENA_MAX, 1);                // every thread's blocks from that heap
#endif
    if (estimate > 0 && estimate <= std::numeric_limits<std::size_t>::max())
        reserveHugePageHeap(std::size_t(estimate));
}

// Refuses an earlier octree that a full build of `volume` with `options` would not have made.
void checkEarlierTree(const octree::Octree& old, const octree::SparseVolume& volume, const octree::BuildOptions& options,
                      const std::string& file) {
    const auto& was = old.info.source;
    if (was.levels != volume.info.levels || was.cyclic != volume.info.cyclic || was.scale != volume.info.scale ||
        was.offset != volume.info.offset)
        throw InputError(file, "built from a volume sampled otherwise (resolution, --cyclic or mapping): build in full");
    if (old.info.rule != options.rule || old.info.tolerance != float(options.tolerance))
        throw InputError(file, "built with --filter " + std::string(octree::filterRuleName(old.info.rule)) + " --tolerance " +
                                   std::to_string(old.info.tolerance) + ", not the options given now");
}

// The octree of `volume`: with `--update`, the earlier tree's builder resumed and only the region
// filtered again when the tree allows it (OctreeBuilder::resume), else a full build; the same
// tree either way. `how` says which.
octree::Octree buildOrUpdate(octree::SparseVolume volume, const octree::BuildOptions& options,
                             const std::string& update, const std::string& regionText, Progress& progress,
                             std::string& how) {
    how = "full build";
    if (update.empty()) return octree::buildOctree(std::move(volume), options, progress);
    const octree::Octree old = octree::readVto(update);  // every section checked
    checkEarlierTree(old, volume, options, update);
    const octree::VoxelBox region = parseRegion("--region", regionText, std::uint32_t(1) << volume.info.levels);
    const bool solid = std::any_of(volume.blocks.begin(), volume.blocks.end(), [](const auto& b) { return b.isSolid(); });
    auto builder = solid ? std::nullopt : octree::OctreeBuilder::resume(old, volume.info, options);
    if (!builder) {
        how = "full build (" + update + " merged nodes or holds a solid interior)";
        return octree::buildOctree(std::move(volume), options, progress);
    }
    std::vector<octree::VolumeBlock> inside;
    for (const auto& b : volume.blocks) {
        const auto c = octree::mortonDecode(b.key);
        if (region.contains(c[0], c[1], c[2])) inside.push_back(b);
    }
    builder->updateRegion(region, std::move(inside), progress);
    how = "updated " + update + " in the region";
    return builder->compress(progress);
}

struct BuildFlags {
    std::string input;
    std::string output;
    std::string filter = "sggx";
    double tolerance = 0;
    std::uint64_t filterErrorSamples = 4096;
    std::uint64_t maxMemory = 0;
    int threads = 0;
    std::string source;
    double tau = 1;
    std::string update;
    std::string region;
};

// The build of `vtex build`: checks, reads, builds or updates, measures against --source, writes.
void runBuild(const BuildFlags& flags, const GlobalOptions& global) {
    const ThreadLimit threadLimit(flags.threads);
    checkOutputPath(flags.output, {flags.input, flags.source, flags.update});  // before any work (atomic_file.h)
    const std::uint64_t estimate = octree::estimateBuildMemory(flags.input);
    checkMemoryEstimate(flags.input, "building its octree", estimate, flags.maxMemory);
    keepFreedMemory(estimate);
    // The source is loaded before the build, quiet or not: a bad --source fails (exit 3,
    // naming it) before any work and leaves no .vto.
    std::optional<ingest::TriangleMesh> source;
    if (!flags.source.empty()) source = ingest::loadMesh(flags.source);
    const auto start = std::chrono::steady_clock::now();
    octree::SparseVolume volume = octree::readVtl(flags.input);
    octree::BuildOptions options;
    options.rule = *octree::parseFilterRule(flags.filter);
    options.tolerance = flags.tolerance;
    options.filterErrorSamples = flags.filterErrorSamples;
    TerminalProgress progress(global);
    std::string how;
    octree::Octree tree = buildOrUpdate(std::move(volume), options, flags.update, flags.region, progress, how);
    // What a render with the default options measures of the texel against the source at
    // load (render::measureSource), stored in the file: a tree built or updated here never
    // carries an earlier tree's measures, which were of other levels.
    if (source) {
        tree.measures = render::measureSource(tree, *source, flags.tau, render::RenderOptions{}.hybridTolerance,
                                              flags.source);
        how += ", source measures stored";
    }
    octree::writeVto(tree, flags.output);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char line[1024];
    std::snprintf(line, sizeof line, "%s: %u levels, %llu stored nodes, compression %.2f%%, %s, %.2f s -> %s",
                  flags.input.c_str(), tree.levelCount(), (unsigned long long)tree.storedNodes(),
                  100.0 * tree.compression(), how.c_str(), seconds, flags.output.c_str());
    status(global, line);
    if (source && global.verbosity() != Verbosity::Quiet)
        printFidelity(render::measureSourceFidelity(tree, *source), flags.source, std::cerr);
}

const bool registered = registerCommand(30, [](CLI::App& app) -> Action {
    app.name("build");
    app.description(
        "Build the octree of a sampled volume (.vtl → .vto): all levels, filtered (the paper's rule "
        "or SGGX), compressed within a tolerance");
    auto flags = std::make_shared<BuildFlags>();
    app.add_option("VOLUME", flags->input, "Sampled volume (.vtl)")->required();
    app.add_option("-o,--output", flags->output, "Octree to write (.vto)")->required();
    app.add_option("--filter", flags->filter,
                   "Filter rule: neyret (mean of normalised M, the paper's) or sggx (mean of S)")
        ->capture_default_str()
        ->check(CLI::IsMember(octree::kFilterRuleNames.names()));
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
                   "chords of the texel and over beams of the level (as vtex inspect --source), and store in the "
                   "octree what a render measures against it at load, so that renders with this source take it "
                   "instead of measuring (stats.json: source_measures)");
    app.add_option("--tau", flags->tau,
                   "With --source: the scene's texel tau the stored measures are for (a render with another tau "
                   "measures at load)")
        ->check(finiteNumber())
        ->capture_default_str()
        ->check(CLI::Range(1e-6, 1e6));
    auto* update = app.add_option("--update", flags->update,
                                  "Earlier octree (.vto) of this volume before an edit inside --region: filter again only "
                                  "the region's ancestors (the same options; an octree that merged nodes, or a solid "
                                  "interior, is built in full)");
    auto* region = app.add_option("--region", flags->region,
                                  "With --update: the voxels that changed, x0,y0,z0,x1,y1,z1 in finest voxel indices, "
                                  "minimum inclusive, maximum exclusive (as given to vtex sample --update)");
    update->needs(region);
    region->needs(update);
    return [flags](const GlobalOptions& global) { runBuild(*flags, global); };
});

}  // namespace
}  // namespace vtex::cli
