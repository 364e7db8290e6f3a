// `vtex inspect texel.vto [--json] [--source mesh.glb]`: what an octree holds, level by level, and
// with its source what each level lets through against the mesh.
#include "cli.h"
#include "fidelity_report.h"
#include "inspect_checksums.h"
#include "json_number.h"

#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/octree/octree.h>
#include <vtex/render/source_visibility.h>

#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace vtex::cli {
namespace {

// Per level, against the source mesh (render::measureSourceFidelity); empty without a source.
render::SourceFidelity measuresAgainstSource(const octree::Octree& tree, const std::filesystem::path& source) {
    if (source.empty()) return {};
    return render::measureSourceFidelity(tree, ingest::loadMesh(source));
}

// The whole report as one JSON line.
void writeVtoJson(const std::filesystem::path& file, const octree::FileCheck& check, const octree::Octree& tree,
                  const render::SourceFidelity& measures, std::ostream& out) {
    const auto& info = tree.info;
    nlohmann::json levels = nlohmann::json::array();
    for (std::uint32_t l = 0; l < tree.levelCount(); ++l) {
        const auto& s = tree.stats[l];
        levels.push_back({{"level", l},
                          {"chords_against_source", fidelityJson(measures, l)},
                          {"resolution", 1u << l},
                          {"stored_nodes", s.storedNodes},
                          {"occupied_nodes", s.occupiedNodes},
                          {"mean_density", jsonNumber(s.meanDensity)},
                          {"mean_occupied_density", jsonNumber(s.meanOccupiedDensity)},
                          {"filter_error", {{"mean", jsonNumber(s.filterErrorMean)},
                                            {"max", jsonNumber(s.filterErrorMax)},
                                            {"samples", s.filterErrorSamples}}}});
    }
    nlohmann::json j = {{"file", file.string()},
                        {"kind", "vto"},
                        {"version", check.version},
                        {"resolution", tree.resolution()},
                        {"levels", tree.levelCount()},
                        {"cyclic", info.source.cyclic},
                        {"filter", std::string(octree::filterRuleName(info.rule))},
                        {"tolerance", jsonNumber(info.tolerance)},
                        {"stored_nodes", tree.storedNodes()},
                        {"compression", jsonNumber(tree.compression())},
                        {"source_triangles", info.source.sourceTriangles},
                        {"source_area", jsonNumber(info.source.sourceArea)},
                        {"fit_error", {{"mean", jsonNumber(info.source.fitError.mean)},
                                       {"max", jsonNumber(info.source.fitError.max)},
                                       {"samples", info.source.fitError.samples}}},
                        {"per_level", levels},
                        {"checksums", checksumsJson(check)}};
    if (tree.measures) {
        const octree::SourceMeasures& m = *tree.measures;
        j["source_measures"] = {{"tau", jsonNumber(m.tau)},
                                {"tolerance", jsonNumber(m.tolerance)},
                                {"faithful_levels", {m.faithfulCoarsest, m.faithfulFinest}},
                                {"mesh_level", m.meshLevel},
                                {"level_scales", m.levelScales},
                                {"shadow_levels", m.shadowLevels},
                                {"own_shares", m.ownShares}};
    }
    if (tree.layerMeans) {
        // The coarse levels' density profile's layer means (octree::LayerMeans, the PROF section).
        const octree::LayerMeans& m = *tree.layerMeans;
        j["density_profile"] = {{"level", m.level}, {"x", m.axis[0]}, {"y", m.axis[1]}, {"z", m.axis[2]}};
    }
    out << j.dump() << '\n';
}

// What `vtex build --source` stored for renders (render::measureSource), as text.
void printSourceMeasures(const octree::SourceMeasures& m, std::ostream& out) {
    char line[512];
    std::snprintf(line, sizeof line,
                  "source measures (vtex build --source, for tau %g, tolerance %g): faithful levels %d-%d, mesh "
                  "level %d, %zu level scales, %zu shadow levels\n",
                  m.tau, m.tolerance, int(m.faithfulCoarsest), int(m.faithfulFinest), int(m.meshLevel),
                  m.levelScales.size(), m.shadowLevels.size());
    out << line;
    if (m.ownShares.empty()) return;
    // A lit voxel's own leaf (docs/render.md): the share of its matter a shadow query from it
    // takes off its own voxel, per level.
    out << "own shares by level:";
    for (const double s : m.ownShares) {
        std::snprintf(line, sizeof line, " %.3f", s);
        out << line;
    }
    out << '\n';
}

// The coarse levels' density profile (octree::DensityProfile): its height profile, a few layers
// of the profile level, bottom to top, as a share of the level's mean.
void printDensityProfile(const octree::LayerMeans& m, std::ostream& out) {
    char line[64];
    const std::size_t layers = m.axis[2].size(), every = std::max<std::size_t>(1, layers / 8);
    double mean = 0;
    for (const double v : m.axis[2]) mean += v / double(layers);
    out << "density profile (level " << m.level << " layer means, stored by the build): layers 0, " << every << ", "
        << 2 * every << " ... bottom to top, over the mean:";
    for (std::size_t k = 0; k < layers; k += every) {
        std::snprintf(line, sizeof line, " %.2f", mean > 0 ? m.axis[2][k] / mean : 0.0);
        out << line;
    }
    out << '\n';
}

// The report as text: the octree, its levels, what the build stored, the source's chords.
void printVto(const std::filesystem::path& file, const octree::FileCheck& check, const octree::Octree& tree,
              const render::SourceFidelity& measures, const InspectOptions& options, std::ostream& out) {
    const auto& info = tree.info;
    char line[512];
    out << file.string() << ": octree (.vto version " << check.version << ")\n";
    std::snprintf(line, sizeof line, "resolution: %u^3, %u levels%s; filter %s, tolerance %g\n", tree.resolution(),
                  tree.levelCount(), info.source.cyclic ? ", cyclic in x and y" : "",
                  std::string(octree::filterRuleName(info.rule)).c_str(), double(info.tolerance));
    out << line;
    std::snprintf(line, sizeof line, "stored nodes: %llu, compression 1 - stored/N^3 = %.4f%%\n",
                  (unsigned long long)tree.storedNodes(), 100.0 * tree.compression());
    out << line;
    std::snprintf(line, sizeof line, "source: %llu triangles, area %.6g; fit error mean %.4g, max %.4g (%llu voxels)\n",
                  (unsigned long long)info.source.sourceTriangles, info.source.sourceArea, info.source.fitError.mean,
                  info.source.fitError.max, (unsigned long long)info.source.fitError.samples);
    out << line;
    out << "level    N   stored nodes  occupied nodes  mean density  mean occupied  filter error mean / max (samples)\n";
    for (std::uint32_t l = 0; l < tree.levelCount(); ++l) {
        const auto& s = tree.stats[l];
        std::snprintf(line, sizeof line, "%5u %5u %14llu %15llu %13.6g %14.6g  %.4g / %.4g (%llu)\n", l, 1u << l,
                      (unsigned long long)s.storedNodes, (unsigned long long)s.occupiedNodes, s.meanDensity,
                      s.meanOccupiedDensity, s.filterErrorMean, s.filterErrorMax,
                      (unsigned long long)s.filterErrorSamples);
        out << line;
    }
    if (tree.measures) printSourceMeasures(*tree.measures, out);
    if (tree.layerMeans) printDensityProfile(*tree.layerMeans, out);
    printFidelity(measures, options.source, out);
    printChecksums(check, out);
}

void inspectVto(const std::filesystem::path& file, const InspectOptions& options, std::ostream& out) {
    const auto [bytes, check] = readCheckedFile(file, std::string_view("VTEX.VTO", 8), octree::kVtoVersion, options.json, out);
    const octree::Octree tree = octree::parseVto(bytes, file);  // throws on any problem
    const render::SourceFidelity measures = measuresAgainstSource(tree, options.source);
    if (options.json) writeVtoJson(file, check, tree, measures, out);
    else printVto(file, check, tree, measures, options, out);
}

const bool registered = registerInspector(".vto", inspectVto);

}  // namespace
}  // namespace vtex::cli
