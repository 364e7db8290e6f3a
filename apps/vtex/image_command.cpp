#include "image_command.h"

#include <vtex/core/atomic_file.h>
#include <vtex/render/image.h>

#include <optional>
#include <stdexcept>
#include <string>

namespace vtex::cli {
namespace {

// `--rows A:B`: whole numbers, A below B (B exclusive), into `begin` and `end`; what is wrong
// with the text otherwise. Whether B fits the image is known once the scene is read
// (loadSceneFor).
std::string parseRows(const std::string& text, int& begin, int& end) {
    const std::size_t colon = text.find(':');
    const auto number = [](const std::string& s) {
        return !s.empty() && s.size() <= 5 && s.find_first_not_of("0123456789") == std::string::npos;
    };
    if (colon == std::string::npos || !number(text.substr(0, colon)) || !number(text.substr(colon + 1)))
        return "expected A:B, the rows from A (inclusive) to B (exclusive), whole numbers";
    begin = std::stoi(text.substr(0, colon));
    end = std::stoi(text.substr(colon + 1));
    return begin < end ? "" : "empty: A must be below B (which is exclusive)";
}

}  // namespace

void addImageCommandOptions(CLI::App& app, ImageCommandArgs& args, const std::string& aovHelp) {
    app.add_option("SCENE", args.scene, "The scene file (scene.toml)")->required();
    app.add_option("-o,--output", args.output, "The image to write, by its extension: .exr (linear OpenEXR) or .png (sRGB)")
        ->required();
    app.add_option("--png", args.png, "Also write an sRGB PNG preview");
    app.add_option("--width", args.width, "Image width (default: the scene's camera.width)")->check(CLI::Range(1, 16384));
    app.add_option("--height", args.height, "Image height (default: the scene's camera.height)")->check(CLI::Range(1, 16384));
    app.add_option("--rows", args.rows,
                   "Render only the rows A to B (B exclusive, row 0 at the top) of the image: an image of those rows, "
                   "each pixel exactly as in the whole render")
        ->type_name("A:B")
        ->check(CLI::Validator(
            [](std::string& text) {
                int begin = 0, end = 0;
                const std::string why = parseRows(text, begin, end);
                return why.empty() ? why : text + ": " + why;
            },
            "A:B"));
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
    if (!args.rows.empty()) parseRows(args.rows, options.rowBegin, options.rowEnd);  // checked when parsed
}

render::Scene loadSceneFor(const ImageCommandArgs& args, const GlobalOptions& global) {
    // Every output checked before any work (atomic_file.h), against every file the render reads:
    // `-o plane.obj` would replace the scene's mesh. Parsing the scene reads the scene file alone.
    render::Scene scene = render::loadScene(args.scene);
    const std::vector<std::filesystem::path> inputs = render::sceneFiles(scene);
    checkOutputs({{"-o", args.output}, {"--png", args.png}, {"--stats", args.stats}}, inputs);
    // The format follows the name (after the checks above, which say more about a path that is
    // a directory, a device or an input): a typo is bad usage before any rendering.
    checkImageExtension("--output", args.output, {"exr", "png"});
    checkImageExtension("--png", args.png, {"png"});
    render::ImageOptions rows;
    applyImageOptions(args, rows);
    try {
        render::imageRows(rows, args.height > 0 ? args.height : scene.camera.height);
    } catch (const std::invalid_argument& e) {
        throw CLI::ValidationError("--rows", e.what());
    }
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
    if (render::imageFormat(args.output) == "png") render::writePng(result.image, exr);
    else render::writeExr(result.image, exr);
    if (!args.png.empty()) render::writePng(result.image, png.emplace(args.png));
    if (!args.stats.empty()) render::writeStatsJson(result.stats, stats.emplace(args.stats));
    commitAll({&exr, png ? &*png : nullptr, stats ? &*stats : nullptr});
}

}  // namespace vtex::cli
