// pipeline.toml → Pipeline, validated completely before anything runs.
#include <vtex/pipelines/pipeline.h>

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>
#include <vtex/core/toml_reader.h>
#include <vtex/render/scene.h>
#include <vtex/sampler/patterns.h>

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace vtex::pipelines {
namespace {

namespace fs = std::filesystem;

std::string indexed(std::string_view table, std::size_t i) {
    return std::string(table) + "[" + std::to_string(i) + "]";
}

// Step names become file names in the output directory.
void checkName(const TomlReader& reader, const std::string& key, const std::string& name,
               std::set<std::string>& seen) {
    if (name.empty() || name.size() > 100 || name.find_first_of("/\\\0", 0, 3) != std::string::npos ||
        name == "." || name == ".." || name.front() == '.')
        reader.fail(key, "'" + name + "' is not a usable name (no slashes, not empty, not starting with '.')");
    if (!seen.insert(name).second) reader.fail(key, "duplicate name '" + name + "'");
}

// Without an error_code, a name too long or a link loop threw filesystem_error, which the CLI
// reported as a failure (exit 1) instead of bad input (found by fuzz_pipeline).
void requireFile(const TomlReader& reader, const std::string& key, const fs::path& path) {
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (fs::is_regular_file(status)) return;
    if (fs::exists(status)) reader.fail(key, "not a regular file: " + path.string());
    reader.fail(key, "no such file: " + path.string() + (error && error != std::errc::no_such_file_or_directory
                                                            ? " (" + error.message() + ")" : ""));
}

// A pattern source made as the runner will make it, at 64 elements at most: a bad option (a
// lean past ±80°, which makePattern refuses) or a count whose mesh vtex could not read back
// (sampler::kMaxPatternTriangles; `brushed` with a count of 10⁶ is about 5·10⁸ triangles) is
// the file's error at once, not a failure or an exhausted memory half-way through a run.
void checkPattern(const TomlReader& reader, const std::string& path, const SourceStep& s) {
    sampler::PatternOptions o;
    o.seed = s.seed;
    o.count = s.count == 0 ? 1 : s.count;  // every pattern's default count is small: one element checks the rest
    o.fluctuation = s.fluctuation;
    o.leanDegrees = s.leanDegrees;
    o.variant = s.variant;
    std::uint64_t triangles = 0;
    try {
        triangles = sampler::estimatePatternTriangles(s.pattern, o);
    } catch (const std::invalid_argument& e) {
        reader.fail(path, e.what());
    }
    if (triangles > sampler::kMaxPatternTriangles)
        reader.fail(TomlReader::join(path, "count"),
                    std::to_string(s.count) + " makes about " + std::to_string(triangles) + " triangles, more than the " +
                        std::to_string(sampler::kMaxPatternTriangles) + " vtex ingests");
}

// [slurm]: passed to sbatch as they are, so only their shape is checked here (sbatch judges the
// values); an argument with a newline would break the job script's comment lines.
void readSlurmSettings(TomlReader& reader, const toml::table& t, SlurmSettings& s) {
    reader.checkKeys(t, "slurm", {"partition", "time", "mem", "cpus", "sbatch_args"});
    s.partition = reader.string(t, "slurm", "partition", std::string());
    s.time = reader.string(t, "slurm", "time", std::string());
    s.mem = reader.string(t, "slurm", "mem", std::string());
    s.cpus = int(reader.integer(t, "slurm", "cpus", 2, 1, 4096));
    if (t.contains("sbatch_args")) {
        const toml::array* args = t["sbatch_args"].as_array();
        if (!args) reader.fail("slurm.sbatch_args", "must be an array of strings");
        for (const toml::node& arg : *args) {
            const auto word = arg.as_string();
            if (!word || word->get().empty()) reader.fail("slurm.sbatch_args", "must be an array of non-empty strings");
            s.sbatchArguments.push_back(word->get());
        }
    }
    for (const std::string* value : {&s.partition, &s.time, &s.mem})
        if (value->find_first_of("\n\r") != std::string::npos) reader.fail("slurm", "a value holds a line break");
    for (const std::string& value : s.sbatchArguments)
        if (value.find_first_of("\n\r") != std::string::npos) reader.fail("slurm.sbatch_args", "an argument holds a line break");
}

// One [[source]] table (`path` names it in messages): a pattern or a file, the options the
// source reads and no other.
SourceStep readSource(TomlReader& reader, const toml::table& t, const std::string& path, std::set<std::string>& sourceNames) {
    const auto& patterns = sampler::patternNames();
    reader.checkKeys(t, path, {"name", "pattern", "file", "up", "fit", "seed", "count", "fluctuation", "lean", "variant"});
    SourceStep s;
    s.name = reader.string(t, path, "name", {});
    checkName(reader, TomlReader::join(path, "name"), s.name, sourceNames);
    const bool hasPattern = t.contains("pattern"), hasFile = t.contains("file");
    if (hasPattern == hasFile) reader.fail(path, "give exactly one of 'pattern' and 'file'");
    if (hasPattern) {
        s.pattern = reader.string(t, path, "pattern", {});
        if (std::find(patterns.begin(), patterns.end(), s.pattern) == patterns.end())
            reader.fail(TomlReader::join(path, "pattern"), "unknown pattern '" + s.pattern + "'");
    } else {
        s.file = reader.resolve(TomlReader::join(path, "file"), reader.string(t, path, "file", {}));
        requireFile(reader, TomlReader::join(path, "file"), s.file);
        // As `vtex ingest --up x|y|z --fit keep|cell`.
        const std::string up = reader.string(t, path, "up", std::string());
        if (!up.empty() && up != "x" && up != "y" && up != "z")
            reader.fail(TomlReader::join(path, "up"), "must be \"x\", \"y\" or \"z\"");
        s.up = up.empty() ? 0 : up[0];
        const std::string fit = reader.string(t, path, "fit", "keep");
        if (fit != "keep" && fit != "cell") reader.fail(TomlReader::join(path, "fit"), "must be \"keep\" or \"cell\"");
        s.fitCell = fit == "cell";
    }
    for (const char* key : {"up", "fit"})
        if (hasPattern && t.contains(key))
            reader.fail(TomlReader::join(path, key), "a pattern source is already in the unit cell, +Z up");
    s.seed = std::uint64_t(reader.integer(t, path, "seed", 1, 0, std::numeric_limits<long long>::max()));
    s.count = int(reader.integer(t, path, "count", 0, 0, 1'000'000));
    s.fluctuation = reader.number(t, path, "fluctuation", -1.0, -1.0, 3.2);
    s.leanDegrees = reader.number(t, path, "lean", 0.0, -89.0, 89.0);
    s.variant = reader.string(t, path, "variant", std::string());
    // A key the source does not read is refused, not silently ignored: a file source reads
    // none of the pattern keys, a pattern only its own (sampler::patternUses).
    for (const char* key : {"seed", "count", "fluctuation", "lean", "variant"})
        if (t.contains(key) && !(hasPattern && sampler::patternUses(s.pattern, key)))
            reader.fail(TomlReader::join(path, key),
                        hasPattern ? "the " + s.pattern + " pattern does not use it (" + sampler::patternsUsing(key) + " do)"
                                   : std::string("a file source has no pattern options"));
    if (hasPattern) checkPattern(reader, path, s);
    return s;
}

// One [[texel]] table: it names a [[source]] read before it.
TexelStep readTexel(TomlReader& reader, const toml::table& t, const std::string& path, std::set<std::string>& texelNames,
                    const std::set<std::string>& sourceNames) {
    reader.checkKeys(t, path, {"name", "source", "resolution", "cyclic", "solid", "filter", "tolerance"});
    TexelStep s;
    s.name = reader.string(t, path, "name", {});
    checkName(reader, TomlReader::join(path, "name"), s.name, texelNames);
    s.source = reader.string(t, path, "source", {});
    if (!sourceNames.count(s.source))
        reader.fail(TomlReader::join(path, "source"), "no [[source]] named '" + s.source + "'");
    s.resolution = std::uint32_t(reader.integer(t, path, "resolution", 64, 1, 4096));
    if ((s.resolution & (s.resolution - 1)) != 0)
        reader.fail(TomlReader::join(path, "resolution"), "must be a power of two");
    if (t.contains("cyclic")) s.cyclic = reader.boolean(t, path, "cyclic", {});
    s.solid = reader.enumeration(t, path, "solid", s.solid, sampler::kSolidModeNames);
    s.filter = reader.enumeration(t, path, "filter", s.filter, octree::kFilterRuleNames);
    s.tolerance = reader.number(t, path, "tolerance", 0.0, 0.0, 1e6);
    return s;
}

// One [[render]] table: its scene is loaded, so that it is valid and defines every texel the
// step binds, before anything runs.
RenderStep readRender(TomlReader& reader, const toml::table& t, const std::string& path, std::set<std::string>& renderNames,
                      const std::set<std::string>& texelNames) {
    reader.checkKeys(t, path, {"name", "scene", "texels", "width", "height", "spp", "lod_bias", "shading", "hybrid", "level_fit", "approximations", "renderer", "mode", "tiles"});
    RenderStep s;
    s.name = reader.string(t, path, "name", {});
    checkName(reader, TomlReader::join(path, "name"), s.name, renderNames);
    s.scene = reader.resolve(TomlReader::join(path, "scene"), reader.string(t, path, "scene", {}));
    requireFile(reader, TomlReader::join(path, "scene"), s.scene);
    if (const toml::table* bindings = reader.subtable(t, path, "texels", false)) {
        for (const auto& [sceneName, node] : *bindings) {
            const std::string key = TomlReader::join(TomlReader::join(path, "texels"), sceneName.str());
            const auto value = node.as_string();
            if (!value) reader.fail(key, "must be the name of a [[texel]]");
            if (!texelNames.count(value->get())) reader.fail(key, "no [[texel]] named '" + value->get() + "'");
            s.texels[std::string(sceneName.str())] = value->get();
        }
    }
    // The scene itself must be valid and define every bound texel, before anything runs.
    const render::Scene scene = render::loadScene(s.scene);
    for (const auto& [sceneTexel, texel] : s.texels) {
        try {
            sceneTexelIndex(scene, sceneTexel);
        } catch (const InputError& e) {
            reader.fail(TomlReader::join(TomlReader::join(path, "texels"), sceneTexel), e.problem());
        }
    }
    s.width = int(reader.integer(t, path, "width", 0, 0, 16384));
    s.height = int(reader.integer(t, path, "height", 0, 0, 16384));
    s.spp = int(reader.integer(t, path, "spp", 1, 1, 65536));
    s.lodBias = reader.number(t, path, "lod_bias", 0.0, -16.0, 16.0);
    s.shading = reader.enumeration(t, path, "shading", s.shading, render::kShadingModeNames);
    s.hybrid = reader.boolean(t, path, "hybrid", true);
    s.levelFit = reader.boolean(t, path, "level_fit", true);
    s.approximations = reader.enumeration(t, path, "approximations", s.approximations, kApproximationsNames);
    s.renderer = reader.enumeration(t, path, "renderer", s.renderer, kRendererNames);
    s.mode = reader.enumeration(t, path, "mode", s.mode, render::kReferenceModeNames);
    // Tiles of rows: no more than the image has rows (the scene's camera unless `height`).
    s.tiles = int(reader.integer(t, path, "tiles", 1, 1, RenderStep::kMaxTiles));
    if (const int rows = s.height > 0 ? s.height : scene.camera.height; s.tiles > rows)
        reader.fail(TomlReader::join(path, "tiles"),
                    std::to_string(s.tiles) + " tiles of rows, more than the image's " + std::to_string(rows) + " rows");
    if (s.renderer == Renderer::Reference) {
        // The reference draws each texel's source mesh: a bound texel brings the pipeline's
        // source, an unbound one needs `source =` in the scene.
        for (const std::size_t used : render::usedTexels(scene)) {
            const render::TexelDef& texel = scene.texels.at(used);
            if (!s.texels.count(texel.name) && texel.source.empty())
                reader.fail(TomlReader::join(path, "renderer"),
                            "texel '" + texel.name + "' of " + s.scene.filename().string() +
                                " is neither bound to a [[texel]] nor given a source mesh in the scene");
        }
    }
    return s;
}

// One [[compare]] table: two [[render]] steps read before it.
CompareStep readCompare(TomlReader& reader, const toml::table& t, const std::string& path, std::set<std::string>& compareNames,
                        const std::set<std::string>& renderNames) {
    reader.checkKeys(t, path, {"name", "a", "b"});
    CompareStep s;
    s.name = reader.string(t, path, "name", {});
    checkName(reader, TomlReader::join(path, "name"), s.name, compareNames);
    for (auto [key, target] : {std::pair{"a", &s.a}, std::pair{"b", &s.b}}) {
        *target = reader.string(t, path, key, {});
        if (!renderNames.count(*target))
            reader.fail(TomlReader::join(path, key), "no [[render]] named '" + *target + "'");
    }
    return s;
}

}  // namespace

std::size_t sceneTexelIndex(const render::Scene& scene, const std::string& name) {
    for (std::size_t i = 0; i < scene.texels.size(); ++i)
        if (scene.texels[i].name == name) return i;
    throw InputError(scene.file, "the pipeline binds texel '" + name + "', which the scene does not define");
}

Pipeline loadPipeline(const fs::path& file) {
    const std::string text = readInputFile(file, std::uint64_t(64) << 20, "pipeline file");

    Pipeline pipeline;
    pipeline.file = file;
    TomlReader reader(file, pipeline.warnings);
    reader.collectUnknownKeys(pipeline.unknownKeys);
    const toml::table root = reader.parse(text);
    reader.checkKeys(root, "", {"pipeline", "slurm", "source", "texel", "render", "compare"});

    pipeline.output = file.parent_path() / (file.stem().string() + "-out");
    if (const toml::table* settings = reader.subtable(root, "", "pipeline", false)) {
        reader.checkKeys(*settings, "pipeline", {"output", "fit_resolution"});
        pipeline.fitResolution = reader.boolean(*settings, "pipeline", "fit_resolution", true);
        if (settings->contains("output")) pipeline.output = reader.resolve("pipeline.output", reader.string(*settings, "pipeline", "output", {}));
    }

    if (const toml::table* slurm = reader.subtable(root, "", "slurm", false)) readSlurmSettings(reader, *slurm, pipeline.slurm);

    // Each kind names the one before it, so they are read in this order.
    std::set<std::string> sourceNames, texelNames, renderNames, compareNames;
    const auto sources = reader.arrayOfTables(root, "source");
    for (std::size_t i = 0; i < sources.size(); ++i)
        pipeline.sources.push_back(readSource(reader, *sources[i], indexed("source", i), sourceNames));
    const auto texels = reader.arrayOfTables(root, "texel");
    for (std::size_t i = 0; i < texels.size(); ++i)
        pipeline.texels.push_back(readTexel(reader, *texels[i], indexed("texel", i), texelNames, sourceNames));
    const auto renders = reader.arrayOfTables(root, "render");
    for (std::size_t i = 0; i < renders.size(); ++i)
        pipeline.renders.push_back(readRender(reader, *renders[i], indexed("render", i), renderNames, texelNames));
    const auto compares = reader.arrayOfTables(root, "compare");
    for (std::size_t i = 0; i < compares.size(); ++i)
        pipeline.compares.push_back(readCompare(reader, *compares[i], indexed("compare", i), compareNames, renderNames));
    return pipeline;
}

}  // namespace vtex::pipelines
