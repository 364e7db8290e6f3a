// `vtex sample mesh.glb -o leaves.vtl --resolution N [--cyclic] [--solid auto|on|off]
// [--update old.vtl --region x0,y0,z0,x1,y1,z1]`: the finest level of a texel (sampler library),
// or an earlier one re-sampled inside a region (the partial recompute).
#include "cli.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>
#include <vtex/sampler/sampler.h>

#include <vtex/octree/volume.h>

#include <chrono>
#include <cstdio>
#include <optional>

namespace vtex::cli {
namespace {

// The earlier volume of `--update`, and the resolution it fixes unless -r was given.
octree::SparseVolume readEarlierVolume(const std::string& file, bool resolutionGiven, std::uint32_t& resolution) {
    octree::SparseVolume old = octree::readVtl(file);
    if (!resolutionGiven) resolution = std::uint32_t(1) << old.info.levels;
    return old;
}

struct SampleFlags {
    std::string input;
    std::string output;
    std::uint32_t resolution = 128;
    bool cyclic = false;
    std::string solid = "auto";
    std::string bounds = "auto";
    double solidDensity = 0;
    std::uint64_t maxMemory = 0;
    int threads = 0;
    std::string update;
    std::string region;
};

// The sampling of `vtex sample` (resolutionGiven: -r was on the command line, so an --update
// keeps it rather than the earlier volume's).
void runSample(SampleFlags flags, bool resolutionGiven, const GlobalOptions& global) {
    const ThreadLimit threadLimit(flags.threads);
    checkOutputPath(flags.output, {flags.input, flags.update});  // before any work (atomic_file.h)
    const auto start = std::chrono::steady_clock::now();
    std::optional<octree::SparseVolume> old;
    std::optional<octree::VoxelBox> regionBox;
    if (!flags.update.empty()) {
        old = readEarlierVolume(flags.update, resolutionGiven, flags.resolution);
        regionBox = parseRegion("--region", flags.region, flags.resolution);  // before the mesh is read
    }
    const ingest::TriangleMesh mesh = ingest::loadMesh(flags.input);
    sampler::SampleOptions options;
    options.resolution = flags.resolution;
    options.cyclic = flags.cyclic;
    options.solid = *sampler::kSolidModeNames.parse(flags.solid);
    options.bounds = *sampler::kBoundsModeNames.parse(flags.bounds);
    options.solidDensity = flags.solidDensity;
    options.maxMemoryBytes = flags.maxMemory;
    options.source = flags.input;
    if (options.cyclic && options.solid == sampler::SolidMode::On)
        throw CLI::ValidationError("--solid on", "cannot be combined with --cyclic");
    if (options.solid == sampler::SolidMode::On && !mesh.closed)
        throw InputError(flags.input, "--solid on needs a closed (watertight) mesh");
    if (global.verbosity() == Verbosity::Verbose) {
        char line[256];
        std::snprintf(line, sizeof line, "estimated footprint %.1f MiB",
                      double(sampler::estimateSampleMemory(mesh, options)) / 1048576.0);
        status(global, line);
    }
    options.region = regionBox;
    TerminalProgress progress(global);
    const octree::SparseVolume volume = old ? sampler::updateRegion(mesh, *old, options, flags.update, progress)
                                            : sampler::sampleMesh(mesh, options, progress);
    octree::writeVtl(volume, flags.output);
    std::uint64_t surface = 0, solid = 0;
    for (const auto& b : volume.blocks) (b.isSolid() ? solid : surface)++;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char line[512];
    std::snprintf(line, sizeof line, "%s: %u^3, %llu surface voxels, %llu solid blocks, fit error %.3g, %.2f s -> %s",
                  flags.input.c_str(), options.resolution, (unsigned long long)surface,
                  (unsigned long long)solid, volume.info.fitError.mean, seconds, flags.output.c_str());
    status(global, line);
}

const bool registered = registerCommand(20, [](CLI::App& app) -> Action {
    app.name("sample");
    app.description(
        "Sample a mesh into the finest level of a texel (.vtl): per voxel the density from the exact "
        "clipped area, the ellipsoid fitted to the normals, the albedo; solid interior of closed meshes");
    auto flags = std::make_shared<SampleFlags>();
    app.add_option("MESH", flags->input, "Source mesh (.glb, or anything `vtex ingest` reads)")->required();
    app.add_option("-o,--output", flags->output, "Sampled volume to write (.vtl)")->required();
    app.add_option("-r,--resolution", flags->resolution, "Voxels per side N, a power of two")
        ->capture_default_str()
        ->check(powerOfTwo(1ull << 20));
    app.add_flag("--cyclic", flags->cyclic, "Periodic in x and y (tileable patterns: grass, fur)");
    app.add_option("--solid", flags->solid, "Fill the interior of closed meshes: auto (if closed), on, off")
        ->capture_default_str()
        ->check(CLI::IsMember(sampler::kSolidModeNames.names()));
    app.add_option("--solid-density", flags->solidDensity, "Density of solid voxels, 1/length (0 = 16·N)")
        ->check(finiteNumber())
        ->check(CLI::NonNegativeNumber);
    app.add_option("--bounds", flags->bounds,
                   "Source → unit cube: auto (unit if the mesh fits in [0,1]³, else fit), unit, fit")
        ->capture_default_str()
        ->check(CLI::IsMember(sampler::kBoundsModeNames.names()));
    addMaxMemoryOption(app, flags->maxMemory, "the sampler's footprint");
    addThreadsOption(app, flags->threads);
    auto* update = app.add_option("--update", flags->update,
                                  "Earlier volume (.vtl) of this mesh before an edit: re-sample only --region, keep the "
                                  "rest (the same options; its resolution unless -r is given)");
    auto* region = app.add_option("--region", flags->region,
                                  "With --update: the voxels to re-sample, x0,y0,z0,x1,y1,z1 in finest voxel indices, "
                                  "minimum inclusive, maximum exclusive; every voxel the edited triangles touched, before "
                                  "and after the edit, must lie inside");
    update->needs(region);
    region->needs(update);
    auto* resolution = app.get_option("--resolution");
    return [flags, resolution](const GlobalOptions& global) { runSample(*flags, resolution->count() > 0, global); };
});

}  // namespace
}  // namespace vtex::cli
