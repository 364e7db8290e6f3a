/// @file
/// @brief `vtex run`: staged batch runs of a pipeline file, with a content-hash cache.
///
/// A pipeline file (TOML) names source meshes (procedural patterns or files), the texels to
/// sample and build from them, the scenes to render with those texels, and the comparisons of
/// renders. Each stage's outputs are keyed by a hash of its parameters, the content of its input
/// files and artifacts, and the vtex version; an up-to-date stage is not run again. Outputs are
/// written atomically and recorded in a manifest written after them, so a run killed at any
/// moment never leaves an artifact that a later run would trust half-written, and a cached
/// artifact whose content no longer matches its manifest (corrupted, edited) is rebuilt.
///
/// Layout of the output directory: sources/<name>.glb, texels/<name>.vtl and .vto,
/// tiles/<render>.<k>.exr/.stats.json (renders split into tiles), renders/<name>.exr/.png/.stats.json,
/// compares/<name>.json and .diff.png, each with a <name>.manifest.json; report.json and
/// report.html at the top.
#pragma once

#include <vtex/core/enum_names.h>
#include <vtex/core/progress.h>
#include <vtex/octree/filtering.h>
#include <vtex/pipelines/run_observer.h>
#include <vtex/render/reference.h>
#include <vtex/render/renderer.h>
#include <vtex/sampler/sampler.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vtex::pipelines {

struct SourceStep {
    std::string name;
    std::string pattern;            ///< a `vtex pattern` name, or empty when `file` is given
    std::filesystem::path file;     ///< a mesh file for ingest (resolved against the pipeline file)
    char up = 0;                    ///< a file's up axis, 'x' | 'y' | 'z' (ingest::IngestOptions::up); 0: the format's
    bool fitCell = false;           ///< fit = "cell": scaled and centred into the unit cell (IngestOptions::fitCell)
    std::uint64_t seed = 1;         ///< pattern parameters (see sampler::PatternOptions)
    int count = 0;
    double fluctuation = -1;
    double leanDegrees = 0;
    std::string variant;
};

struct TexelStep {
    std::string name;
    std::string source;                 ///< a SourceStep name
    /// Finest voxels per side (power of two): the maximum; with Pipeline::fitResolution the
    /// texel is sampled only as finely as some render can use.
    std::uint32_t resolution = 64;
    std::optional<bool> cyclic;         ///< default: whether the source pattern is cyclic
    sampler::SolidMode solid = sampler::SolidMode::Auto;   ///< `solid`: auto | on | off
    octree::FilterRule filter = octree::FilterRule::Sggx;  ///< `filter`: neyret | sggx
    double tolerance = 0;
};

/// Which program a render stage is.
enum class Renderer {
    Texel,     ///< `vtex render`: the texels' volumes
    Reference  ///< `vtex reference`: the texels' source meshes instead (lod_bias and shading do not apply)
};
inline constexpr EnumNames<Renderer, 2> kRendererNames{{{{Renderer::Texel, "texel"}, {Renderer::Reference, "reference"}}}};

/// A texel render's approximations: the default budget, or every one off
/// (render::ApproximationBudget::exact()).
enum class Approximations { Default, Exact };
inline constexpr EnumNames<Approximations, 2> kApproximationsNames{
    {{{Approximations::Default, "default"}, {Approximations::Exact, "exact"}}}};

struct RenderStep {
    std::string name;
    std::filesystem::path scene;        ///< a scene file (resolved against the pipeline file)
    /// Scene texel name → pipeline texel name: those texels use the built octrees and sources.
    std::map<std::string, std::string> texels;
    int width = 0, height = 0;          ///< 0: the scene's camera
    int spp = 1;
    double lodBias = 0;
    render::ShadingMode shading = render::ShadingMode::Fast;
    /// The texel renderer's mesh/volume hybrid (render::RenderOptions::hybrid) for texels with
    /// a source: the pipeline binds each built texel's source mesh.
    bool hybrid = true;
    /// Each level's densities fitted to the source across the shell (render::RenderOptions::fitLevels).
    bool levelFit = true;
    Approximations approximations = Approximations::Default;
    Renderer renderer = Renderer::Texel;
    render::ReferenceMode mode = render::ReferenceMode::Embedded;  ///< reference renders: embedded | deformed
    /// Above 1: the render is split into this many tile stages of image rows (kind "tile", named
    /// "<render>.<k>", tile k the rows [k·H/N, (k+1)·H/N) of the H rows), each rendering its rows
    /// alone (render::ImageOptions::rowBegin) into tiles/<render>.<k>.exr and .stats.json, and the
    /// render's own stage assembles them into the image, bit for bit the unsplit render's, and
    /// merges their statistics (docs/pipelines.md, "Tiles"). 1 to kMaxTiles, and at most H.
    int tiles = 1;
    static constexpr int kMaxTiles = 256;
};

/// `b` is the truth `a` is measured against: the report's error-against-run-time table groups
/// the comparisons by `b`.
struct CompareStep {
    std::string name;
    std::string a, b;                   ///< RenderStep names
};

/// [slurm] of a pipeline file: what `vtex run --executor slurm` asks of the cluster (slurm.h);
/// the flags of the same names override it. Empty strings leave a setting to the cluster.
struct SlurmSettings {
    std::string partition;              ///< sbatch --partition
    std::string time;                   ///< --time, each job's wall-time limit ("1:00:00")
    /// --mem of every job. Empty: renders and tiles take their node's whole memory (--mem=0, with
    /// --exclusive), the other stages the cluster's default per CPU.
    std::string mem;
    int cpus = 2;                       ///< CPUs (-c) of a sample or build job; sources, compares and assembles take 1
    std::vector<std::string> sbatchArguments;  ///< more sbatch arguments, one word each, after vtex's own
    friend bool operator==(const SlurmSettings&, const SlurmSettings&) = default;
};

struct Pipeline {
    std::filesystem::path file;
    std::filesystem::path output;       ///< [pipeline] output, resolved; default "<file stem>-out"
    std::vector<SourceStep> sources;
    std::vector<TexelStep> texels;
    std::vector<RenderStep> renders;
    std::vector<CompareStep> compares;
    /// [pipeline] fit_resolution (default true): when the pipeline renders anything, sample each
    /// texel only to the finest level its renders can use (render::finestUsefulLevels) and leave
    /// out the texels no render uses.
    bool fitResolution = true;
    SlurmSettings slurm;                ///< [slurm]
    std::vector<std::string> warnings;  ///< unknown keys, as messages naming the file
    std::vector<std::string> unknownKeys;  ///< the same keys' paths ("render[2].spp_typo"), for `--strict`
};

/// Reads and validates a pipeline file completely (names unique, references resolved, enums and
/// ranges checked, input files present) before anything runs. Throws vtex::InputError naming the
/// file and the key.
Pipeline loadPipeline(const std::filesystem::path& file);

/// The index of the texel named `name` in `scene`. Throws vtex::InputError naming the scene.
std::size_t sceneTexelIndex(const render::Scene& scene, const std::string& name);

struct RunOptions {
    std::filesystem::path output;       ///< overrides Pipeline::output when not empty
    bool force = false;                 ///< redo every stage
    int jobs = 0;                       ///< stages run at once; 0 = as many as cores
    /// The memory the stages running side by side may plan for together (core's MemoryBudget):
    /// a stage waits while the others hold too much of it, and fails (as bad input) when its
    /// estimate alone exceeds it. 0: no limit.
    std::uint64_t maxMemoryBytes = 0;
    /// Another run holds the output folder (core's FolderLock): wait for it instead of failing.
    bool waitForLock = false;
    /// Run only this stage ("kind/name", as stageId names it: "render/fur"), its inputs taken
    /// from the cache, with the outputs and manifest it makes inside a whole run; what one job
    /// of a cluster runs. An unknown id throws UnknownStage; an input not in the cache,
    /// vtex::InputError naming it. No report is written (the whole run's stays).
    std::string stage;
    /// One line per stage event ("run     render a (changed parameter: spp 1 → 4)", "ran     render
    /// a in 1.52 s, peak 210 MiB", "cached  …", "failed  …"); may be empty. Called one line at a time.
    std::function<void(const std::string&)> log;
    /// The plan, each stage's start, progress and end (run_observer.h); may be null.
    RunObserver* observer = nullptr;
};

struct StageRecord {
    std::string kind;                   ///< source | sample | build | tile | render | compare
    std::string name;
    std::string key;                    ///< the content hash that keys the outputs (hex)
    enum class Status { Ran, Cached, Failed, Skipped } status = Status::Skipped;
    std::string message;                ///< why it failed or was skipped
    bool badInput = false;              ///< it failed on bad input data (vtex::InputError): exit 3
    double seconds = 0;                 ///< work time (0 when cached)
    /// The process's peak resident memory while the stage ran (0 when cached). Stages of a wave
    /// run side by side, so this is the stage's own peak plus what ran beside it.
    std::uint64_t peakMemoryBytes = 0;
    std::vector<std::filesystem::path> outputs;
    std::string detailsJson;            ///< stage figures (sizes, compression, render stats…)
};

/// What the run left out of a texel, and why.
struct Omission {
    std::string texel;
    std::string reason;  ///< e.g. "sampled at 32³ instead of 128³: the finest level …"
};

/// A stage's id, "kind/name" (RunOptions::stage).
inline std::string stageId(const std::string& kind, const std::string& name) { return kind + "/" + name; }

/// RunOptions::stage names no stage of the pipeline; what() lists those it has.
struct UnknownStage : std::invalid_argument {
    using std::invalid_argument::invalid_argument;
};

/// "ran", "cached", "failed" or "skipped": the word the log and the reports use.
std::string statusName(StageRecord::Status status);

struct RunReport {
    std::filesystem::path output;
    std::vector<StageRecord> stages;
    std::vector<Omission> leftOut;
    double seconds = 0;
    std::filesystem::path reportJson, reportHtml;
    /// The error-against-run-time tables as report.json has them under `error_against_time`.
    std::string errorAgainstTimeJson;
    bool succeeded() const;
};

/// Runs the pipeline. Writes report.json and report.html whatever happens; a failed stage stops
/// the stages that depend on it and leaves the others' outputs valid. Returns the report; the
/// caller decides the exit status from RunReport::succeeded() (the first failure's message is in
/// its record). Throws vtex::InputError, before anything is made, when the output folder exists
/// and is not a directory (checkOutputFolder), vtex::IoError when it cannot be written.
RunReport runPipeline(const Pipeline& pipeline, const RunOptions& options);

/// What runPipeline would do, writing nothing (`vtex run --dry-run`): every stage in run order,
/// whether it would run and why. A stage whose input would run is planned to run too (its input's
/// new content is not known yet). Throws as runPipeline does before it starts.
std::vector<PlannedStage> planPipeline(const Pipeline& pipeline, const RunOptions& options);

}  // namespace vtex::pipelines
