// `vtex pattern NAME -o mesh.glb [--seed S] [options]`: a procedural source mesh (sampler
// library, vtex/sampler/patterns.h).
#include "cli.h"

#include <vtex/core/atomic_file.h>
#include <vtex/ingest/ingest.h>
#include <vtex/sampler/patterns.h>

#include <cstdio>
#include <stdexcept>

namespace vtex::cli {
namespace {

const bool registered = registerCommand(15, [](CLI::App& app) -> Action {
    app.name("pattern");
    app.description(
        "Generate a procedural source mesh in the unit cube: grass (V-section blades, cyclic), bush "
        "(leaves), fur (thin cylinders, cyclic), brushed (concentric or radial cylinders), blocks "
        "(building elements)");
    struct Flags {
        std::string name;
        std::string output;
        sampler::PatternOptions options;
        int leaves = 0;
    };
    auto flags = std::make_shared<Flags>();
    app.add_option("NAME", flags->name, "Pattern name")
        ->required()
        ->check(CLI::IsMember(sampler::patternNames()));
    app.add_option("-o,--output", flags->output, "Mesh to write (.glb)")->required();
    app.add_option("--seed", flags->options.seed, "Random seed (same seed, same mesh)")
        ->check(seedNumber())
        ->capture_default_str();
    app.add_option("--count", flags->options.count,
                   "Number of elements (grass 16 blades, bush 2000 leaves, fur 300 hairs, brushed 9 "
                   "rings or 24 spokes, blocks 24); 0 = default")
        ->check(CLI::Range(0, 10'000'000));
    app.add_option("--leaves", flags->leaves, "bush: number of leaves (default 2000)")
        ->check(CLI::Range(1, 10'000'000));
    app.add_option("--fluctuation", flags->options.fluctuation,
                   "Angular fluctuation of blades and hairs, radians (grass 0.25, fur 0.15)")
        ->check(finiteNumber())
        ->check(CLI::Range(0.0, 3.14159));
    app.add_option("--lean", flags->options.leanDegrees, "Mean lean of blades and hairs toward +x, degrees")
        ->check(finiteNumber())
        ->check(CLI::Range(-80.0, 80.0));
    app.add_option("--variant", flags->options.variant, "brushed: concentric (default) or radial")
        ->check(CLI::IsMember({"concentric", "radial"}));
    return [flags, &app](const GlobalOptions& global) {
        checkOutputPath(flags->output);  // before any work (atomic_file.h)
        // An option the pattern does not read is bad usage, not silently ignored.
        for (const char* option : {"fluctuation", "lean", "variant"})
            if (app.count(std::string("--") + option) > 0 && !sampler::patternUses(flags->name, option))
                throw CLI::ValidationError(std::string("--") + option, "the " + flags->name + " pattern does not use it (" +
                                                                          sampler::patternsUsing(option) + " do)");
        sampler::PatternOptions options = flags->options;
        if (flags->leaves > 0) {
            if (flags->name != "bush") throw CLI::ValidationError("--leaves", "only for the bush pattern");
            options.count = flags->leaves;
        }
        ingest::TriangleMesh mesh;
        try {
            // A count whose mesh vtex could not read back is bad usage, refused before the
            // work: `brushed --variant radial --count 2097152` grew past 6 GB (fuzz_cli.py).
            if (options.count > 64) {
                const std::uint64_t triangles = sampler::estimatePatternTriangles(flags->name, options);
                if (triangles > sampler::kMaxPatternTriangles)
                    throw CLI::ValidationError(flags->leaves > 0 ? "--leaves" : "--count",
                                               std::to_string(options.count) + " makes about " +
                                                   std::to_string(triangles) + " triangles, more than the " +
                                                   std::to_string(sampler::kMaxPatternTriangles) + " vtex ingests");
            }
            mesh = sampler::makePattern(flags->name, options);
        } catch (const std::invalid_argument& e) {
            throw std::runtime_error(std::string("pattern: ") + e.what());
        }
        ingest::writeMeshGlb(mesh, flags->output);
        char line[512];
        std::snprintf(line, sizeof line, "%s: %zu triangles%s -> %s", flags->name.c_str(), mesh.triangles.size(),
                      sampler::isCyclicPattern(flags->name) ? " (cyclic: sample with --cyclic)" : "",
                      flags->output.c_str());
        status(global, line);
    };
});

}  // namespace
}  // namespace vtex::cli
