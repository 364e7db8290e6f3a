// `vtex inspect texel.vto [--json]`: what an octree holds, level by level.
#include "cli.h"

#include <vtex/core/error.h>
#include <vtex/octree/octree.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace vtex::cli {
namespace {

std::string number(double v) {
    if (!std::isfinite(v)) return "null";
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.9g", v);
    return buffer;
}

std::string quoted(const std::string& s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') out += '\\';
        if (static_cast<unsigned char>(c) < 0x20) {
            char esc[8];
            std::snprintf(esc, sizeof esc, "\\u%04x", c);
            out += esc;
        } else {
            out += c;
        }
    }
    return out + "\"";
}

std::string checksumsJson(const octree::FileCheck& check) {
    std::string out = "{\"valid\": " + std::string(check.problem.empty() ? "true" : "false") +
                      ", \"version\": " + std::to_string(check.version) + ", \"problem\": " +
                      (check.problem.empty() ? "null" : quoted(check.problem)) + ", \"sections\": [";
    for (std::size_t i = 0; i < check.sections.size(); ++i) {
        const auto& s = check.sections[i];
        out += (i ? ", " : "") + std::string("{\"tag\": ") + quoted(s.tag) + ", \"bytes\": " + std::to_string(s.size) +
               ", \"checksum\": " + (s.checksumOk ? "\"ok\"" : "\"mismatch\"") + "}";
    }
    return out + "]}";
}

void inspectVto(const std::filesystem::path& file, bool json, std::ostream& out) {
    const std::string bytes = octree::readFileBytes(file);
    const octree::FileCheck check = octree::checkFile(bytes, std::string_view("VTEX.VTO", 8), octree::kVtoVersion);
    if (!check.problem.empty()) {
        if (json) {
            out << "{\"file\": " << quoted(file.string()) << ", \"checksums\": " << checksumsJson(check) << "}\n";
        } else {
            out << "checksums:";
            for (const auto& s : check.sections) out << "  " << s.tag << (s.checksumOk ? " ok" : " MISMATCH");
            out << "  -- " << check.problem << '\n';
        }
    }
    const octree::Octree tree = octree::parseVto(bytes, file);  // throws on any problem
    const auto& info = tree.info;
    if (json) {
        out << "{\"file\": " << quoted(file.string()) << ", \"kind\": \"vto\", \"version\": " << check.version
            << ", \"resolution\": " << tree.resolution() << ", \"levels\": " << tree.levelCount()
            << ", \"cyclic\": " << (info.source.cyclic ? "true" : "false") << ", \"filter\": \""
            << octree::filterRuleName(info.rule) << "\", \"tolerance\": " << number(info.tolerance)
            << ", \"stored_nodes\": " << tree.storedNodes() << ", \"compression\": " << number(tree.compression())
            << ", \"source_triangles\": " << info.source.sourceTriangles
            << ", \"source_area\": " << number(info.source.sourceArea) << ", \"fit_error\": {\"mean\": "
            << number(info.source.fitError.mean) << ", \"max\": " << number(info.source.fitError.max)
            << ", \"samples\": " << info.source.fitError.samples << "}, \"per_level\": [";
        for (std::uint32_t l = 0; l < tree.levelCount(); ++l) {
            const auto& s = tree.stats[l];
            out << (l ? ", " : "") << "{\"level\": " << l << ", \"resolution\": " << (1u << l)
                << ", \"stored_nodes\": " << s.storedNodes << ", \"occupied_nodes\": " << s.occupiedNodes
                << ", \"mean_density\": " << number(s.meanDensity)
                << ", \"mean_occupied_density\": " << number(s.meanOccupiedDensity)
                << ", \"filter_error\": {\"mean\": " << number(s.filterErrorMean) << ", \"max\": "
                << number(s.filterErrorMax) << ", \"samples\": " << s.filterErrorSamples << "}}";
        }
        out << "], \"checksums\": " << checksumsJson(check) << "}\n";
        return;
    }
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
    out << "checksums:";
    for (const auto& s : check.sections) out << "  " << s.tag << (s.checksumOk ? " ok" : " MISMATCH");
    out << '\n';
}

const bool registered = registerInspector(".vto", inspectVto);

}  // namespace
}  // namespace vtex::cli
