#include "cli.h"

#include <sstream>
#include "registry.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/memory_budget.h>
#include <vtex/render/image.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <system_error>

#include <unistd.h>

namespace vtex::cli {

std::vector<std::pair<int, CommandFactory>>& commandRegistry() {
    static std::vector<std::pair<int, CommandFactory>> registry;
    return registry;
}

bool registerCommand(int order, CommandFactory factory) {
    commandRegistry().emplace_back(order, std::move(factory));
    return true;
}

namespace {
std::map<std::string, Inspector>& inspectorRegistry() {
    static std::map<std::string, Inspector> registry;
    return registry;
}
}  // namespace

bool registerInspector(const std::string& extension, Inspector inspector) {
    inspectorRegistry()[extension] = std::move(inspector);
    return true;
}

const Inspector* findInspector(const std::string& extension) {
    const auto& registry = inspectorRegistry();
    const auto found = registry.find(extension);
    return found == registry.end() ? nullptr : &found->second;
}

namespace {

// CLI11's size conversion refuses "16EiB" as an overflow but saturates a plain number past
// 2⁶⁴ − 1 and wraps a negative one: `--max-memory 18446744073709551616` and `--max-memory -1`
// were taken for 16 EiB, no limit (found by fuzz_cli.py). The number in front of the unit must
// fit in 64 bits, unsigned.
CLI::Validator sizeNumberFits() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            const char* begin = text.data() + std::min(text.find_first_not_of(" \t"), text.size());
            if (begin < text.data() + text.size() && *begin == '-') return "a size cannot be negative";
            const char* end = begin;
            while (end < text.data() + text.size() && *end >= '0' && *end <= '9') ++end;
            std::uint64_t value = 0;
            if (std::from_chars(begin, end, value).ec == std::errc::result_out_of_range)
                return "the number " + std::string(begin, end) + " is more than 2^64 - 1";
            return {};
        },
        "");
}

}  // namespace

CLI::Option* addMaxMemoryOption(CLI::App& app, std::uint64_t& limit, const std::string& work) {
    limit = defaultMemoryLimit();
    return app
        .add_option("--max-memory", limit,
                    "Refuse before starting if " + work +
                        " is estimated to exceed this (e.g. 4GiB, 512MB; default half of this machine's memory, " +
                        formatBytes(limit) + " here; 0: no limit)")
        ->transform(CLI::AsSizeValue(false))
        ->transform(sizeNumberFits());  // a transform goes first: it sees the text as given
}

CLI::Validator wholeNumber(std::uint64_t least, std::uint64_t most) {
    return CLI::Validator(
        [least, most](std::string& text) -> std::string {
            std::uint64_t value = 0;
            const char* last = text.data() + text.size();
            const auto [end, error] = std::from_chars(text.data(), last, value);
            if (text.empty() || text[0] == '-' || error != std::errc() || end != last || value < least || value > most)
                return "must be a whole number from " + std::to_string(least) + " to " + std::to_string(most);
            return {};
        },
        "");
}

CLI::Validator seedNumber() {
    return wholeNumber(0, std::uint64_t(std::numeric_limits<std::int64_t>::max())).description("SEED");
}

CLI::Option* addThreadsOption(CLI::App& app, int& threads) {
    return app.add_option("--threads", threads, "Worker threads (0: all cores)")->check(CLI::Range(0, 1024))->capture_default_str();
}

struct ThreadControl {
    tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads) {
    if (threads > 0)
        mControl = std::make_unique<ThreadControl>(
            ThreadControl{tbb::global_control(tbb::global_control::max_allowed_parallelism, std::size_t(threads))});
}

ThreadLimit::~ThreadLimit() = default;

void checkImageExtension(const std::string& flag, const std::string& file, const std::vector<std::string>& formats) {
    const std::string extension = std::filesystem::path(file).extension().string();
    if (file.empty() || extension.empty()) return;  // a name without one takes the first format
    if (std::find(formats.begin(), formats.end(), render::imageFormat(file)) != formats.end()) return;
    std::string expected;
    for (const std::string& f : formats) expected += (expected.empty() ? "." : " or .") + f;
    throw CLI::ValidationError(flag, file + ": unknown image format '" + extension + "' (expected " + expected + ")");
}

CLI::Validator finiteNumber() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            std::size_t used = 0;
            double value = 0;
            try {
                value = std::stod(text, &used);
            } catch (const std::out_of_range&) {
                return "must be a finite number";
            } catch (const std::exception&) {
                return "must be a number";
            }
            if (used != text.size() || !std::isfinite(value)) return "must be a finite number";
            return {};
        },
        "NUMBER");
}

void checkOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                  const std::vector<std::filesystem::path>& inputs) {
    std::vector<std::pair<std::string, std::filesystem::path>> seen;
    for (const auto& [flag, path] : outputs) {
        if (path.empty()) continue;
        const std::filesystem::path normal = std::filesystem::absolute(path).lexically_normal();
        for (const auto& [other, earlier] : seen)
            if (earlier == normal) throw CLI::ValidationError(other + " and " + flag, "name the same file " + path);
        seen.emplace_back(flag, normal);
        checkOutputPath(path, inputs);
    }
}

CLI::Validator powerOfTwo(unsigned long long largest) {
    return CLI::Validator(
        [largest](std::string& text) -> std::string {
            unsigned long long n = 0;
            try {
                n = std::stoull(text);
            } catch (const std::exception&) {
            }
            if (n == 0 || (n & (n - 1)) != 0 || n > largest)
                return "must be a power of two from 1 to " + std::to_string(largest);
            return {};
        },
        "POWER OF TWO");
}

void status(const GlobalOptions& options, const std::string& line) {
    if (options.verbosity() != Verbosity::Quiet) std::cerr << line << '\n';
}

void warning(const GlobalOptions& options, const std::string& line) {
    if (options.verbosity() != Verbosity::Quiet) std::cerr << "vtex: warning: " << oneLine(line) << '\n';
}

TerminalProgress::TerminalProgress(const GlobalOptions& options)
    : mEnabled(options.verbosity() != Verbosity::Quiet && ::isatty(STDERR_FILENO) == 1) {}

TerminalProgress::~TerminalProgress() {
    if (mDrawn) std::fputc('\n', stderr);
}

void TerminalProgress::start(std::string_view phase, std::uint64_t total) {
    std::lock_guard lock(mMutex);
    if (mDrawn) std::fputc('\n', stderr);
    mDrawn = false;
    mPhase = phase;
    mTotal = total;
    mDone = 0;
    mStart = mLastDraw = std::chrono::steady_clock::now();
}

void TerminalProgress::advance(std::uint64_t units) {
    std::lock_guard lock(mMutex);
    mDone += units;
    // A bar only for work that takes more than a second, redrawn at most 10 times a second.
    const auto now = std::chrono::steady_clock::now();
    if (now - mStart < std::chrono::seconds(1) || now - mLastDraw < std::chrono::milliseconds(100))
        return;
    mLastDraw = now;
    draw(false);
}

void TerminalProgress::finish() {
    std::lock_guard lock(mMutex);
    if (mDrawn) {
        mDone = mTotal;
        draw(true);
        std::fputc('\n', stderr);
        mDrawn = false;
    }
}

void TerminalProgress::draw(bool final) {
    if (!mEnabled) return;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
    const double fraction = mTotal > 0 ? std::min(1.0, double(mDone) / double(mTotal)) : 0.0;
    const double remaining = fraction > 0 ? elapsed * (1 - fraction) / fraction : 0.0;
    constexpr int kWidth = 30;
    const int filled = int(fraction * kWidth);
    std::fprintf(stderr, "\r%-12.12s [%s%s] %5.1f%%  %6.1fs elapsed", mPhase.c_str(),
                 std::string(filled, '=').c_str(), std::string(kWidth - filled, ' ').c_str(),
                 100 * fraction, elapsed);
    if (!final) std::fprintf(stderr, "  %6.1fs left", remaining);
    std::fflush(stderr);
    mDrawn = true;
}

// `--region x0,y0,z0,x1,y1,z1`: finest voxel indices, the minimum corner inclusive and the
// maximum exclusive (octree::VoxelBox), each from 0 to N. Bad usage naming the flag otherwise.
octree::VoxelBox parseRegion(const std::string& flag, const std::string& text, std::uint32_t n) {
    const auto refuse = [&](const std::string& why) { return CLI::ValidationError(flag, text + ": " + why); };
    std::vector<std::uint32_t> values;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) {
        if (item.empty() || item.size() > 7 || item.find_first_not_of("0123456789") != std::string::npos)
            throw refuse("expected six whole numbers x0,y0,z0,x1,y1,z1");
        values.push_back(std::uint32_t(std::stoul(item)));
    }
    if (values.size() != 6 || text.back() == ',') throw refuse("expected six whole numbers x0,y0,z0,x1,y1,z1");
    octree::VoxelBox box{{values[0], values[1], values[2]}, {values[3], values[4], values[5]}};
    for (int a = 0; a < 3; ++a) {
        if (box.max[std::size_t(a)] > n)
            throw refuse("beyond the volume's " + std::to_string(n) + " voxels a side (the maximum is exclusive)");
        if (box.min[std::size_t(a)] >= box.max[std::size_t(a)])
            throw refuse("empty (each minimum must be below its maximum, which is exclusive)");
    }
    return box;
}


}  // namespace vtex::cli
