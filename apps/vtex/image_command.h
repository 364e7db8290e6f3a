// What `vtex render` and `vtex reference` share: a scene in, an EXR (with a PNG preview and
// stats.json on request) out, and the options that size and parallelise the image.
#pragma once

#include "cli.h"

#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

#include <string>

namespace vtex::cli {

struct ImageCommandArgs {
    std::string scene;
    std::string output;
    std::string png;
    std::string stats;
    int width = 0;
    int height = 0;
    int threads = 0;
    bool aovs = false;
};

/// SCENE, -o/--output, --png, --width, --height, --stats, --threads, --aov.
void addImageCommandOptions(CLI::App& app, ImageCommandArgs& args, const std::string& aovHelp);
/// Loads the scene, checks every output path before any work (checkOutputPath: a regular file
/// or a new path, none of the files the render reads: render::sceneFiles), and prints the
/// scene's warnings.
render::Scene loadSceneFor(const ImageCommandArgs& args, const GlobalOptions& global);
/// The render's own warnings (those past the scene's, which loadSceneFor printed): clamped
/// pixels, for one.
void printRenderWarnings(const render::RenderResult& result, const render::Scene& scene, const GlobalOptions& global);
/// The EXR, then the PNG and stats.json when asked for.
void writeImageOutputs(const render::RenderResult& result, const ImageCommandArgs& args);

}  // namespace vtex::cli
