// `vtex demo [-o DIR]`: the built-in showcase (vtex::pipelines::runDemo).
#include "cli.h"
#include "run_progress.h"

#include <vtex/pipelines/demo.h>

#include <iostream>

namespace vtex::cli {
namespace {

const bool registered = registerCommand(90, [](CLI::App& app) -> Action {
    app.name("demo");
    app.description("The built-in showcase: the paper's figures rebuilt from the procedural patterns, run as a "
                    "cached pipeline with a report; needs no input");
    auto options = std::make_shared<pipelines::DemoOptions>();
    app.add_option("-o,--output", options->outputDirectory, "Directory for everything the demo makes")
        ->capture_default_str();
    app.add_option("--resolution", options->maxResolution, "Largest texel resolution (a power of two)")
        ->capture_default_str()
        ->check(CLI::Range(4u, 1024u))
        ->check(powerOfTwo(1024));
    app.add_option("--scale", options->imageScale, "Image size relative to 768x576")
        ->check(finiteNumber())
        ->capture_default_str()
        ->check(CLI::Range(0.05, 4.0));
    app.add_option("--seed", options->seed, "Seed of the procedural patterns")
        ->check(seedNumber())
        ->capture_default_str();
    app.add_flag("--force", options->force, "Redo every stage, cached or not");
    app.add_option("--jobs", options->run.jobs, "Stages run at once (0: as many as cores)")->check(CLI::Range(0, 1024));
    auto threads = std::make_shared<int>(0);
    addThreadsOption(app, *threads);
    return [options, threads](const GlobalOptions& global) {
        const ThreadLimit threadLimit(*threads);
        pipelines::RunReport report;
        {
            RunProgressDisplay display(global, options->run.jobs);  // gone before the summary is printed
            options->run.log = display.logger();
            if (display.enabled()) options->run.observer = &display;
            report = pipelines::runDemo(*options);
            options->run.observer = nullptr;
        }
        std::cout << pipelines::formatDemoReport(report);
        if (!report.succeeded()) throw std::runtime_error("some stages of the demo failed (see above)");
    };
});

}  // namespace
}  // namespace vtex::cli
