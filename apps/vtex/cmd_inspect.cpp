// `vtex inspect FILE [--json] [--source MESH]`: what a .glb, .vtl or .vto holds. Each kind of file has its
// inspector in a cmd_inspect_<kind>.cpp; this file only dispatches on the extension.
#include "cli.h"

#include <vtex/core/error.h>

#include <algorithm>
#include <iostream>

namespace vtex::cli {
namespace {

const bool registered = registerCommand(50, [](CLI::App& app) -> Action {
    app.name("inspect");
    app.description("Summarise a mesh (.glb), sampled volume (.vtl) or octree (.vto)");
    auto file = std::make_shared<std::string>();
    auto options = std::make_shared<InspectOptions>();
    app.add_option("FILE", *file, "The file to summarise")->required();
    app.add_flag("--json", options->json, "Print JSON on stdout instead of a summary");
    app.add_option("--source", options->source,
                   "Octrees: the source mesh, to measure each level's transmittance along random chords against "
                   "the fraction of them that miss it");
    return [file, options](const GlobalOptions&) {
        const std::filesystem::path path(*file);
        std::string extension = path.extension().string();
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        const Inspector* inspector = findInspector(extension);
        if (!inspector) throw InputError(path, "unknown file kind '" + extension + "'");
        std::error_code error;  // a name too long or a link loop is no such file either, not an exception
        if (!std::filesystem::is_regular_file(path, error)) throw InputError(path, "no such file");
        if (!options->source.empty() && extension != ".vto")
            throw CLI::ValidationError("--source", "only for an octree (.vto)");
        (*inspector)(path, *options, std::cout);
    };
});

}  // namespace
}  // namespace vtex::cli
