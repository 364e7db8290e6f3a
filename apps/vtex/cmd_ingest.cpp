// `vtex ingest IN -o mesh.glb [--report r.json]`: load, validate, repair, bake transforms,
// write the canonical mesh.
#include "cli.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>

#include <cstdio>
#include <optional>

namespace vtex::cli {
namespace {

const bool registered = registerCommand(10, [](CLI::App& app) -> Action {
    app.name("ingest");
    app.description(
        "Load a .gltf/.glb/.obj/.off/.ply/.stl mesh, validate and repair it, bake node "
        "transforms, and write the canonical mesh as .glb");
    struct Flags {
        std::string input;
        std::string output;
        std::string report;
        std::string up;
        std::string fit = "keep";
        ingest::IngestOptions options;
    };
    auto flags = std::make_shared<Flags>();
    app.add_option("IN", flags->input, "Source mesh")->required();
    app.add_option("-o,--output", flags->output, "Canonical mesh to write (.glb)")->required();
    app.add_option("--report", flags->report, "Write a JSON report (counts, bounds, repairs, warnings)");
    app.add_option("--max-triangles", flags->options.maxTriangles,
                   "Refuse meshes with more triangles than this")
        ->capture_default_str()
        ->check(wholeNumber(1, ~std::uint64_t(0)));
    app.add_option("--weld-tolerance", flags->options.weldTolerance,
                   "Merge vertices closer than this fraction of the bounding-box diagonal")
        ->check(finiteNumber())
        ->capture_default_str()
        ->check(CLI::Range(0.0, 0.01));
    app.add_option("--up", flags->up,
                   "The file's up axis, turned to vtex's +Z (default: the format's own, +Y for glTF "
                   "except vtex's own .glb, +Z for OBJ, OFF, PLY and STL)")
        ->check(CLI::IsMember({"x", "y", "z"}));
    app.add_option("--fit", flags->fit,
                   "keep the coordinates, or scale uniformly into the unit cell, centred in x and y "
                   "with the base at z = 0 (cell)")
        ->check(CLI::IsMember({"keep", "cell"}))
        ->capture_default_str();
    app.add_flag("--drop-invalid", flags->options.dropInvalidFaces,
                 "Drop faces with an index out of range or a NaN/Inf coordinate (counted in the "
                 "report) instead of refusing the file");
    return [flags](const GlobalOptions& global) {
        // Both outputs checked before any work (atomic_file.h).
        checkOutputs({{"-o", flags->output}, {"--report", flags->report}}, {flags->input});
        TerminalProgress progress(global);
        ingest::IngestOptions options = flags->options;
        options.progress = &progress;
        options.up = flags->up.empty() ? 0 : flags->up[0];
        options.fitCell = flags->fit == "cell";
        ingest::IngestReport report;
        const ingest::TriangleMesh mesh = ingest::loadMesh(flags->input, options, &report);
        // All or none (commitAll): a report that cannot be written leaves no mesh either.
        AtomicOutputFile glb(flags->output);
        std::optional<AtomicOutputFile> json;
        ingest::writeMeshGlb(mesh, glb);
        if (!flags->report.empty()) json.emplace(flags->report).stream() << ingest::toJson(report);
        commitAll({&glb, json ? &*json : nullptr});
        for (const auto& w : report.warnings) warning(global, flags->input + ": " + w);
        char line[512];
        std::snprintf(line, sizeof line,
                      "%s: %llu triangles in, %llu out, %llu vertices, %s, %.3f s -> %s",
                      flags->input.c_str(), (unsigned long long)report.trianglesIn,
                      (unsigned long long)report.trianglesOut, (unsigned long long)report.verticesOut,
                      report.closed ? "closed" : "open", report.seconds, flags->output.c_str());
        status(global, line);
    };
});

}  // namespace
}  // namespace vtex::cli
