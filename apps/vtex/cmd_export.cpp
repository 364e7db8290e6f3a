// `vtex export texel.vto -o texel.vdb [--level L | --levels all] [--tau T] [--scale S]
// [--translate X,Y,Z]`: a texel's levels as OpenVDB grids for Blender, Houdini, Nuke;
// `vtex export scene.toml -o layout.glb`: the scene's base meshes and texel cells as glTF, to lay
// the texels out in Blender (interop library, docs/export.md).
#include "cli.h"

#include "vtex_commit.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/interop/layout_glb.h>
#include <vtex/interop/vdb.h>
#include <vtex/octree/octree.h>
#include <vtex/render/scene.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

namespace vtex::cli {
namespace {

std::string lowerExtension(const std::string& file) {
    std::string extension = std::filesystem::path(file).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return extension;
}

struct ExportFlags {
    std::string input;
    std::string output;
    std::uint32_t level = 0;
    std::string levels;
    double tau = 1;
    double scale = 1;
    std::vector<double> translate{0, 0, 0};
    std::string centres = "openvdb";
    std::vector<double> along;
};

// Bad usage that needs no file read: the input's kind. True for an octree, false for a scene.
bool isOctreeExport(const ExportFlags& flags) {
    const std::string in = lowerExtension(flags.input);
    if (in == ".vto") return true;
    if (in == ".toml") return false;
    throw CLI::ValidationError("INPUT", flags.input + ": export reads an octree (.vto) or a scene (.toml), not '" +
                                            in + "'");
}

// Bad usage once the output path is known to be writable (checkOutputs: a FIFO or an input named
// as the output is refused first, exit 3, as for every command): the output's kind follows the
// input's (a name without an extension takes it), an octree's options on a scene, a .vdb from a
// build without OpenVDB.
void checkOutputKind(const ExportFlags& flags, bool octree, const std::vector<const CLI::Option*>& octreeOptions) {
    const std::string out = lowerExtension(flags.output);
    const std::string wanted = octree ? ".vdb" : ".glb";
    if (!out.empty() && out != wanted)
        throw CLI::ValidationError("--output", flags.output + ": " +
                                                   (octree ? "an octree is exported to OpenVDB (.vdb)"
                                                           : "a scene is exported as its layout (.glb)") +
                                                   ", not '" + out + "'");
    if (!octree)
        for (const CLI::Option* option : octreeOptions)
            if (option->count() > 0)
                throw CLI::ValidationError(option->get_name(),
                                           "applies to an octree (.vto) export, not a scene's layout");
    if (octree && !interop::kHasOpenVdb)
        throw CLI::ValidationError("--output", "this vtex was built without OpenVDB (install libopenvdb-dev and "
                                               "libboost-iostreams-dev, then rebuild): it cannot write .vdb");
}

void exportLayout(const ExportFlags& flags, const std::vector<const CLI::Option*>& octreeOptions,
                  const GlobalOptions& global) {
    const render::Scene scene = render::loadScene(flags.input);
    checkOutputs({{"--output", flags.output}}, render::sceneFiles(scene));  // before any work (atomic_file.h)
    checkOutputKind(flags, false, octreeOptions);
    for (const std::string& w : scene.warnings) warning(global, flags.input + ": " + w);
    const interop::LayoutSummary summary = interop::writeLayoutGlb(scene, flags.output);
    status(global, flags.input + ": " + std::to_string(summary.surfaces) + " surfaces, " +
                       std::to_string(summary.faces) + " faces, " + std::to_string(summary.cells) +
                       " texel cells -> " + flags.output);
}

// The levels asked for, once the octree says which it has: --level L, --levels all, or the finest.
std::vector<std::uint32_t> exportLevels(const ExportFlags& flags, bool levelGiven, const octree::Octree& tree) {
    const std::uint32_t finest = tree.levelCount() - 1;
    if (!flags.levels.empty()) {
        std::vector<std::uint32_t> all(tree.levelCount());
        for (std::uint32_t l = 0; l <= finest; ++l) all[l] = l;
        return all;
    }
    if (!levelGiven) return {finest};
    if (flags.level > finest)
        throw CLI::ValidationError("--level", "no level " + std::to_string(flags.level) + " in " + flags.input +
                                              " (levels 0 to " + std::to_string(finest) + ")");
    return {flags.level};
}

std::array<double, 3> unitDirection(const std::vector<double>& w) {
    const double length = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(length > 1e-12) || !std::isfinite(length))
        throw CLI::ValidationError("--along", "needs a non-zero direction");
    return {w[0] / length, w[1] / length, w[2] / length};
}

// The options of an octree export, --level first (a scene's layout takes none of them).
std::vector<const CLI::Option*> addOctreeOptions(CLI::App& app, ExportFlags& flags) {
    auto* level = app.add_option("--level", flags.level, "The level to export (default: the finest)")
                      ->check(wholeNumber(0, octree::kMaxLevel));
    auto* levels = app.add_option("--levels", flags.levels, "all: every level, grid names suffixed _L<level>")
        ->check(CLI::IsMember({"all"}))
        ->excludes(level);
    auto* tau = app.add_option("--tau", flags.tau, "Density -> extinction constant (a scene texel's tau)")
        ->check(finiteNumber())
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    auto* scale = app.add_option("--scale", flags.scale,
                                 "World length of one reference unit (the texel is the unit cube)")
        ->check(finiteNumber())
        ->check(CLI::Range(1e-9, 1e9))
        ->capture_default_str();
    auto* translate = app.add_option("--translate", flags.translate, "World position X,Y,Z of the reference origin")
        ->delimiter(',')
        ->expected(3)
        ->check(finiteNumber())
        ->capture_default_str();
    auto* centres = app.add_option("--voxel-centres", flags.centres,
                                   "openvdb: voxel i centred on index i (OpenVDB, Houdini); blender: voxel i over "
                                   "[i, i+1] of index space, as Blender's Cycles draws it")
                        ->check(CLI::IsMember({"openvdb", "blender"}))
                        ->capture_default_str();
    auto* along = app.add_option("--along", flags.along,
                                 "Unit direction X,Y,Z: density is the extinction along it (tau*rho*sqrt(w'Sw)) "
                                 "instead of the direction average, for a fixed view in a renderer without anisotropy")
                      ->delimiter(',')
                      ->expected(3)
                      ->check(finiteNumber());
    return {level, levels, tau, scale, translate, centres, along};
}

const bool registered = registerCommand(55, [](CLI::App& app) -> Action {
    app.name("export");
    app.description(
        "Write what vtex makes for other tools: an octree (.vto) as OpenVDB grids (.vdb: density as extinction, "
        "albedo, the six SGGX entries), a scene (.toml) as its base meshes and texel cells (.glb); docs/export.md");
    auto flags = std::make_shared<ExportFlags>();
    app.add_option("INPUT", flags->input, "Octree (.vto) or scene (.toml)")->required();
    app.add_option("-o,--output", flags->output, "File to write: .vdb for an octree, .glb for a scene")->required();
    const std::vector<const CLI::Option*> octreeOptions = addOctreeOptions(app, *flags);
    const CLI::Option* level = octreeOptions.front();
    return [flags, level, octreeOptions](const GlobalOptions& global) {
        if (!isOctreeExport(*flags)) return exportLayout(*flags, octreeOptions, global);
        checkOutputs({{"--output", flags->output}}, {flags->input});  // before any work (atomic_file.h)
        checkOutputKind(*flags, true, octreeOptions);
        interop::VdbExportOptions options;
        options.tau = flags->tau;
        options.scale = flags->scale;
        std::copy(flags->translate.begin(), flags->translate.end(), options.translate.begin());
        options.centres =
            flags->centres == "blender" ? interop::VoxelCentres::Blender : interop::VoxelCentres::OpenVdb;
        if (!flags->along.empty()) options.along = unitDirection(flags->along);
        options.writer = std::string(kVersion) + " (commit " + kCommit + ")";
        options.source = std::filesystem::path(flags->input).filename().string();
        const octree::Octree tree = octree::readVto(flags->input);
        options.levels = exportLevels(*flags, level->count() > 0, tree);
        const auto summary = interop::writeVdb(tree, options, flags->output);
        for (const interop::VdbLevelSummary& s : summary) {
            char line[512];
            std::snprintf(line, sizeof line,
                          "%s: level %u: %llu active voxels (%llu in %llu tiles, %llu in leaf nodes), density grid "
                          "%.1f MiB -> %s",
                          flags->input.c_str(), s.level, (unsigned long long)s.activeVoxels,
                          (unsigned long long)(s.activeVoxels - s.leafVoxels), (unsigned long long)s.tiles,
                          (unsigned long long)s.leafVoxels, double(s.memoryBytes) / (1 << 20), flags->output.c_str());
            status(global, line);
        }
    };
});

}  // namespace
}  // namespace vtex::cli
