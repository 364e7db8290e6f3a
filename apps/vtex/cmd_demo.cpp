// `vtex demo [-o DIR]`: the built-in showcase (vtex::pipelines::runDemo).
#include "cli.h"

#include <vtex/pipelines/demo.h>
#include <vtex/sampler/patterns.h>

#include <iostream>

namespace vtex::cli {
namespace {

const bool registered = registerCommand(90, [](CLI::App& app) -> Action {
    app.name("demo");
    app.description("The built-in showcase: the paper's patterns turned into texels, no input needed");
    auto options = std::make_shared<pipelines::DemoOptions>();
    app.add_option("-o,--output", options->outputDirectory, "Directory for everything the demo makes")
        ->capture_default_str();
    app.add_option("--resolution", options->resolution, "Finest voxels per side (a power of two)")
        ->capture_default_str()
        ->check(CLI::Range(4u, 1024u))
        ->check(CLI::Validator(
            [](std::string& value) {
                const unsigned long n = std::stoul(value);
                return (n & (n - 1)) == 0 ? std::string() : std::string("must be a power of two");
            },
            "POWER OF TWO"));
    app.add_option("--seed", options->seed, "Seed of the procedural patterns")->capture_default_str();
    app.add_option("--pattern", options->patterns, "Run only these patterns (repeatable)")
        ->check(CLI::IsMember(sampler::patternNames()));
    return [options](const GlobalOptions& global) {
        TerminalProgress progress(global);
        const pipelines::DemoReport report = pipelines::runDemo(*options, progress);
        std::cout << pipelines::formatDemoReport(report);
    };
});

}  // namespace
}  // namespace vtex::cli
