// loadBaseMesh(): the renderer's quad mesh. Reads through the same bounded readers as
// loadMesh() (OpenMesh PolyMesh for OFF/PLY/STL, vtex's OBJ parser, tinygltf for glTF), then
// rebuilds each source polygon from its fan: a quad stays a quad, a triangle becomes a
// collapsed quad, a larger polygon is cut into quads (and a last triangle) from its first corner.
#include "detail.h"

#include <vtex/core/input_file.h>

#include <vtex/core/error.h>
#include <vtex/ingest/base_mesh.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>

namespace vtex::ingest {

QuadMesh loadBaseMesh(const std::filesystem::path& file, const IngestOptions& options) {
    std::string extension = file.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    const std::filesystem::path directory = file.parent_path().empty() ? "." : file.parent_path();
    detail::RawMesh raw;
    const std::string bytes = readInputFile(file, options.maxFileBytes, "file");
    if (extension == ".gltf" || extension == ".glb")
        raw = detail::readGltf(bytes, extension == ".glb", file, directory, options);
    else if (extension == ".obj")
        raw = detail::readObj(bytes, file, directory, options);
    else if (extension == ".off" || extension == ".ply" || extension == ".stl")
        raw = detail::readOffPlyStl(bytes, extension.substr(1), file, options);
    else
        throw InputError(file, "unknown mesh format '" + extension + "'");
    detail::turnToZUp(raw, options);

    for (const auto& t : raw.triangles)
        for (auto v : t)
            if (!raw.positions[v].allFinite())
                throw InputError(file, "NaN or infinite coordinate at vertex " + std::to_string(v));

    // Polygons back from their fans.
    if (raw.polygonTriangles.empty()) raw.polygonTriangles.assign(raw.triangles.size(), 1);
    QuadMesh mesh;
    std::size_t t = 0;
    for (std::uint32_t count : raw.polygonTriangles) {
        if (t + count > raw.triangles.size()) throw InputError(file, "internal: polygon table mismatch");
        std::vector<std::uint32_t> polygon{raw.triangles[t][0], raw.triangles[t][1], raw.triangles[t][2]};
        for (std::uint32_t k = 1; k < count; ++k) polygon.push_back(raw.triangles[t + k][2]);
        t += count;
        std::size_t i = 1;
        for (; i + 2 < polygon.size(); i += 2) mesh.quads.push_back({polygon[0], polygon[i], polygon[i + 1], polygon[i + 2]});
        if (i + 1 < polygon.size()) mesh.quads.push_back({polygon[0], polygon[i], polygon[i + 1], polygon[i + 1]});
    }
    if (mesh.quads.empty()) throw InputError(file, "no faces");

    // Positions, UVs; normals: the file's when valid, else area-weighted over the faces around
    // each position (vertices at the same position share them, across UV seams).
    mesh.positions = raw.positions;
    mesh.uvs = raw.uvs;
    std::map<std::array<float, 3>, Eigen::Vector3d> byPosition;
    for (const auto& q : mesh.quads) {
        const Eigen::Vector3d a = raw.positions[q[0]].cast<double>(), b = raw.positions[q[1]].cast<double>(),
                              c = raw.positions[q[2]].cast<double>(), d = raw.positions[q[3]].cast<double>();
        // Twice the vector area of the (possibly non-planar) quad: the cross of its diagonals.
        const Eigen::Vector3d area = (c - a).cross(d - b);
        for (auto v : q) {
            const auto& p = raw.positions[v];
            // (Eigen vectors are not zero-initialised by default.)
            byPosition.try_emplace({p.x(), p.y(), p.z()}, Eigen::Vector3d::Zero()).first->second += area;
        }
    }
    mesh.normals.resize(mesh.positions.size(), Eigen::Vector3f::UnitZ());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        if (v < raw.normals.size() && raw.normals[v].allFinite() && raw.normals[v].squaredNorm() > 1e-12f) {
            mesh.normals[v] = raw.normals[v].normalized();
            continue;
        }
        const auto& p = mesh.positions[v];
        const auto it = byPosition.find({p.x(), p.y(), p.z()});
        if (it != byPosition.end() && it->second.norm() > 0) mesh.normals[v] = it->second.normalized().cast<float>();
    }
    return mesh;
}

}  // namespace vtex::ingest
