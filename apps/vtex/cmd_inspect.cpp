// `vtex inspect FILE [--json]`: what a .glb, .vtl or .vto holds. Each kind of file has its
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
    auto json = std::make_shared<bool>(false);
    app.add_option("FILE", *file, "The file to summarise")->required();
    app.add_flag("--json", *json, "Print JSON on stdout instead of a summary");
    return [file, json](const GlobalOptions&) {
        const std::filesystem::path path(*file);
        std::string extension = path.extension().string();
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        const Inspector* inspector = findInspector(extension);
        if (!inspector) throw InputError(path, "unknown file kind '" + extension + "'");
        if (!std::filesystem::is_regular_file(path)) throw InputError(path, "no such file");
        (*inspector)(path, *json, std::cout);
    };
});

}  // namespace
}  // namespace vtex::cli
