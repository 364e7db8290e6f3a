// `vtex render scene.toml -o img.exr [--png img.png] [...]`: the texel renderer (render/).
#include "cli.h"

#include <vtex/core/error.h>
#include <vtex/render/renderer.h>

#include <iostream>
#include <sstream>

namespace vtex::cli {
namespace {

struct RenderArgs {
    std::string scene;
    std::string output;
    std::string png;
    std::string stats;
    int width = 0;
    int height = 0;
    int spp = 1;
    double lodBias = 0;
    int threads = 0;
    std::string shading = "fast";
    bool aovs = false;
};

const bool registered = registerCommand(40, [](CLI::App& app) -> Action {
    app.name("render");
    app.description("Render a scene of texel-covered surfaces (linear EXR, sRGB PNG preview, stats.json)");
    auto a = std::make_shared<RenderArgs>();
    app.add_option("SCENE", a->scene, "The scene file (scene.toml)")->required();
    app.add_option("-o,--output", a->output, "The linear OpenEXR image to write")->required();
    app.add_option("--png", a->png, "Also write an sRGB PNG preview");
    app.add_option("--width", a->width, "Image width (default: the scene's camera.width)")->check(CLI::Range(1, 16384));
    app.add_option("--height", a->height, "Image height (default: the scene's camera.height)")->check(CLI::Range(1, 16384));
    app.add_option("--spp", a->spp, "Samples per pixel (a stratified grid, rounded up to a square)")
        ->check(CLI::Range(1, 4096))
        ->capture_default_str();
    app.add_option("--lod-bias", a->lodBias, "Octree level bias: +1 is one level coarser")
        ->check(CLI::Range(-32.0, 32.0))
        ->capture_default_str();
    app.add_option("--stats", a->stats, "Write statistics (time, rays, voxels, level histogram) as JSON");
    app.add_option("--threads", a->threads, "Worker threads (0: all cores)")->check(CLI::Range(0, 1024))->capture_default_str();
    app.add_option("--shading", a->shading, "Micro-primitive reflectance: fast (SGGX visible-normal quadrature) or reference (the paper's integration)")
        ->check(CLI::IsMember({"fast", "reference"}))
        ->capture_default_str();
    app.add_flag("--aov", a->aovs, "Add depth (Z) and octree level (level) channels to the EXR");
    app.footer("Exit status: 0 success, 2 bad usage, 3 bad input (file and key named), 1 other failure.");
    return [a](const GlobalOptions& global) {
        const render::Scene scene = render::loadScene(a->scene);
        for (const auto& w : scene.warnings) warning(global, w);
        render::RenderOptions options;
        options.width = a->width;
        options.height = a->height;
        options.spp = a->spp;
        options.lodBias = a->lodBias;
        options.threads = a->threads;
        options.shading = a->shading == "reference" ? render::ShadingMode::Reference : render::ShadingMode::Fast;
        options.aovs = a->aovs;
        TerminalProgress progress(global);
        const render::RenderResult result = render::renderScene(scene, options, progress);
        render::writeExr(result.image, a->output);
        if (!a->png.empty()) render::writePng(result.image, a->png);
        if (!a->stats.empty()) render::writeStatsJson(result.stats, a->stats);
        std::ostringstream line;
        line << "rendered " << result.image.width << "x" << result.image.height << " in " << result.stats.wallSeconds
             << " s on " << result.stats.threads << " threads (" << result.stats.primaryRays << " camera rays, "
             << result.stats.shadowRays << " shadow rays, " << result.stats.voxelsVisited << " voxels)";
        status(global, line.str());
    };
});

}  // namespace
}  // namespace vtex::cli
