// `vtex reference scene.toml -o truth.exr [...]`: the explicit-geometry reference renderer.
#include "cli.h"
#include "image_command.h"

#include <vtex/core/error.h>
#include <vtex/render/reference.h>

#include <iostream>
#include <sstream>

namespace vtex::cli {
namespace {

struct ReferenceArgs : ImageCommandArgs {
    int spp = 16;
    std::string mode = "embedded";
    double tolerance = 1e-3;
};

const bool registered = registerCommand(45, [](CLI::App& app) -> Action {
    app.name("reference");
    app.description("Render a scene with each texel's source mesh instead of its volume: the ground truth of vtex render");
    auto a = std::make_shared<ReferenceArgs>();
    addImageCommandOptions(app, *a, "Add a depth (Z) channel to the EXR (and a level channel, -1 everywhere)");
    app.add_option("--spp", a->spp, "Samples per pixel (jittered on a stratified grid, rounded up to a square)")
        ->check(CLI::Range(1, 65536))
        ->capture_default_str();
    app.add_option("--mode", a->mode,
                   "embedded: trace each cell's straight reference-space segment against one shared source BVH; "
                   "deformed: deform the source into every cell and trace one world BVH")
        ->check(CLI::IsMember(render::kReferenceModeNames.names()))
        ->capture_default_str();
    app.add_option("--tolerance", a->tolerance,
                   "Deformed mode: largest distance of a subdivided triangle from the deformed surface, fraction of the cell size")
        ->check(finiteNumber())
        ->check(CLI::Range(1e-6, 1.0))
        ->capture_default_str();
    return [a](const GlobalOptions& global) {
        const render::Scene scene = loadSceneFor(*a, global);
        render::ReferenceOptions options;
        applyImageOptions(*a, options);
        options.spp = a->spp;
        options.mode = *render::kReferenceModeNames.parse(a->mode);
        options.tolerance = a->tolerance;
        TerminalProgress progress(global);
        const render::RenderResult result = render::renderReference(scene, options, progress);
        writeImageOutputs(result, *a);
        printRenderWarnings(result, scene, global);
        std::ostringstream line;
        line << "rendered the " << a->mode << " reference " << result.image.width << "x" << result.image.height << " at "
             << result.stats.spp << " spp in " << result.stats.wallSeconds << " s on " << result.stats.threads << " threads ("
             << result.stats.primaryRays << " camera rays, " << result.stats.shadowRays << " shadow rays, "
             << result.stats.referenceTriangles << " triangles)";
        status(global, line.str());
    };
});

}  // namespace
}  // namespace vtex::cli
