/// @file
/// @brief What every `vtex` subcommand shares: registration, verbosity, progress on a terminal.
///
/// A subcommand lives in its own cmd_<name>.cpp, declares its flags on the CLI::App it is
/// given, and returns the action to run after parsing. Actions throw vtex::InputError for bad
/// input (exit 3), vtex::IoError or anything else for other failures (exit 1); main() maps
/// them. No algorithm lives in apps/: actions call the stage libraries.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/octree/volume.h>

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <ostream>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace vtex::cli {

enum class Verbosity { Quiet, Normal, Verbose };

/// Options every subcommand understands (given before or after the subcommand name).
struct GlobalOptions {
    bool quiet = false;
    bool verbose = false;
    Verbosity verbosity() const {
        return quiet ? Verbosity::Quiet : verbose ? Verbosity::Verbose : Verbosity::Normal;
    }
};

using Action = std::function<void(const GlobalOptions&)>;
using CommandFactory = std::function<Action(CLI::App& app)>;

/// Registers a subcommand; called from a static initialiser in each cmd_<name>.cpp. `order`
/// sorts the subcommands in `vtex --help` by pipeline stage.
bool registerCommand(int order, CommandFactory factory);

/// What `vtex inspect` was asked for: JSON instead of a summary; for an octree, the source mesh
/// to measure each level's chord transmittance against.
struct InspectOptions {
    bool json = false;
    std::filesystem::path source;
};

/// How `vtex inspect` summarises one kind of file; registered per file extension (".glb",
/// ".vtl", ...) from a cmd_inspect_<kind>.cpp. Writes a human summary, or JSON when asked, to
/// `out`; throws vtex::InputError for a file it cannot read.
using Inspector = std::function<void(const std::filesystem::path& file, const InspectOptions& options, std::ostream& out)>;
bool registerInspector(const std::string& extension, Inspector inspector);
const Inspector* findInspector(const std::string& extension);

/// Accepts a finite number: CLI11's ranges let NaN through (every comparison with it is false),
/// and an infinite or NaN flag would reach the stages as a value. Checked before any range.
CLI::Validator finiteNumber();

/// Accepts a whole number from `least` to `most`, written in decimal digits only: CLI11 took -1
/// for an unsigned option's 2⁶⁴ − 1 and saturated larger numbers (found by fuzz_cli.py), and its
/// own ranges print their bounds as doubles of 300 digits.
CLI::Validator wholeNumber(std::uint64_t least, std::uint64_t most);

/// Accepts a seed: a whole number from 0 to 2⁶³ − 1, what a pipeline file can hold (TOML integers
/// are signed 64-bit); `vtex demo --seed -1` wrote a pipeline it then could not read.
CLI::Validator seedNumber();

/// `--max-memory SIZE` into `limit`, which starts at vtex::defaultMemoryLimit() (half of this
/// machine's physical memory): a resolution, image or volume too large for it is refused at once
/// with its estimate (exit 3) instead of running into the kernel's OOM killer. `work` says what
/// is estimated ("the sampler's footprint").
CLI::Option* addMaxMemoryOption(CLI::App& app, std::uint64_t& limit, const std::string& work);

/// `--threads N` into `threads`, one meaning for every command that uses threads: the worker
/// threads it may run at once, 0 (the default) all cores.
CLI::Option* addThreadsOption(CLI::App& app, int& threads);

/// Holds the process's TBB workers to `threads` while it lives (tbb::global_control); 0: no limit.
class ThreadLimit {
public:
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;

private:
    std::unique_ptr<struct ThreadControl> mControl;
};

/// A command's output files, each as (flag, path), checked before any work: every non-empty
/// path with checkOutputPath against `inputs` (exit 3), and no two flags naming one file (bad
/// usage, exit 2: `-o a.exr --png a.exr` would write both and keep the second).
void checkOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                  const std::vector<std::filesystem::path>& inputs);

/// Bad usage (CLI::ValidationError naming `flag`) unless the file name's extension (any case) is
/// one of `formats` ("exr", "png") or it has none (written in the first): the format an image
/// output is written in follows its name. An empty name passes (no such output).
void checkImageExtension(const std::string& flag, const std::string& file, const std::vector<std::string>& formats);

/// A region of voxels given on the command line as `x0,y0,z0,x1,y1,z1`: finest voxel indices,
/// the minimum corner inclusive and the maximum exclusive (octree::VoxelBox), each from 0 to `n`
/// (`vtex sample --update`, `vtex build --update`). Bad usage (CLI::ValidationError naming
/// `flag`) when not six whole numbers, beyond the volume or empty.
octree::VoxelBox parseRegion(const std::string& flag, const std::string& text, std::uint32_t n);

/// Accepts a power of two from 1 to `largest` (voxel resolutions).
CLI::Validator powerOfTwo(unsigned long long largest);

/// Status lines and warnings go to stderr; stdout carries only what was asked for.
void status(const GlobalOptions& options, const std::string& line);
void warning(const GlobalOptions& options, const std::string& line);

/// Draws one line on stderr (phase, percent, elapsed, remaining) when stderr is a terminal
/// and the user did not ask for --quiet; otherwise silent.
class TerminalProgress final : public Progress {
public:
    explicit TerminalProgress(const GlobalOptions& options);
    ~TerminalProgress() override;
    void start(std::string_view phase, std::uint64_t total) override;
    void advance(std::uint64_t units) override;
    void finish() override;

private:
    void draw(bool final);

    bool mEnabled;
    std::mutex mMutex;
    std::string mPhase;
    std::uint64_t mTotal = 0;
    std::uint64_t mDone = 0;
    std::chrono::steady_clock::time_point mStart;
    std::chrono::steady_clock::time_point mLastDraw;
    bool mDrawn = false;
};

}  // namespace vtex::cli
