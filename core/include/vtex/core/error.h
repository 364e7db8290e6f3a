/// @file
/// @brief The exceptions that cross a stage boundary, and how the CLI maps them to exit codes.
///
/// Readers, writers, scene and pipeline parsers throw these; numerical code never does (it
/// returns an empty std::optional for a degenerate case instead).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace vtex {

/// Exit statuses of the `vtex` program (see DESIGN.md, "The command line").
enum class ExitStatus : int { Success = 0, Failure = 1, Usage = 2, BadInput = 3 };

/// `text` on one line, as InputError and IoError write their messages: newlines, carriage
/// returns and tabs as spaces, NUL and the other control characters as \xHH. For any message
/// that may quote untrusted text (a file's key, a command-line argument).
std::string oneLine(std::string_view text);

/// Malformed, truncated, hostile or absurd input data. `what()` is one line:
/// "<file>: [<location>: ]<problem>", where location is a glTF JSON path, an OBJ line, a
/// file section, a TOML key.
class InputError : public std::runtime_error {
public:
    InputError(const std::filesystem::path& file, const std::string& problem,
               const std::string& location = {});

    const std::filesystem::path& file() const { return mFile; }
    const std::string& location() const { return mLocation; }
    const std::string& problem() const { return mProblem; }

private:
    std::filesystem::path mFile;
    std::string mLocation;
    std::string mProblem;
};

/// The operating system refused a read or a write that should have worked (disk full,
/// permission denied on an output, rename across devices).
class IoError : public std::runtime_error {
public:
    IoError(const std::filesystem::path& file, const std::string& problem);
    const std::filesystem::path& file() const { return mFile; }

private:
    std::filesystem::path mFile;
};

}  // namespace vtex
