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
#include <memory>
#include <string>
#include <vector>

namespace vtex::pipelines::detail {

struct Stage;

/// One kind of stage's work, one type per kind (texel_stages.h: source, sample, build;
/// render_stages.h: tile, render, assembly, compare), holding that kind's typed parameters as
/// the pipeline file gave them. Each kind's key text comes from one function of its step that
/// names every field of it (a structured binding: a field added to the step does not compile
/// until that function places it in the key or says why not).
class StageWork {
public:
    virtual ~StageWork() = default;
    /// The canonical text of the stage's parameters and inputs' content, hashed into its key.
    virtual std::string describe(const std::vector<Stage>& stages, const Stage& self) const = 0;
    /// Makes the stage's outputs (each atomically, all or none) from its inputs' outputs and
    /// returns the details its manifest records.
    virtual nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const = 0;
};

/// One stage of the graph: what it reads and writes, its work, and what running it recorded.
struct Stage {
    Stage(std::string stageKind, std::string stageName) : kind(std::move(stageKind)), name(std::move(stageName)) {}

    std::string kind, name;
    std::vector<std::size_t> inputs;                   ///< indices of the stages it reads
    std::map<std::string, std::filesystem::path> outputs;  ///< role → path
    std::shared_ptr<const StageWork> work;
    // Filled while running:
    StageRecord record;
    std::map<std::string, std::string> outputHashes;   ///< role → content hash
    /// Its own progress while it runs (the CLI's bar); set by the runner before run().
    Progress* progress = nullptr;

    std::string describe(const std::vector<Stage>& stages) const { return work->describe(stages, *this); }
    nlohmann::json run(const std::vector<Stage>& stages) const { return work->run(stages, *this); }
};

/// <root>/<kind>s/<name>.manifest.json
std::filesystem::path manifestPath(const Stage& stage, const std::filesystem::path& root);

/// Builds the graph into `stages` (empty; `budget` must outlive the stages' work, and stages
/// address each other by index in the vector), and the texels it leaves out
/// (not used by any render, or sampled less finely than their resolution) into `leftOut`.
/// Throws vtex::InputError when two stages would write one file, or a scene cannot be read.
void buildStageGraph(const Pipeline& pipeline, const std::filesystem::path& root, bool force, MemoryBudget& budget,
                     std::vector<Stage>& stages, std::vector<Omission>& leftOut);

/// Creates `folder` and its parents. Throws vtex::IoError naming it.
void createFolder(const std::filesystem::path& folder);

/// With the output folder's lock held: creates the stages' folders and, when the lock is the
/// caller's alone (`removeTemporaries`: a whole run, a Slurm submission with no job of the last
/// one alive), removes the temporaries that writers killed mid-write left there. Throws
/// vtex::IoError when a folder cannot be created.
void prepareFolders(const std::filesystem::path& root, bool removeTemporaries);

/// The plan of a graph nothing has run in yet (planPipeline, and what a Slurm submission
/// submits): wave by wave, a stage whose inputs are all up to date is judged by its manifest, one
/// with an input that runs first runs too. Leaves the stages as it found them.
std::vector<PlannedStage> planStages(std::vector<Stage>& stages, const std::filesystem::path& root, bool force);

}  // namespace vtex::pipelines::detail
