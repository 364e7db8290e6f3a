/// @file
/// @brief `vtex demo`: the built-in showcase, from procedural patterns to texels, needing no
/// input files.
///
/// Today it runs every stage that exists: each of the paper's patterns is generated, written as
/// the canonical .glb, read back through ingest (as any user file would be), sampled into the
/// finest level (.vtl), built into an octree with both filter rules (.vto), and rendered on a
/// hill of 144 bilinear faces (a scene file per texel, written beside the images so that
/// `vtex render` can redo them). The summary lists, per pattern, what was made and what it
/// cost, and is also written as demo.json.
#pragma once

#include <vtex/core/progress.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vtex::pipelines {

struct DemoOptions {
    std::filesystem::path outputDirectory = "demo-out";
    std::uint32_t resolution = 64;  ///< finest voxels per side (a power of two)
    std::uint64_t seed = 1;
    /// Patterns to run, by name; empty = all of them.
    std::vector<std::string> patterns;
};

struct DemoLevel {
    std::uint32_t level = 0;
    std::uint64_t storedNodes = 0;
    double meanDensity = 0;
    double filterErrorNeyret = 0;  ///< mean filter error of the level's nodes, neyret rule
    double filterErrorSggx = 0;    ///< same, sggx rule
};

struct DemoPattern {
    std::string name;
    std::uint64_t triangles = 0;
    double sourceArea = 0;            ///< reference units²
    std::uint64_t occupiedVoxels = 0; ///< stored blocks of the finest level
    double fitErrorMean = 0;
    double compressionNeyret = 0;     ///< 1 − stored / N³
    double compressionSggx = 0;
    std::vector<DemoLevel> levels;
    double secondsPattern = 0, secondsIngest = 0, secondsSample = 0, secondsBuild = 0, secondsRender = 0;
    double meanLevel = 0;     ///< of the hill render's level choices
    std::uint64_t rays = 0;   ///< primary and shadow rays of the hill render
    std::vector<std::filesystem::path> files;  ///< the artifacts written
};

struct DemoReport {
    DemoOptions options;
    std::vector<DemoPattern> patterns;
    double seconds = 0;
    int hillFaces = 0;                  ///< bilinear faces of the base surface
    std::filesystem::path summaryFile;  ///< demo.json
};

/// Runs the demo. Throws vtex::IoError when the output directory cannot be written,
/// std::invalid_argument for an unknown pattern or a bad resolution.
DemoReport runDemo(const DemoOptions& options, Progress& progress);

/// The human summary printed by `vtex demo`.
std::string formatDemoReport(const DemoReport& report);

}  // namespace vtex::pipelines
