// The stages a pipeline file asks for, as a graph in waves (sources, samples, builds, tiles, renders,
// compares): each stage's parameters and inputs (`describe`, hashed into its cache key), its
// outputs, and the work that makes them. runner.cpp runs the graph, or only tells what it would
// run (a dry run).
#pragma once

#include <vtex/core/memory_budget.h>
#include <vtex/pipelines/pipeline.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace vtex::pipelines::detail {

/// What one stage needs to run and what it made.
struct Stage {
    Stage(std::string stageKind, std::string stageName) : kind(std::move(stageKind)), name(std::move(stageName)) {}

    std::string kind, name;
    std::vector<std::size_t> inputs;                   ///< indices of the stages it reads
    std::function<std::string()> describe;             ///< canonical text of parameters and inputs
    std::function<nlohmann::json(Stage&)> run;         ///< writes the outputs, returns details
    std::map<std::string, std::filesystem::path> outputs;  ///< role → path
    // Filled while running:
    StageRecord record;
    std::map<std::string, std::string> outputHashes;   ///< role → content hash
    /// This stage's work time in the earlier run its manifest records (the ETA's estimate); < 0: none.
    double earlierSeconds = -1;
    /// Its own progress while it runs (the CLI's bar); set by the runner before run().
    Progress* progress = nullptr;
};

/// <root>/<kind>s/<name>.manifest.json
std::filesystem::path manifestPath(const Stage& stage, const std::filesystem::path& root);

/// Builds the graph into `stages` (empty; it and `budget` must outlive the stages' closures, which
/// address each other by index in the vector, so it must not grow after), and the texels it leaves out
/// (not used by any render, or sampled less finely than their resolution) into `leftOut`.
/// Throws vtex::InputError when two stages would write one file, or a scene cannot be read.
void buildStageGraph(const Pipeline& pipeline, const std::filesystem::path& root, bool force, MemoryBudget& budget,
                     std::vector<Stage>& stages, std::vector<Omission>& leftOut);

/// The plan of a graph nothing has run in yet (planPipeline, and what a Slurm submission
/// submits): wave by wave, a stage whose inputs are all up to date is judged by its manifest, one
/// with an input that runs first runs too. Leaves the stages as it found them.
std::vector<PlannedStage> planStages(std::vector<Stage>& stages, const std::filesystem::path& root, bool force);

}  // namespace vtex::pipelines::detail
