// `vtex run`'s Slurm side: `--executor slurm` and its sbatch settings, `--status DIR`.
#pragma once

#include "cli.h"

#include <vtex/pipelines/pipeline.h>
#include <vtex/pipelines/slurm.h>

#include <string>
#include <vector>

namespace vtex::cli {

struct SlurmFlags {
    std::string executor = "local";
    std::string partition, time, mem;
    int cpus = 0;                          ///< 0: the pipeline file's
    std::vector<std::string> sbatchArguments;
    std::string status;                    ///< --status DIR
};

/// --executor, --partition, --time, --mem, --cpus, --sbatch-arg and --status.
void addSlurmOptions(CLI::App& app, SlurmFlags& flags);

/// Submits the pipeline's stale stages (pipelines::submitPipeline) with the pipeline file's
/// [slurm] settings overridden by the flags, and prints what it submitted.
void submitToSlurm(const pipelines::Pipeline& pipeline, const pipelines::RunOptions& options, const SlurmFlags& flags,
                   const GlobalOptions& global);

/// `vtex run --status DIR`: one line per stage on stdout, then the counts.
void printSubmissionStatus(const std::string& folder);

}  // namespace vtex::cli
