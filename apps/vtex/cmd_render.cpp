// `vtex render scene.toml -o img.exr [--png img.png] [...]`: the texel renderer (render/).
#include "cli.h"
#include "image_command.h"

#include <vtex/core/error.h>
#include <vtex/render/renderer.h>

#include <iostream>
#include <sstream>

namespace vtex::cli {
namespace {

struct RenderArgs : ImageCommandArgs {
    int spp = 1;
    double lodBias = 0;
    std::string shading = "fast";
    double shadowRefresh = 1;
    std::string hybrid = "on";
    std::string levelFit = "on";
    bool exact = false;
};

const bool registered = registerCommand(40, [](CLI::App& app) -> Action {
    app.name("render");
    app.description("Render a scene of texel-covered surfaces (linear EXR, sRGB PNG preview, stats.json)");
    auto a = std::make_shared<RenderArgs>();
    addImageCommandOptions(app, *a, "Add depth (Z) and octree level (level) channels to the EXR");
    app.add_option("--spp", a->spp, "Samples per pixel (a stratified grid, rounded up to a square)")
        ->check(CLI::Range(1, 4096))
        ->capture_default_str();
    app.add_option("--lod-bias", a->lodBias, "Octree level bias: +1 is one level coarser")
        ->check(finiteNumber())
        ->check(CLI::Range(-32.0, 32.0))
        ->capture_default_str();
    app.add_option("--shadow-refresh", a->shadowRefresh,
                   "A new shadow query once a march's transmittance falls below this fraction of the last "
                   "query's (1, the default: a query at every voxel; below 1 faster, deeper voxels too bright)")
        ->check(finiteNumber())
        ->check(CLI::Range(0.001, 1.0))
        ->capture_default_str();
    app.add_flag("--exact", a->exact,
                 "Turn every approximation off (shadow reuse, lattice, blend cut-off, reflectance reuse): "
                 "the render they are measured against");
    app.add_option("--hybrid", a->hybrid,
                   "Trace a texel's source mesh where the footprint is finer than its volume is faithful "
                   "(on, the default, for texels with a source) or always march the volume (off)")
        ->check(CLI::IsMember({"on", "off"}))
        ->capture_default_str();
    app.add_option("--level-fit", a->levelFit,
                   "Scale each level's density so that it lets through, across the shell, what the texel's source "
                   "mesh does (on, the default, for texels with a source; measured at load) or keep the filtered densities (off)")
        ->check(CLI::IsMember({"on", "off"}))
        ->capture_default_str();
    app.add_option("--shading", a->shading, "Micro-primitive reflectance: fast (SGGX visible-normal quadrature) or reference (the paper's integration)")
        ->check(CLI::IsMember(render::kShadingModeNames.names()))
        ->capture_default_str();
    return [a](const GlobalOptions& global) {
        const render::Scene scene = loadSceneFor(*a, global);
        render::RenderOptions options;
        applyImageOptions(*a, options);
        options.spp = a->spp;
        options.lodBias = a->lodBias;
        options.shading = *render::kShadingModeNames.parse(a->shading);
        if (a->exact) options.approximations = render::ApproximationBudget::exact();
        else options.approximations.shadowRefresh = a->shadowRefresh;
        options.hybrid = a->hybrid == "on";
        options.fitLevels = a->levelFit == "on";
        TerminalProgress progress(global);
        const render::RenderResult result = render::renderScene(scene, options, progress);
        writeImageOutputs(result, *a);
        printRenderWarnings(result, scene, global);
        std::ostringstream line;
        line << "rendered " << result.image.width << "x" << result.image.height << " in " << result.stats.wallSeconds
             << " s on " << result.stats.threads << " threads (" << result.stats.primaryRays << " camera rays, "
             << result.stats.shadowRays << " shadow rays, " << result.stats.voxelsVisited << " voxels)";
        status(global, line.str());
    };
});

}  // namespace
}  // namespace vtex::cli
