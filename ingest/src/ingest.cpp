// loadMesh(): dispatch by extension, bounded file reading, the report.
#include "detail.h"

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>
#include <vtex/core/progress.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>

namespace vtex::ingest {
namespace detail {

namespace fs = std::filesystem;

bool isContainedRegularFile(const fs::path& root, const fs::path& candidate) {
    std::error_code error;
    const fs::path resolved = fs::canonical(candidate, error);  // follows every symbolic link
    if (error) return false;
    if (!fs::is_regular_file(resolved, error) || error) return false;
    auto r = root.begin();
    auto c = resolved.begin();
    for (; r != root.end(); ++r, ++c)
        if (c == resolved.end() || *r != *c) return false;
    return c != resolved.end();
}

char turnToZUp(RawMesh& raw, const IngestOptions& options) {
    const char up = options.up ? options.up : raw.up;
    // Rotations taking the axis to +Z (determinant 1, so windings and normals stay outward).
    const auto turn = [up](const Eigen::Vector3f& p) -> Eigen::Vector3f {
        if (up == 'y') return {p.x(), -p.z(), p.y()};
        if (up == 'x') return {-p.z(), p.y(), p.x()};
        return p;
    };
    if (up != 'z') {
        for (auto& p : raw.positions) p = turn(p);
        for (auto& n : raw.normals) n = turn(n);
    }
    return up;
}

}  // namespace detail

namespace {

// IngestOptions::fitCell: uniformly into the unit cube, centred in x and y, base at z = 0.
void fitToCell(TriangleMesh& mesh, IngestReport& r) {
    if (mesh.positions.empty()) return;
    Eigen::Vector3d lo = mesh.positions[0].cast<double>(), hi = lo;
    for (const auto& p : mesh.positions) {
        lo = lo.cwiseMin(p.cast<double>());
        hi = hi.cwiseMax(p.cast<double>());
    }
    const double extent = (hi - lo).maxCoeff();
    const double scale = extent > 0 ? 1 / extent : 1;
    const Eigen::Vector3d offset(0.5 - scale * 0.5 * (lo.x() + hi.x()), 0.5 - scale * 0.5 * (lo.y() + hi.y()), -scale * lo.z());
    for (auto& p : mesh.positions) p = (scale * p.cast<double>() + offset).cast<float>().cwiseMax(0.0f).cwiseMin(1.0f);
    r.fitCell = true;
    r.fitScale = scale;
    r.fitOffset = offset;
    r.boundsMin = (scale * lo + offset).cast<float>();
    r.boundsMax = (scale * hi + offset).cast<float>().cwiseMin(1.0f);
}

std::string lowerExtension(const std::filesystem::path& file) {
    std::string extension = file.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return extension;
}

void phase(const IngestOptions& options, const char* name) {
    if (options.progress) {
        options.progress->start(name, 1);
        options.progress->advance(1);
        options.progress->finish();
    }
}

}  // namespace

TriangleMesh loadMesh(const std::filesystem::path& file) { return loadMesh(file, IngestOptions{}); }

TriangleMesh loadMesh(const std::filesystem::path& file, const IngestOptions& options, IngestReport* report) {
    const auto start = std::chrono::steady_clock::now();
    IngestReport local;
    IngestReport& r = report ? *report : local;
    r = IngestReport{};
    r.file = file.string();

    const std::string extension = lowerExtension(file);
    const std::filesystem::path directory = file.parent_path().empty() ? "." : file.parent_path();
    detail::RawMesh raw;
    phase(options, "reading");
    if (extension == ".gltf" || extension == ".glb") {
        const std::string bytes = readInputFile(file, options.maxFileBytes, "file");
        raw = detail::readGltf(bytes, extension == ".glb", file, directory, options);
    } else if (extension == ".obj") {
        const std::string bytes = readInputFile(file, options.maxFileBytes, "file");
        raw = detail::readObj(bytes, file, directory, options);
    } else if (extension == ".off" || extension == ".ply" || extension == ".stl") {
        const std::string bytes = readInputFile(file, options.maxFileBytes, "file");
        raw = detail::readOffPlyStl(bytes, extension.substr(1), file, options);
    } else {
        throw InputError(file, "unknown mesh format '" + extension +
                                   "' (expected .gltf, .glb, .obj, .off, .ply or .stl)");
    }
    r.format = raw.format;
    r.up = detail::turnToZUp(raw, options);
    phase(options, "repairing");
    TriangleMesh mesh = detail::repairMesh(std::move(raw), file, options, r);
    if (options.fitCell) fitToCell(mesh, r);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return mesh;
}

std::string toJson(const IngestReport& r) {
    using nlohmann::json;
    json j;
    j["file"] = r.file;
    j["format"] = r.format;
    j["vertices_in"] = r.verticesIn;
    j["triangles_in"] = r.trianglesIn;
    j["vertices_out"] = r.verticesOut;
    j["triangles_out"] = r.trianglesOut;
    j["materials"] = r.materials;
    j["textures"] = r.textures;
    j["bounds"] = {{"min", {r.boundsMin.x(), r.boundsMin.y(), r.boundsMin.z()}},
                   {"max", {r.boundsMax.x(), r.boundsMax.y(), r.boundsMax.z()}}};
    j["closed"] = r.closed;
    j["up"] = std::string(1, r.up);
    j["fit"] = r.fitCell ? json{{"mode", "cell"}, {"scale", r.fitScale}, {"offset", {r.fitOffset.x(), r.fitOffset.y(), r.fitOffset.z()}}}
                         : json{{"mode", "keep"}};
    const RepairCounts& c = r.repairs;
    j["repairs"] = {{"invalid_index_faces", c.invalidIndexFaces},
                    {"non_finite_faces", c.nonFiniteFaces},
                    {"degenerate_faces", c.degenerateFaces},
                    {"zero_area_faces", c.zeroAreaFaces},
                    {"merged_vertices", c.mergedVertices},
                    {"unreferenced_vertices", c.unreferencedVertices},
                    {"recomputed_normals", c.recomputedNormals},
                    {"flipped_normals", c.flippedNormals},
                    {"flipped_faces", c.flippedFaces}};
    j["warnings"] = r.warnings;
    j["seconds"] = r.seconds;
    // Untrusted text (file names, warnings) may hold invalid UTF-8: replace, never throw.
    return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
}

}  // namespace vtex::ingest
