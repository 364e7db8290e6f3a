/// @file
/// @brief Runs the `vtex` program from a test and captures its exit status and output.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace vtex::test {

struct RunResult {
    int exitStatus = -1;   ///< the process's exit status; -1 when it died of a signal
    int signal = 0;        ///< the signal that killed it, 0 when it exited
    std::string out;
    std::string err;
};

inline std::string shellQuote(const std::string& s) {
    std::string quoted = "'";
    for (char c : s) quoted += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

inline std::string readText(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

/// Runs `vtex args...` with stdin from /dev/null; stdout and stderr go through temporary files
/// in VTEX_TEST_TMP so that large outputs cannot dead-lock a pipe.
inline RunResult runVtex(const std::vector<std::string>& args) {
    namespace fs = std::filesystem;
    static int counter = 0;
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "run";
    fs::create_directories(dir);
    // Appends rather than operator+ chains throughout: GCC 12 warns falsely (-Wrestrict) on
    // `"literal" + std::string`.
    std::string stem = std::to_string(::getpid());
    stem += '_';
    stem += std::to_string(counter++);
    fs::path outPath = dir / stem;
    outPath += ".out";
    fs::path errPath = dir / stem;
    errPath += ".err";

    std::string command = shellQuote(VTEX_BINARY);
    for (const auto& a : args) {
        command += ' ';
        command += shellQuote(a);
    }
    command += " </dev/null >";
    command += shellQuote(outPath.string());
    command += " 2>";
    command += shellQuote(errPath.string());

    RunResult result;
    const int raw = std::system(command.c_str());
    if (WIFEXITED(raw)) {
        result.exitStatus = WEXITSTATUS(raw);
        // The shell reports a child killed by a signal as 128 + signal.
        if (result.exitStatus > 128) {
            result.signal = result.exitStatus - 128;
            result.exitStatus = -1;
        }
    } else if (WIFSIGNALED(raw)) {
        result.signal = WTERMSIG(raw);
    }
    result.out = readText(outPath);
    result.err = readText(errPath);
    fs::remove(outPath);
    fs::remove(errPath);
    return result;
}

inline std::size_t lineCount(const std::string& text) {
    std::size_t lines = 0;
    for (char c : text) lines += (c == '\n');
    return lines;
}

}  // namespace vtex::test
