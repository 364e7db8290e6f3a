// loadBaseMesh(): the renderer's quad mesh. Reads through the same bounded readers as
// loadMesh() (OpenMesh PolyMesh for OFF/PLY/STL, vtex's OBJ parser, tinygltf for glTF), then
// rebuilds each source polygon from its fan: a quad stays a quad, two triangles that were one
// quad (a triangulated export) become that quad again, any other triangle a collapsed quad, and a
// larger polygon is cut into quads (and a last triangle) from its first corner.
#include "detail.h"

#include <vtex/core/input_file.h>

#include <vtex/core/error.h>
#include <vtex/ingest/base_mesh.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>

namespace vtex::ingest {
namespace {

using Polygon = std::vector<std::uint32_t>;
// A polygon's material and group (QuadMesh::faceNames): triangles of different ones are never
// one quad.
using Label = std::array<std::uint32_t, 2>;

// Two triangles that were one quad an exporter triangulated along its diagonal become that quad
// again, if their normals are within kMaxFold of each other and their union is convex
// (Blender's "Tris to Quads" takes the same 40° by default; a bilinear patch's two halves fold by
// less on any mesh a texel would cover).
struct TrianglePairs {
    static constexpr double kMaxFold = 40.0 * 3.14159265358979323846 / 180.0;
    const std::vector<Eigen::Vector3f>& positions;

    Eigen::Vector3d at(std::uint32_t v) const { return positions[v].cast<double>(); }

    // quad = (a, d, b, c) of triangles a→b→c and b→a→d: planar enough and convex.
    bool mergeable(const Polygon& quad) const {
        const std::uint32_t a = quad[0], d = quad[1], b = quad[2], c = quad[3];
        const Eigen::Vector3d n1 = (at(b) - at(a)).cross(at(c) - at(a)), n2 = (at(a) - at(b)).cross(at(d) - at(b));
        if (!(n1.norm() > 0) || !(n2.norm() > 0)) return false;
        if (std::acos(std::clamp(n1.normalized().dot(n2.normalized()), -1.0, 1.0)) > kMaxFold) return false;
        for (int k = 0; k < 4; ++k) {
            const Eigen::Vector3d p = at(quad[std::size_t(k)]), q = at(quad[std::size_t((k + 1) % 4)]),
                                  r = at(quad[std::size_t((k + 2) % 4)]);
            if (!((q - p).cross(r - q).dot(n1 + n2) > 0)) return false;
        }
        return true;
    }

    // The longest edge of triangle t, as (from, to) in its winding.
    std::pair<std::uint32_t, std::uint32_t> longestEdge(const Polygon& t) const {
        int best = 0;
        double length = -1;
        for (int k = 0; k < 3; ++k) {
            const double l = (at(t[std::size_t((k + 1) % 3)]) - at(t[std::size_t(k)])).squaredNorm();
            if (l > length) {
                length = l;
                best = k;
            }
        }
        return {t[std::size_t(best)], t[std::size_t((best + 1) % 3)]};
    }

    // The pairs an exporter writes one after the other as a fan, (v0, v1, v2) then (v0, v2, v3):
    // the quad (v0, v1, v2, v3), in its own orientation, so that texels keep their direction
    // from cell to cell.
    void mergeFans(std::vector<Polygon>& polygons, std::vector<Label>& labels) const {
        std::vector<Polygon> out;
        std::vector<Label> outLabels;
        for (std::size_t i = 0; i < polygons.size(); ++i) {
            const Polygon& t = polygons[i];
            outLabels.push_back(labels[i]);
            if (i + 1 < polygons.size() && t.size() == 3 && polygons[i + 1].size() == 3 && labels[i] == labels[i + 1]) {
                const Polygon& u = polygons[i + 1];
                // The shared diagonal v0–v2; as (a, d, b, c): a = v2, b = v0.
                if (u[0] == t[0] && u[1] == t[2] && u[2] != t[1] && mergeable({t[2], u[2], t[0], t[1]})) {
                    out.push_back({t[0], t[1], t[2], u[2]});
                    ++i;
                    continue;
                }
            }
            out.push_back(t);
        }
        polygons = std::move(out);
        labels = std::move(outLabels);
    }

    // Any two triangles sharing an edge that is the longest of both, wound consistently: the quad
    // starting at the first corner of the earlier triangle. A quad (v0, v1, v2, v3) cut along its
    // other diagonal is written (v0, v1, v3), (v1, v2, v3) (Blender, OpenMesh), so that corner is
    // the quad's own first one, and the texel keeps its direction from cell to cell (a start at
    // the lowest vertex index turned cells, as the reader numbers vertices by first use:
    // PerFaceTexels.ATriangulatedGridRendersAsItsQuads). A triangle pairs only with a later one
    // (an earlier one had its turn).
    void mergeLongestEdges(std::vector<Polygon>& polygons, std::vector<Label>& labels) const {
        std::vector<std::pair<std::uint32_t, std::uint32_t>> edge(polygons.size());
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> byEdge;
        for (std::size_t i = 0; i < polygons.size(); ++i)
            if (polygons[i].size() == 3) byEdge.emplace(edge[i] = longestEdge(polygons[i]), i);
        std::vector<char> merged(polygons.size(), 0);
        std::vector<Polygon> out;
        std::vector<Label> outLabels;
        for (std::size_t i = 0; i < polygons.size(); ++i) {
            if (merged[i]) continue;
            const Polygon& t = polygons[i];
            outLabels.push_back(labels[i]);
            const auto partner = t.size() == 3 ? byEdge.find({edge[i].second, edge[i].first}) : byEdge.end();
            if (partner != byEdge.end() && partner->second > i && labels[partner->second] == labels[i]) {
                const auto [a, b] = edge[i];
                // The corner off the edge (a degenerate triangle has none: a, which mergeable refuses).
                const auto apex = [a = a, b = b](const Polygon& p) {
                    const auto v = std::find_if(p.begin(), p.end(), [&](std::uint32_t w) { return w != a && w != b; });
                    return v == p.end() ? a : *v;
                };
                Polygon quad{a, apex(polygons[partner->second]), b, apex(t)};  // t = a→b→c, its partner b→a→d
                if (mergeable(quad)) {
                    std::rotate(quad.begin(), std::find(quad.begin(), quad.end(), t[0]), quad.end());
                    out.push_back(std::move(quad));
                    merged[partner->second] = 1;
                    continue;
                }
            }
            out.push_back(t);
        }
        polygons = std::move(out);
        labels = std::move(outLabels);
    }
};

void mergeTrianglePairs(std::vector<Polygon>& polygons, std::vector<Label>& labels,
                        const std::vector<Eigen::Vector3f>& positions) {
    const TrianglePairs pairs{positions};
    pairs.mergeFans(polygons, labels);
    pairs.mergeLongestEdges(polygons, labels);
}

// The material and group names of the raw mesh's triangles as QuadMesh::names indices, one label
// per triangle; `names` stays empty when the file names nothing.
std::vector<Label> triangleLabels(const detail::RawMesh& raw, std::vector<std::string>& names) {
    std::map<std::string, std::uint32_t> index;
    const auto nameIndex = [&](const std::string& name) {
        if (name.empty()) return QuadMesh::kNoName;
        const auto [it, inserted] = index.try_emplace(name, std::uint32_t(names.size()));
        if (inserted) names.push_back(name);
        return it->second;
    };
    std::vector<Label> labels(raw.triangles.size(), Label{QuadMesh::kNoName, QuadMesh::kNoName});
    for (std::size_t t = 0; t < raw.triangles.size(); ++t) {
        if (t < raw.triangleMaterials.size() && raw.triangleMaterials[t] < raw.materials.size())
            labels[t][0] = nameIndex(raw.materials[raw.triangleMaterials[t]].name);
        if (t < raw.triangleGroups.size() && raw.triangleGroups[t] < raw.groups.size())
            labels[t][1] = nameIndex(raw.groups[raw.triangleGroups[t]]);
    }
    return labels;
}

}  // namespace

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
    const std::vector<Label> triangleLabel = triangleLabels(raw, mesh.names);
    std::vector<Polygon> polygons;
    std::vector<Label> labels;
    std::size_t t = 0;
    for (std::uint32_t count : raw.polygonTriangles) {
        if (t + count > raw.triangles.size()) throw InputError(file, "internal: polygon table mismatch");
        Polygon polygon{raw.triangles[t][0], raw.triangles[t][1], raw.triangles[t][2]};
        for (std::uint32_t k = 1; k < count; ++k) polygon.push_back(raw.triangles[t + k][2]);
        labels.push_back(triangleLabel[t]);
        t += count;
        polygons.push_back(std::move(polygon));
    }
    mergeTrianglePairs(polygons, labels, raw.positions);
    for (std::size_t p = 0; p < polygons.size(); ++p) {
        const Polygon& polygon = polygons[p];
        const std::size_t first = mesh.quads.size();
        std::size_t i = 1;
        for (; i + 2 < polygon.size(); i += 2) mesh.quads.push_back({polygon[0], polygon[i], polygon[i + 1], polygon[i + 2]});
        if (i + 1 < polygon.size()) mesh.quads.push_back({polygon[0], polygon[i], polygon[i + 1], polygon[i + 1]});
        if (!mesh.names.empty()) mesh.faceNames.insert(mesh.faceNames.end(), mesh.quads.size() - first, labels[p]);
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
