// `vtex inspect leaves.vtl [--json]`: what a sampled volume holds.
#include "cli.h"
#include "inspect_checksums.h"
#include "json_number.h"

#include <vtex/core/error.h>
#include <vtex/octree/volume.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

namespace vtex::cli {
namespace {

// What inspect reports of a volume's blocks.
struct VtlSummary {
    std::uint64_t surface = 0, solidBlocks = 0;
    double solidVoxels = 0, surfaceArea = 0, mass = 0;
    std::array<std::uint32_t, 3> lo{~0u, ~0u, ~0u}, hi{0, 0, 0};  ///< occupied voxels, inclusive
    double meanDensity = 0;
};

VtlSummary summarize(const octree::SparseVolume& volume) {
    const std::uint32_t L = volume.info.levels;
    VtlSummary s;
    for (const auto& b : volume.blocks) {
        const double voxels = std::ldexp(1.0, 3 * int(L - b.level));
        if (!b.isSolid()) {
            ++s.surface;
            s.surfaceArea += double(b.data.density) * 2.0 / std::ldexp(1.0, 3 * int(L));
        } else {
            ++s.solidBlocks;
            s.solidVoxels += voxels;
        }
        s.mass += double(b.data.density) * voxels;
        const auto c = octree::mortonDecode(b.key);
        const std::uint32_t shift = L - b.level;
        for (int a = 0; a < 3; ++a) {
            s.lo[a] = std::min(s.lo[a], c[a] << shift);
            s.hi[a] = std::max(s.hi[a], ((c[a] + 1) << shift) - 1);
        }
    }
    s.meanDensity = s.mass / std::ldexp(1.0, 3 * int(L));
    return s;
}

void printVtlJson(const std::filesystem::path& file, const octree::FileCheck& check, const octree::SparseVolume& volume,
                  const VtlSummary& s, std::ostream& out) {
    const auto& info = volume.info;
    nlohmann::json j = {{"file", file.string()},
                        {"kind", "vtl"},
                        {"version", check.version},
                        {"resolution", info.resolution()},
                        {"levels", info.levels + 1},
                        {"cyclic", info.cyclic},
                        {"scale", jsonNumber(info.scale)},
                        {"offset", {jsonNumber(info.offset[0]), jsonNumber(info.offset[1]), jsonNumber(info.offset[2])}},
                        {"source_triangles", info.sourceTriangles},
                        {"source_area", jsonNumber(info.sourceArea)},
                        {"surface_voxels", s.surface},
                        {"sampled_area", jsonNumber(s.surfaceArea)},
                        {"solid_blocks", s.solidBlocks},
                        {"solid_voxels", jsonNumber(s.solidVoxels)},
                        {"solid_density", jsonNumber(info.solidDensity)},
                        {"mean_density", jsonNumber(s.meanDensity)},
                        {"occupied_bounds", nullptr},
                        {"fit_error", {{"mean", jsonNumber(info.fitError.mean)},
                                       {"max", jsonNumber(info.fitError.max)},
                                       {"samples", info.fitError.samples}}},
                        {"checksums", checksumsJson(check)}};
    if (!volume.blocks.empty()) j["occupied_bounds"] = {{s.lo[0], s.lo[1], s.lo[2]}, {s.hi[0], s.hi[1], s.hi[2]}};
    out << j.dump() << '\n';
}

void printVtlText(const std::filesystem::path& file, const octree::FileCheck& check, const octree::SparseVolume& volume,
                  const VtlSummary& s, std::ostream& out) {
    const auto& info = volume.info;
    const std::uint32_t L = info.levels;
    const double n3 = std::ldexp(1.0, 3 * int(L));
    char line[512];
    out << file.string() << ": sampled volume (.vtl version " << check.version << ")\n";
    std::snprintf(line, sizeof line, "resolution: %u^3 (%u levels)%s\n", info.resolution(), L + 1,
                  info.cyclic ? ", cyclic in x and y" : "");
    out << line;
    std::snprintf(line, sizeof line, "source: %llu triangles, area %.6g (reference units), mapped by x*%.6g + (%.6g, %.6g, %.6g)\n",
                  (unsigned long long)info.sourceTriangles, info.sourceArea, info.scale, info.offset[0],
                  info.offset[1], info.offset[2]);
    out << line;
    std::snprintf(line, sizeof line, "surface voxels: %llu (%.4f%% of N^3), sampled area %.6g\n",
                  (unsigned long long)s.surface, 100.0 * double(s.surface) / n3, s.surfaceArea);
    out << line;
    std::snprintf(line, sizeof line, "solid: %llu blocks covering %.0f voxels, density %.6g\n",
                  (unsigned long long)s.solidBlocks, s.solidVoxels, double(info.solidDensity));
    out << line;
    std::snprintf(line, sizeof line, "mean density: %.6g\n", s.meanDensity);
    out << line;
    if (!volume.blocks.empty()) {
        std::snprintf(line, sizeof line, "occupied voxels: [%u %u %u] .. [%u %u %u]\n", s.lo[0], s.lo[1], s.lo[2],
                      s.hi[0], s.hi[1], s.hi[2]);
        out << line;
    }
    std::snprintf(line, sizeof line, "fit error: mean %.4g, max %.4g over %llu voxels\n", info.fitError.mean,
                  info.fitError.max, (unsigned long long)info.fitError.samples);
    out << line;
    printChecksums(check, out);
}

void inspectVtl(const std::filesystem::path& file, const InspectOptions& options, std::ostream& out) {
    const auto [bytes, check] = readCheckedFile(file, std::string_view("VTEX.VTL", 8), octree::kVtlVersion, options.json, out);
    const octree::SparseVolume volume = octree::parseVtl(bytes, file);  // throws on any problem
    const VtlSummary summary = summarize(volume);
    if (options.json) printVtlJson(file, check, volume, summary, out);
    else printVtlText(file, check, volume, summary, out);
}

const bool registered = registerInspector(".vtl", inspectVtl);

}  // namespace
}  // namespace vtex::cli
