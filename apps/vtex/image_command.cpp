#include "image_command.h"

#include <vtex/core/atomic_file.h>
#include <vtex/render/image.h>

#include <optional>

namespace vtex::cli {

void addImageCommandOptions(CLI::App& app, ImageCommandArgs& args, const std::string& aovHelp) {
    app.add_option("SCENE", args.scene, "The scene file (scene.toml)")->required();
    app.add_option("-o,--output", args.output, "The linear OpenEXR image to write")->required();
    app.add_option("--png", args.png, "Also write an sRGB PNG preview");
    app.add_option("--width", args.width, "Image width (default: the scene's camera.width)")->check(CLI::Range(1, 16384));
    app.add_option("--height", args.height, "Image height (default: the scene's camera.height)")->check(CLI::Range(1, 16384));
    app.add_option("--stats", args.stats, "Write statistics (times, rays, …) as JSON");
    addThreadsOption(app, args.threads);
    app.add_flag("--aov", args.aovs, aovHelp);
    addMaxMemoryOption(app, args.maxMemory, "the image and what the scene loads");
    app.footer("Exit status: 0 success, 2 bad usage, 3 bad input (file and key named), 1 other failure.");
}

void applyImageOptions(const ImageCommandArgs& args, render::ImageOptions& options) {
    options.width = args.width;
    options.height = args.height;
    options.threads = args.threads;
    options.aovs = args.aovs;
    options.maxMemoryBytes = args.maxMemory;
}

render::Scene loadSceneFor(const ImageCommandArgs& args, const GlobalOptions& global) {
    // Every output checked before any work (atomic_file.h), against every file the render reads:
    // `-o plane.obj` would replace the scene's mesh. Parsing the scene reads the scene file alone.
    render::Scene scene = render::loadScene(args.scene);
    const std::vector<std::filesystem::path> inputs = render::sceneFiles(scene);
    checkOutputs({{"-o", args.output}, {"--png", args.png}, {"--stats", args.stats}}, inputs);
    for (const auto& w : scene.warnings) warning(global, w);
    return scene;
}

void printRenderWarnings(const render::RenderResult& result, const render::Scene& scene, const GlobalOptions& global) {
    for (std::size_t i = scene.warnings.size(); i < result.warnings.size(); ++i) warning(global, result.warnings[i]);
}

void writeImageOutputs(const render::RenderResult& result, const ImageCommandArgs& args) {
    // All or none (commitAll): a full disk while writing the PNG leaves no EXR either.
    AtomicOutputFile exr(args.output);
    std::optional<AtomicOutputFile> png, stats;
    render::writeExr(result.image, exr);
    if (!args.png.empty()) render::writePng(result.image, png.emplace(args.png));
    if (!args.stats.empty()) render::writeStatsJson(result.stats, stats.emplace(args.stats));
    commitAll({&exr, png ? &*png : nullptr, stats ? &*stats : nullptr});
}

}  // namespace vtex::cli
