// What `vtex render` and `vtex reference` share: a scene in, an EXR (with a PNG preview and
// stats.json on request) out, and the options that size and parallelise the image.
#pragma once

#include "cli.h"

#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

#include <cstdint>
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
    std::uint64_t maxMemory = 0;
    /// --rows A:B, the rows [A, B) of the image alone (render::ImageOptions::rowBegin); empty: all.
    std::string rows;
};

/// SCENE, -o/--output, --png, --width, --height, --rows, --stats, --threads, --aov, --max-memory.
void addImageCommandOptions(CLI::App& app, ImageCommandArgs& args, const std::string& aovHelp);
/// The size, threads, AOVs and memory limit the flags set (the caller sets spp: its range differs).
void applyImageOptions(const ImageCommandArgs& args, render::ImageOptions& options);
/// Loads the scene, checks every output path before any work (checkOutputPath: a regular file
/// or a new path, none of the files the render reads: render::sceneFiles), and prints the
/// scene's warnings. --rows past the image's height is bad usage (CLI::ValidationError).
render::Scene loadSceneFor(const ImageCommandArgs& args, const GlobalOptions& global);
/// The render's own warnings (those past the scene's, which loadSceneFor printed): clamped
/// pixels, for one.
void printRenderWarnings(const render::RenderResult& result, const render::Scene& scene, const GlobalOptions& global);
/// The EXR, then the PNG and stats.json when asked for.
void writeImageOutputs(const render::RenderResult& result, const ImageCommandArgs& args);

}  // namespace vtex::cli
