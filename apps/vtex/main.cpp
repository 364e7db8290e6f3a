// The `vtex` program: parses the command line, runs one subcommand, maps failures to the
// design's exit statuses (0 success, 1 failure, 2 bad usage, 3 bad input data).
#include "cli.h"
#include "registry.h"

#include "vtex_commit.h"

#include <vtex/core/error.h>
#include <vtex/core/version.h>

#include <algorithm>
#include <iostream>
#include <new>
#include <optional>
#include <string>
#include <vector>

namespace {

constexpr const char* kExitStatuses =
    "Exit status: 0 success, 1 failure, 2 bad usage, 3 bad input data (the message names the "
    "file and the problem).";

int exitCode(vtex::ExitStatus status) { return static_cast<int>(status); }

// Levenshtein distance, for "did you mean".
std::size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = up;
        }
    }
    return row[b.size()];
}

// The command line as CLI11 gets it: `vtex help [CMD]` is `vtex [CMD] --help`, as in git.
std::vector<std::string> normalisedArguments(int argc, char** argv) {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (!args.empty() && args[0] == "help") {
        args.erase(args.begin());
        args.resize(std::min<std::size_t>(args.size(), 1));
        args.push_back("--help");
    }
    return args;
}

// The first argument that is not a global flag, when it names no subcommand: the message
// suggests the nearest one (`vtex rendr` → render), as git does.
std::optional<std::string> unknownCommandMessage(const std::vector<std::string>& args, const CLI::App& app) {
    const auto first = std::find_if(args.begin(), args.end(), [](const std::string& a) { return a.empty() || a[0] != '-'; });
    if (first == args.end()) return std::nullopt;
    std::string nearest;
    std::size_t best = ~std::size_t(0);
    for (const CLI::App* sub : app.get_subcommands({})) {
        if (sub->get_name() == *first) return std::nullopt;
        const std::size_t d = editDistance(*first, sub->get_name());
        if (d < best) best = d, nearest = sub->get_name();
    }
    std::string message = "unknown command '" + *first + "'";
    if (best <= std::max<std::size_t>(2, nearest.size() / 3)) message += "; did you mean '" + nearest + "'?";
    return message + " (vtex --help lists the commands)";
}

}  // namespace

int main(int argc, char** argv) {
    using namespace vtex;
    CLI::App app{"vtex: multiscale volumetric textures (Neyret 1994) from meshes, and their "
                 "renderer",
                 "vtex"};
    app.footer(kExitStatuses);
    app.set_version_flag("--version", std::string("vtex ") + kVersion + " (commit " + kCommit + ")");
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

    std::vector<std::string> args = normalisedArguments(argc, argv);
    if (const auto unknown = unknownCommandMessage(args, app)) {
        std::cerr << "vtex: error: " << oneLine(*unknown) << "\n";  // it quotes the argument: one line (fuzz_cli.py)
        return exitCode(ExitStatus::Usage);
    }
    std::reverse(args.begin(), args.end());  // CLI11 takes a vector last argument first
    try {
        app.parse(args);
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
