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
#include <bit>
#include <map>
#include <span>
#include <unordered_map>

namespace vtex::ingest {
namespace {

// A polygon's material and group (QuadMesh::faceNames): triangles of different ones are never
// one quad.
using Label = std::array<std::uint32_t, 2>;
using Corners = std::span<const std::uint32_t>;
using Quad = std::array<std::uint32_t, 4>;

// The source polygons, their corners in one array (a million faces would be a million heap
// vectors otherwise: issue 18's 10⁶-face load).
struct Polygons {
    std::vector<std::uint32_t> corners;
    std::vector<std::size_t> start{0};  ///< polygon i is corners[start[i], start[i + 1])
    std::vector<Label> labels;

    std::size_t size() const { return labels.size(); }
    Corners operator[](std::size_t i) const { return {corners.data() + start[i], start[i + 1] - start[i]}; }
    void add(Corners polygon, const Label& label) {
        corners.insert(corners.end(), polygon.begin(), polygon.end());
        start.push_back(corners.size());
        labels.push_back(label);
    }
    void reserve(std::size_t polygons, std::size_t totalCorners) {
        corners.reserve(totalCorners);
        start.reserve(polygons + 1);
        labels.reserve(polygons);
    }
};

// Two triangles that were one quad an exporter triangulated along its diagonal become that quad
// again, if their normals are within kMaxFold of each other and their union is convex
// (Blender's "Tris to Quads" takes the same 40° by default; a bilinear patch's two halves fold by
// less on any mesh a texel would cover).
struct TrianglePairs {
    static constexpr double kMaxFold = 40.0 * 3.14159265358979323846 / 180.0;
    const std::vector<Eigen::Vector3f>& positions;

    Eigen::Vector3d at(std::uint32_t v) const { return positions[v].cast<double>(); }

    // quad = (a, d, b, c) of triangles a→b→c and b→a→d: planar enough and convex.
    bool mergeable(const Quad& quad) const {
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
    std::pair<std::uint32_t, std::uint32_t> longestEdge(Corners t) const {
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
    Polygons mergeFans(const Polygons& polygons) const {
        Polygons out;
        out.reserve(polygons.size(), polygons.corners.size());
        for (std::size_t i = 0; i < polygons.size(); ++i) {
            const Corners t = polygons[i];
            if (i + 1 < polygons.size() && t.size() == 3 && polygons[i + 1].size() == 3 &&
                polygons.labels[i] == polygons.labels[i + 1]) {
                const Corners u = polygons[i + 1];
                // The shared diagonal v0–v2; as (a, d, b, c): a = v2, b = v0.
                if (u[0] == t[0] && u[1] == t[2] && u[2] != t[1] && mergeable({t[2], u[2], t[0], t[1]})) {
                    out.add(Quad{t[0], t[1], t[2], u[2]}, polygons.labels[i]);
                    ++i;
                    continue;
                }
            }
            out.add(t, polygons.labels[i]);
        }
        return out;
    }

    // Any two triangles sharing an edge that is the longest of both, wound consistently: the quad
    // starting at the first corner of the earlier triangle. A quad (v0, v1, v2, v3) cut along its
    // other diagonal is written (v0, v1, v3), (v1, v2, v3) (Blender, OpenMesh), so that corner is
    // the quad's own first one, and the texel keeps its direction from cell to cell (a start at
    // the lowest vertex index turned cells, as the reader numbers vertices by first use:
    // PerFaceTexels.ATriangulatedGridRendersAsItsQuads). A triangle pairs only with a later one
    // (an earlier one had its turn).
    Polygons mergeLongestEdges(const Polygons& polygons) const {
        const auto key = [](std::uint32_t from, std::uint32_t to) { return std::uint64_t(from) << 32 | to; };
        std::vector<std::pair<std::uint32_t, std::uint32_t>> edge(polygons.size());
        std::unordered_map<std::uint64_t, std::size_t> byEdge;  // the first triangle with that longest edge
        for (std::size_t i = 0; i < polygons.size(); ++i)
            if (polygons[i].size() == 3) {
                edge[i] = longestEdge(polygons[i]);
                byEdge.emplace(key(edge[i].first, edge[i].second), i);
            }
        std::vector<char> merged(polygons.size(), 0);
        Polygons out;
        out.reserve(polygons.size(), polygons.corners.size());
        for (std::size_t i = 0; i < polygons.size(); ++i) {
            if (merged[i]) continue;
            const Corners t = polygons[i];
            const Label& label = polygons.labels[i];
            const auto partner = t.size() == 3 ? byEdge.find(key(edge[i].second, edge[i].first)) : byEdge.end();
            if (partner != byEdge.end() && partner->second > i && polygons.labels[partner->second] == label) {
                const auto [a, b] = edge[i];
                // The corner off the edge (a degenerate triangle has none: a, which mergeable refuses).
                const auto apex = [a = a, b = b](Corners p) {
                    const auto v = std::find_if(p.begin(), p.end(), [&](std::uint32_t w) { return w != a && w != b; });
                    return v == p.end() ? a : *v;
                };
                Quad quad{a, apex(polygons[partner->second]), b, apex(t)};  // t = a→b→c, its partner b→a→d
                if (mergeable(quad)) {
                    std::rotate(quad.begin(), std::find(quad.begin(), quad.end(), t[0]), quad.end());
                    out.add(quad, label);
                    merged[partner->second] = 1;
                    continue;
                }
            }
            out.add(t, label);
        }
        return out;
    }
};

Polygons mergeTrianglePairs(const Polygons& polygons, const std::vector<Eigen::Vector3f>& positions) {
    const TrianglePairs pairs{positions};
    return pairs.mergeLongestEdges(pairs.mergeFans(polygons));
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

// The positions' vertex ids by position: vertices at the same point (UV or normal seams) share
// one, and −0 is the same point as +0. An open-addressing table of vertex indices (a node-based
// map of a million positions spent a fifth of a 10⁶-face load in allocation and cache misses).
std::vector<std::uint32_t> positionIds(const std::vector<Eigen::Vector3f>& positions, std::size_t& count) {
    const auto bits = [](float x) { return std::uint64_t(std::bit_cast<std::uint32_t>(x == 0.0f ? 0.0f : x)); };
    const auto key = [&](std::size_t v) {
        const auto& p = positions[v];
        return std::array<std::uint64_t, 2>{bits(p.x()) << 32 | bits(p.y()), bits(p.z())};
    };
    const auto hash = [](const std::array<std::uint64_t, 2>& k) {  // splitmix64's finaliser
        std::uint64_t x = k[0] ^ (k[1] * 0x9E3779B97F4A7C15ULL);
        x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
        x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
        return x ^ (x >> 31);
    };
    constexpr std::uint32_t kEmpty = 0xffffffffu;
    std::size_t capacity = 16;
    while (capacity < 2 * positions.size()) capacity *= 2;
    std::vector<std::uint32_t> slot(capacity, kEmpty);  // a vertex at that point, or none
    std::vector<std::uint32_t> id(positions.size());
    count = 0;
    for (std::size_t v = 0; v < positions.size(); ++v) {
        const auto k = key(v);
        std::size_t h = hash(k) & (capacity - 1);
        while (slot[h] != kEmpty && key(slot[h]) != k) h = (h + 1) & (capacity - 1);
        if (slot[h] == kEmpty) {
            slot[h] = std::uint32_t(v);
            id[v] = std::uint32_t(count++);
        } else {
            id[v] = id[slot[h]];
        }
    }
    return id;
}

// Unit normals, one per position: the file's when valid, else area-weighted over the faces around
// each position (vertices at the same position share them, across UV seams); +z for a position
// no face uses.
std::vector<Eigen::Vector3f> vertexNormals(const QuadMesh& mesh, const std::vector<Eigen::Vector3f>& fileNormals) {
    std::size_t count = 0;
    const std::vector<std::uint32_t> id = positionIds(mesh.positions, count);
    std::vector<Eigen::Vector3d> area(count, Eigen::Vector3d::Zero());
    for (const auto& q : mesh.quads) {
        const auto at = [&](std::uint32_t v) { return mesh.positions[v].cast<double>(); };
        // Twice the vector area of the (possibly non-planar) quad: the cross of its diagonals.
        const Eigen::Vector3d a = (at(q[2]) - at(q[0])).cross(at(q[3]) - at(q[1]));
        for (auto v : q) area[id[v]] += a;
    }
    std::vector<Eigen::Vector3f> normals(mesh.positions.size(), Eigen::Vector3f::UnitZ());
    for (std::size_t v = 0; v < normals.size(); ++v) {
        if (v < fileNormals.size() && fileNormals[v].allFinite() && fileNormals[v].squaredNorm() > 1e-12f)
            normals[v] = fileNormals[v].normalized();
        else if (area[id[v]].norm() > 0)
            normals[v] = area[id[v]].normalized().cast<float>();
    }
    return normals;
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
    Polygons fans;
    fans.reserve(raw.polygonTriangles.size(), raw.triangles.size() + 2 * raw.polygonTriangles.size());
    std::vector<std::uint32_t> fan;
    std::size_t t = 0;
    for (std::uint32_t count : raw.polygonTriangles) {
        if (t + count > raw.triangles.size()) throw InputError(file, "internal: polygon table mismatch");
        fan.assign({raw.triangles[t][0], raw.triangles[t][1], raw.triangles[t][2]});
        for (std::uint32_t k = 1; k < count; ++k) fan.push_back(raw.triangles[t + k][2]);
        fans.add(fan, triangleLabel[t]);
        t += count;
    }
    const Polygons polygons = mergeTrianglePairs(fans, raw.positions);
    fans = {};
    mesh.quads.reserve(polygons.size());
    for (std::size_t p = 0; p < polygons.size(); ++p) {
        const Corners polygon = polygons[p];
        const std::size_t first = mesh.quads.size();
        std::size_t i = 1;
        for (; i + 2 < polygon.size(); i += 2) mesh.quads.push_back({polygon[0], polygon[i], polygon[i + 1], polygon[i + 2]});
        if (i + 1 < polygon.size()) mesh.quads.push_back({polygon[0], polygon[i], polygon[i + 1], polygon[i + 1]});
        if (!mesh.names.empty())
            mesh.faceNames.insert(mesh.faceNames.end(), mesh.quads.size() - first, polygons.labels[p]);
    }
    if (mesh.quads.empty()) throw InputError(file, "no faces");
    mesh.positions = std::move(raw.positions);
    mesh.uvs = std::move(raw.uvs);
    mesh.normals = vertexNormals(mesh, raw.normals);
    return mesh;
}

}  // namespace vtex::ingest
