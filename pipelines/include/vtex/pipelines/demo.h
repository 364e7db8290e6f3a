/// @file
/// @brief `vtex demo`: the paper's showcase rebuilt from the procedural patterns, as a built-in
/// pipeline that needs no input files.
///
/// The demo writes its inputs — base meshes generated here, one scene file per figure and a
/// pipeline.toml — into <output>/inputs and runs that pipeline with runPipeline(), so it is
/// cached, leaves out what its renders do not need and ends with the same report.json and
/// report.html as `vtex run`. A user can edit the inputs and re-run them with `vtex run`.
///
/// The figures (Neyret 1994): Fig. 7 grass on a hill of 1404 bilinear faces; Fig. 6 bushes
/// tiling a 50×500 region to the horizon; Fig. 10 fur on a torus of 240 faces; Fig. 9 a forest
/// on a hill of 578 faces; Fig. 11 building elements on 81 faces; Fig. 1 one texel of brushed
/// aluminium; Fig. 4 one texel at four successive octree levels, each measured against the
/// reference and shown as its difference from the finest (not an error: neither is the truth).
/// Every figure is paired with its explicit-geometry reference (`vtex reference`) and its
/// measured error, and an error-against-run-time study on the forest puts texel renders (LoD
/// bias −1/0/+1, 1 and 4 spp) and reference renders (1 to 64 spp) against a 256-spp reference.
#pragma once

#include <vtex/pipelines/pipeline.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace vtex::pipelines {

struct DemoOptions {
    std::filesystem::path outputDirectory = "demo-out";
    std::uint32_t maxResolution = 128;  ///< cap on each texel's finest voxels per side (a power of two)
    double imageScale = 0.5;            ///< image size relative to video resolution (768×576)
    std::uint64_t seed = 1;             ///< of the procedural patterns
    int referenceSpp = 16;              ///< samples per pixel of each figure's reference render
    int studyTruthSpp = 256;            ///< of the reference the error-against-time study measures against
    bool force = false;                 ///< redo every stage
    RunOptions run;                     ///< log, jobs (the output and force fields are set from the above)
};

/// Writes the demo's inputs and runs them. Throws vtex::InputError, before anything is written,
/// when the output folder exists and is not a directory (checkOutputFolder), vtex::IoError when
/// it cannot be written; returns the pipeline's report (check succeeded()).
RunReport runDemo(const DemoOptions& options);

/// The human summary printed by `vtex demo`.
std::string formatDemoReport(const RunReport& report);

}  // namespace vtex::pipelines
