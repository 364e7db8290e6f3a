// The `vtex` program: parses the command line, runs one subcommand, maps failures to the
// design's exit statuses (0 success, 1 failure, 2 bad usage, 3 bad input data).
#include "cli.h"
#include "registry.h"

#include <vtex/core/error.h>
#include <vtex/core/version.h>

#include <algorithm>
#include <iostream>
#include <new>

namespace {

constexpr const char* kExitStatuses =
    "Exit status: 0 success, 1 failure, 2 bad usage, 3 bad input data (the message names the "
    "file and the problem).";

int exitCode(vtex::ExitStatus status) { return static_cast<int>(status); }

}  // namespace

int main(int argc, char** argv) {
    using namespace vtex;
    CLI::App app{"vtex: multiscale volumetric textures (Neyret 1994) from meshes, and their "
                 "renderer",
                 "vtex"};
    app.footer(kExitStatuses);
    app.set_version_flag("--version", std::string("vtex ") + kVersion);
    app.require_subcommand(1);
    app.fallthrough();

    cli::GlobalOptions options;
    app.add_flag("-q,--quiet", options.quiet, "Print nothing but errors");
    app.add_flag("-v,--verbose", options.verbose, "Print more detail");

    auto& registry = cli::commandRegistry();
    std::stable_sort(registry.begin(), registry.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<std::pair<CLI::App*, cli::Action>> actions;
    for (auto& [order, factory] : registry) {
        (void)order;
        CLI::App* sub = app.add_subcommand();
        sub->footer(kExitStatuses);
        actions.emplace_back(sub, factory(*sub));
    }

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // CLI11 quotes the arguments back, and an argument may hold a newline (found by
        // fuzz_cli.py): every message is printed on one line (oneLine).
        std::cerr << "vtex: error: " << oneLine(e.what()) << "\n"
                  << "Run 'vtex --help' or 'vtex <command> --help' for usage.\n";
        return exitCode(ExitStatus::Usage);
    }

    try {
        for (auto& [sub, action] : actions)
            if (sub->parsed()) action(options);
        return exitCode(ExitStatus::Success);
    } catch (const CLI::Error& e) {
        // A flag combination an action found invalid after parsing is still bad usage.
        std::cerr << "vtex: error: " << oneLine(e.what()) << '\n';
        return exitCode(ExitStatus::Usage);
    } catch (const InputError& e) {
        std::cerr << "vtex: error: " << oneLine(e.what()) << '\n';
        return exitCode(ExitStatus::BadInput);
    } catch (const IoError& e) {
        std::cerr << "vtex: error: " << oneLine(e.what()) << '\n';
        return exitCode(ExitStatus::Failure);
    } catch (const std::bad_alloc&) {
        std::cerr << "vtex: error: out of memory\n";
        return exitCode(ExitStatus::Failure);
    } catch (const std::exception& e) {
        std::cerr << "vtex: error: " << oneLine(e.what()) << '\n';
        return exitCode(ExitStatus::Failure);
    }
}
