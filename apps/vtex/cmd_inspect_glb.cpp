// `vtex inspect mesh.glb|scene.gltf [--json]`: what a glTF mesh holds, read through the same
// checks as `vtex ingest` (so a hostile file is refused here too, exit 3).
#include "cli.h"

#include <vtex/ingest/ingest.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <ostream>

namespace vtex::cli {
namespace {

void inspectGltf(const std::filesystem::path& file, const InspectOptions& inspect, std::ostream& out) {
    const bool json = inspect.json;
    ingest::IngestOptions options;
    options.orientClosed = true;
    ingest::IngestReport report;
    const ingest::TriangleMesh mesh = ingest::loadMesh(file, options, &report);
    const auto& r = report.repairs;
    const bool canonical = report.trianglesIn == report.trianglesOut && r.degenerateFaces == 0 &&
                           r.zeroAreaFaces == 0 && r.flippedFaces == 0 && r.recomputedNormals == 0 &&
                           r.flippedNormals == 0;
    if (json) {
        nlohmann::json j = nlohmann::json::parse(ingest::toJson(report));
        j["kind"] = "mesh";
        j["canonical"] = canonical;
        j["has_uvs"] = !mesh.uvs.empty();
        std::vector<nlohmann::json> materials;
        for (const auto& m : mesh.materials)
            materials.push_back({{"base_color_factor", {m.baseColorFactor[0], m.baseColorFactor[1],
                                                        m.baseColorFactor[2], m.baseColorFactor[3]}},
                                 {"base_color_texture", m.baseColorTexture}});
        j["material_list"] = materials;
        std::vector<nlohmann::json> textures;
        for (const auto& t : mesh.textures) textures.push_back({{"width", t.width}, {"height", t.height}});
        j["texture_list"] = textures;
        out << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
        return;
    }
    char line[512];
    out << file.string() << ": glTF mesh (" << report.format << ")\n";
    std::snprintf(line, sizeof line, "  vertices   %llu (file %llu)\n  triangles  %llu (file %llu)\n",
                  (unsigned long long)report.verticesOut, (unsigned long long)report.verticesIn,
                  (unsigned long long)report.trianglesOut, (unsigned long long)report.trianglesIn);
    out << line;
    std::snprintf(line, sizeof line, "  bounds     [%g, %g, %g] .. [%g, %g, %g]\n", report.boundsMin.x(),
                  report.boundsMin.y(), report.boundsMin.z(), report.boundsMax.x(), report.boundsMax.y(),
                  report.boundsMax.z());
    out << line;
    out << "  closed     " << (report.closed ? "yes (oriented outward)" : "no") << '\n';
    out << "  materials  " << mesh.materials.size() << ", textures " << mesh.textures.size()
        << (mesh.uvs.empty() ? ", no UVs" : ", UVs") << '\n';
    for (std::size_t i = 0; i < mesh.textures.size(); ++i)
        out << "    texture " << i << ": " << mesh.textures[i].width << "x" << mesh.textures[i].height << '\n';
    out << "  canonical  " << (canonical ? "yes" : "no (vtex ingest would repair it)") << '\n';
    for (const auto& w : report.warnings) out << "  warning: " << w << '\n';
}

const bool registeredGlb = registerInspector(".glb", inspectGltf);
const bool registeredGltf = registerInspector(".gltf", inspectGltf);

}  // namespace
}  // namespace vtex::cli
