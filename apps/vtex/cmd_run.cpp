// `vtex run pipeline.toml [-o DIR] [--force] [--jobs N] [--dry-run] [--strict] [--stage ID]`: a
// staged batch run with caching, its progress drawn on a terminal (run_progress.h); or one stage
// of it alone, its inputs from the cache (what a cluster job runs); or its stages submitted to
// Slurm (`--executor slurm`, run_slurm.h), and `--status DIR` of such a submission.
#include "cli.h"
#include "run_progress.h"
#include "run_slurm.h"

#include <vtex/core/error.h>
#include <vtex/pipelines/pipeline.h>

#include <iostream>

namespace vtex::cli {
namespace {

// `--dry-run`'s answer, on stdout: one line per stage, then the count.
void printPlan(const std::vector<pipelines::PlannedStage>& plan) {
    std::size_t runs = 0;
    for (const pipelines::PlannedStage& p : plan) {
        runs += p.runs;
        std::cout << (p.runs ? "would run " : "cached    ") << p.kind << " " << p.name << (p.runs ? ": " + p.reason : "")
                  << "\n";
    }
    std::cout << runs << " of " << plan.size() << " stages would run; nothing was run or written (--dry-run)\n";
}

struct RunFlags {
    std::string file, output;
    bool force = false;
    int jobs = 0;
    std::uint64_t maxMemory = 0;
    int threads = 0;
    bool wait = false;
    bool dryRun = false;
    bool strict = false;
    std::string stage;
    SlurmFlags slurm;
};

// `vtex run`: --status, --dry-run, a Slurm submission, or the pipeline run here with its progress
// display; a failed stage's message is the command's (exit 3 for bad input, else 1).
void runPipelineFile(const RunFlags& o, const GlobalOptions& global) {
    if (!o.slurm.status.empty()) {
        if (!o.file.empty()) throw CLI::ValidationError("--status", "takes an output folder, not a pipeline file too");
        return printSubmissionStatus(o.slurm.status);
    }
    if (o.file.empty()) throw CLI::RequiredError("PIPELINE");
    if (o.slurm.executor == "slurm" && (o.dryRun || !o.stage.empty()))
        throw CLI::ValidationError("--executor", "slurm submits a whole pipeline: not with --dry-run or --stage");
    const ThreadLimit threadLimit(o.threads);
    const pipelines::Pipeline pipeline = pipelines::loadPipeline(o.file);
    if (o.strict && !pipeline.unknownKeys.empty())
        throw CLI::ValidationError("--strict", o.file + ": unknown key '" + pipeline.unknownKeys.front() + "'" +
                                                   (pipeline.unknownKeys.size() > 1
                                                        ? " (and " + std::to_string(pipeline.unknownKeys.size() - 1) + " more)"
                                                        : std::string()));
    for (const auto& w : pipeline.warnings) warning(global, w);
    pipelines::RunOptions options;
    options.output = o.output;
    options.force = o.force;
    options.jobs = o.jobs;
    options.maxMemoryBytes = o.maxMemory;
    options.waitForLock = o.wait;
    options.stage = o.stage;
    if (o.dryRun) return printPlan(pipelines::planPipeline(pipeline, options));
    if (o.slurm.executor == "slurm") return submitToSlurm(pipeline, options, o.slurm, global);
    pipelines::RunReport report;
    {
        RunProgressDisplay display(global, o.jobs);  // gone before the closing lines are printed
        options.log = display.logger();
        // The display draws a whole run's plan; a stage alone logs its lines only.
        if (display.enabled() && o.stage.empty()) options.observer = &display;
        try {
            report = pipelines::runPipeline(pipeline, options);
        } catch (const pipelines::UnknownStage& e) {
            throw CLI::ValidationError("--stage", e.what());
        }
    }
    for (const auto& omission : report.leftOut) status(global, "left out: texel " + omission.texel + ": " + omission.reason);
    if (!report.reportHtml.empty()) status(global, "report: " + report.reportHtml.string());
    if (!report.succeeded()) {
        // Exit 3 when a stage failed on bad input (a mesh, a scene, an estimate over the memory
        // limit), 1 otherwise; the message is the first failure's.
        for (const auto& stage : report.stages)
            if (stage.status == pipelines::StageRecord::Status::Failed) {
                const std::string what = stage.kind + " '" + stage.name + "' failed: " + stage.message;
                if (stage.badInput) throw InputError(o.file, what);
                throw std::runtime_error(what);
            }
        throw std::runtime_error("some stages did not run");
    }
}

const bool registered = registerCommand(80, [](CLI::App& app) -> Action {
    app.name("run");
    app.description("Run a pipeline file: sources → texels → renders → comparisons, each stage cached by a "
                    "content hash of its inputs and parameters; writes report.json and report.html");
    auto o = std::make_shared<RunFlags>();
    app.add_option("PIPELINE", o->file, "The pipeline file (.toml); not with --status");
    app.add_option("-o,--output", o->output, "Output directory (default: the file's [pipeline] output, or <name>-out)");
    app.add_flag("--force", o->force, "Redo every stage, cached or not");
    app.add_option("--jobs", o->jobs, "Stages run at once (0: as many as cores)")->check(CLI::Range(0, 1024));
    addMaxMemoryOption(app, o->maxMemory, "a stage, together with those running beside it,");
    addThreadsOption(app, o->threads);
    app.add_flag("--wait", o->wait, "When another run holds the output folder, wait until it ends (default: refuse)");
    app.add_flag("--dry-run", o->dryRun,
                 "List the stages that would run and why (changed input, changed parameter, missing output); run "
                 "nothing, leave every file as it is");
    app.add_flag("--strict", o->strict, "Refuse a pipeline file with an unknown key (exit 2) instead of warning");
    app.add_option("--stage", o->stage,
                   "Run only this stage, KIND/NAME as the log names it (render/fur), its inputs taken from the cache "
                   "(exit 3 when one is not there), with the result it has in a whole run; no report is written")
        ->excludes("--dry-run");
    addSlurmOptions(app, o->slurm);
    return [o](const GlobalOptions& global) { runPipelineFile(*o, global); };
});

}  // namespace
}  // namespace vtex::cli
