// `vtex reference scene.toml -o truth.exr [...]`: the explicit-geometry reference renderer.
#include "cli.h"

#include <vtex/core/error.h>
#include <vtex/render/reference.h>

#include <iostream>
#include <sstream>

namespace vtex::cli {
namespace {

struct ReferenceArgs {
    std::string scene;
    std::string output;
    std::string png;
    std::string stats;
    int width = 0;
    int height = 0;
    int spp = 16;
    int threads = 0;
    std::string mode = "embedded";
    double tolerance = 1e-3;
    double maxMemoryGiB = 4;
    bool aovs = false;
};

const bool registered = registerCommand(45, [](CLI::App& app) -> Action {
    app.name("reference");
    app.description("Render a scene with each texel's source mesh instead of its volume: the ground truth of vtex render");
    auto a = std::make_shared<ReferenceArgs>();
    app.add_option("SCENE", a->scene, "The scene file (scene.toml); every texel used needs `source =`")->required();
    app.add_option("-o,--output", a->output, "The linear OpenEXR image to write")->required();
    app.add_option("--png", a->png, "Also write an sRGB PNG preview");
    app.add_option("--width", a->width, "Image width (default: the scene's camera.width)")->check(CLI::Range(1, 16384));
    app.add_option("--height", a->height, "Image height (default: the scene's camera.height)")->check(CLI::Range(1, 16384));
    app.add_option("--spp", a->spp, "Samples per pixel (jittered on a stratified grid, rounded up to a square)")
        ->check(CLI::Range(1, 65536))
        ->capture_default_str();
    app.add_option("--mode", a->mode,
                   "embedded: trace each cell's straight reference-space segment against one shared source BVH; "
                   "deformed: deform the source into every cell and trace one world BVH")
        ->check(CLI::IsMember({"embedded", "deformed"}))
        ->capture_default_str();
    app.add_option("--tolerance", a->tolerance,
                   "Deformed mode: largest distance of a subdivided triangle from the deformed surface, fraction of the cell size")
        ->check(CLI::Range(1e-6, 1.0))
        ->capture_default_str();
    app.add_option("--max-memory", a->maxMemoryGiB, "Deformed mode: refuse scenes whose deformed triangles need more (GiB)")
        ->check(CLI::Range(1e-6, 1024.0))
        ->capture_default_str();
    app.add_option("--stats", a->stats, "Write statistics (time, rays, triangles) as JSON");
    app.add_option("--threads", a->threads, "Worker threads (0: all cores)")->check(CLI::Range(0, 1024))->capture_default_str();
    app.add_flag("--aov", a->aovs, "Add a depth (Z) channel to the EXR (and a level channel, −1 everywhere)");
    app.footer("Exit status: 0 success, 2 bad usage, 3 bad input (file and key named), 1 other failure.");
    return [a](const GlobalOptions& global) {
        const render::Scene scene = render::loadScene(a->scene);
        for (const auto& w : scene.warnings) warning(global, w);
        render::ReferenceOptions options;
        options.width = a->width;
        options.height = a->height;
        options.spp = a->spp;
        options.threads = a->threads;
        options.aovs = a->aovs;
        options.mode = a->mode == "deformed" ? render::ReferenceMode::Deformed : render::ReferenceMode::Embedded;
        options.tolerance = a->tolerance;
        options.maxMemoryBytes = a->maxMemoryGiB * double(1ull << 30);
        TerminalProgress progress(global);
        const render::RenderResult result = render::renderReference(scene, options, progress);
        render::writeExr(result.image, a->output);
        if (!a->png.empty()) render::writePng(result.image, a->png);
        if (!a->stats.empty()) render::writeStatsJson(result.stats, a->stats);
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
