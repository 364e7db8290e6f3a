// Runs a program (sbatch, squeue, scancel) and captures what it prints: the Slurm executor's
// only way to talk to the cluster, since Slurm's C API (slurm.h) is not stable across releases
// and the commands are what every site supports.
#pragma once

#include <string>
#include <vector>

namespace vtex::pipelines::detail {

struct ProcessResult {
    int exitStatus = -1;  ///< the program's exit status; -1 when it died of a signal or timed out
    bool timedOut = false;
    std::string out, err;
};

/// Runs argv[0] (looked up in PATH) with argv, stdin from /dev/null, and waits at most
/// `timeoutSeconds` (then kills it: a controller that does not answer must not hang vtex).
/// Throws std::runtime_error when the program cannot be started (not installed), naming it.
ProcessResult runProcess(const std::vector<std::string>& argv, double timeoutSeconds = 60);

/// argv as one line a user could paste into a shell (words quoted where they need it).
std::string commandLine(const std::vector<std::string>& argv);

/// `word` quoted for a POSIX shell when it holds anything but [A-Za-z0-9_./:=@%+,-].
std::string shellWord(const std::string& word);

}  // namespace vtex::pipelines::detail
