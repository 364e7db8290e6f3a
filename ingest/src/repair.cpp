// The repair pass every reader's output goes through: non-finite and invalid faces, vertex
// welding relative to the bounding box, degenerate and zero-area faces, normals, closedness
// and outward orientation.
#include "detail.h"

#include <vtex/core/error.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

namespace vtex::ingest::detail {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

struct Cell {
    std::int64_t x, y, z;
    bool operator==(const Cell&) const = default;
};
struct CellHash {
    std::size_t operator()(const Cell& c) const {
        return std::size_t(std::uint64_t(c.x) * 73856093ULL) ^ std::size_t(std::uint64_t(c.y) * 19349663ULL) ^
               std::size_t(std::uint64_t(c.z) * 83492791ULL);
    }
};

// Merges every used vertex into the first vertex within `tolerance` of it (Euclidean), with a
// hash grid whose cells are several tolerances wide: a vertex only looks into the neighbouring
// cells it is within `tolerance` of, so most vertices probe a single cell.
std::vector<std::uint32_t> weldVertices(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<char>& used, const Eigen::Vector3d& origin,
                                        double tolerance, double diagonal) {
    const double cellSize = std::max(8.0 * tolerance, diagonal * 1e-9);
    const double margin = tolerance / cellSize;
    std::unordered_map<Cell, std::uint32_t, CellHash> heads;
    heads.reserve(points.size());
    std::vector<std::uint32_t> next(points.size(), kNone);
    std::vector<std::uint32_t> rep(points.size(), kNone);
    const double tolerance2 = tolerance * tolerance;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (!used[i]) continue;
        const Eigen::Vector3d g = (points[i] - origin) / cellSize;
        const Eigen::Vector3d f = g.array().floor();
        const Cell home{std::int64_t(f.x()), std::int64_t(f.y()), std::int64_t(f.z())};
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const double frac = g[a] - f[a];
            lo[a] = frac < margin ? -1 : 0;
            hi[a] = frac > 1.0 - margin ? 1 : 0;
        }
        std::uint32_t found = kNone;
        for (int dx = lo[0]; dx <= hi[0] && found == kNone; ++dx)
            for (int dy = lo[1]; dy <= hi[1] && found == kNone; ++dy)
                for (int dz = lo[2]; dz <= hi[2] && found == kNone; ++dz) {
                    auto it = heads.find({home.x + dx, home.y + dy, home.z + dz});
                    for (std::uint32_t k = it == heads.end() ? kNone : it->second; k != kNone; k = next[k])
                        if ((points[k] - points[i]).squaredNorm() <= tolerance2) {
                            found = k;
                            break;
                        }
                }
        if (found != kNone) {
            rep[i] = found;
        } else {
            rep[i] = std::uint32_t(i);
            auto [it, inserted] = heads.try_emplace(home, std::uint32_t(i));
            if (!inserted) {
                next[i] = it->second;
                it->second = std::uint32_t(i);
            }
        }
    }
    return rep;
}

// True when every undirected edge is shared by exactly two triangles.
bool isEdgeClosed(const std::vector<std::array<std::uint32_t, 3>>& triangles) {
    std::vector<std::uint64_t> edges;
    edges.reserve(triangles.size() * 3);
    for (const auto& t : triangles)
        for (int k = 0; k < 3; ++k) {
            const std::uint64_t a = t[k], b = t[(k + 1) % 3];
            edges.push_back(std::min(a, b) << 32 | std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i != 2) return false;
        i = j;
    }
    return !edges.empty();
}

// True when every directed edge appears once (the winding is consistent).
bool isConsistentlyWound(const std::vector<std::array<std::uint32_t, 3>>& triangles) {
    std::vector<std::uint64_t> edges;
    edges.reserve(triangles.size() * 3);
    for (const auto& t : triangles)
        for (int k = 0; k < 3; ++k) edges.push_back(std::uint64_t(t[k]) << 32 | t[(k + 1) % 3]);
    std::sort(edges.begin(), edges.end());
    return std::adjacent_find(edges.begin(), edges.end()) == edges.end();
}

struct VertexKey {
    std::uint32_t rep;
    std::uint32_t bits[5];  // uv and file normal, bitwise
    bool operator==(const VertexKey& o) const {
        return rep == o.rep && std::memcmp(bits, o.bits, sizeof bits) == 0;
    }
};
struct VertexKeyHash {
    std::size_t operator()(const VertexKey& k) const {
        std::size_t h = k.rep * 0x9E3779B97F4A7C15ULL;
        for (std::uint32_t b : k.bits) h = (h ^ b) * 0x100000001B3ULL;
        return h;
    }
};

using Triangle = std::array<std::uint32_t, 3>;

// The faces whose three corners are finite, with their materials and which vertices they use; a
// face with a NaN/Inf corner refuses the file, or is counted and dropped with --drop-invalid.
struct FiniteFaces {
    std::vector<Triangle> faces;
    std::vector<std::uint32_t> materials;
    std::vector<char> used;  ///< per raw vertex
};
FiniteFaces finiteFaces(const RawMesh& raw, const std::filesystem::path& file, const IngestOptions& options,
                        RepairCounts& counts) {
    FiniteFaces out;
    out.used.assign(raw.positions.size(), 0);
    out.faces.reserve(raw.triangles.size());
    for (std::size_t t = 0; t < raw.triangles.size(); ++t) {
        const auto& tri = raw.triangles[t];
        bool finite = true;
        for (std::uint32_t v : tri) finite &= raw.positions[v].allFinite();
        if (!finite) {
            if (!options.dropInvalidFaces) {
                std::uint32_t bad = tri[0];
                for (std::uint32_t v : tri)
                    if (!raw.positions[v].allFinite()) bad = v;
                throw InputError(file, "NaN or infinite coordinate at vertex " + std::to_string(bad) +
                                           " (used by triangle " + std::to_string(t) + ")");
            }
            ++counts.nonFiniteFaces;
            continue;
        }
        for (std::uint32_t v : tri) out.used[v] = 1;
        out.faces.push_back(tri);
        out.materials.push_back(raw.triangleMaterials.empty() ? 0 : raw.triangleMaterials[t]);
    }
    if (out.faces.empty()) throw InputError(file, "no valid triangle (every face used a NaN or infinite coordinate)");
    return out;
}

// The faces left after welding the used vertices (relative to the bounding box's diagonal) and
// dropping the degenerate and zero-area ones, each by its raw corners (`raw`, for the file's
// UVs and normals) and by its welded vertices (`welded`, indices into `points`).
struct WeldedFaces {
    std::vector<Triangle> raw;
    std::vector<Triangle> welded;
    std::vector<std::uint32_t> materials;
    std::vector<Eigen::Vector3d> points;  ///< the welded vertices that some kept face uses
};
WeldedFaces weldFaces(const RawMesh& mesh, const FiniteFaces& finite, const std::filesystem::path& file,
                      const IngestOptions& options, RepairCounts& counts) {
    const std::size_t n = mesh.positions.size();
    // Bounding box of what is used, in double.
    std::vector<Eigen::Vector3d> points(n);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (std::size_t i = 0; i < n; ++i) {
        points[i] = mesh.positions[i].cast<double>();
        if (!finite.used[i]) continue;
        lo = lo.cwiseMin(points[i]);
        hi = hi.cwiseMax(points[i]);
    }
    const double diagonal = (hi - lo).norm();
    if (!(diagonal > 0) || !std::isfinite(diagonal))
        throw InputError(file, "every triangle is degenerate (the mesh has no extent)");

    const double tolerance = options.weldTolerance * diagonal;
    const std::vector<std::uint32_t> rep = weldVertices(points, finite.used, lo, tolerance, diagonal);
    for (std::size_t i = 0; i < n; ++i)
        if (finite.used[i] && rep[i] != i) ++counts.mergedVertices;
    // A triangle whose doubled area is at most tolerance² has no area at the mesh's scale (with
    // a zero tolerance: exactly zero).
    const double minDoubleArea = tolerance * tolerance;
    WeldedFaces out;
    for (std::size_t t = 0; t < finite.faces.size(); ++t) {
        const Triangle& f = finite.faces[t];
        const Triangle w{rep[f[0]], rep[f[1]], rep[f[2]]};
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) {
            ++counts.degenerateFaces;
            continue;
        }
        const double doubleArea = (points[w[1]] - points[w[0]]).cross(points[w[2]] - points[w[0]]).norm();
        if (!(doubleArea > minDoubleArea)) {
            ++counts.zeroAreaFaces;
            continue;
        }
        out.raw.push_back(f);
        out.welded.push_back(w);
        out.materials.push_back(finite.materials[t]);
    }
    if (out.raw.empty())
        throw InputError(file, "no valid triangle left: " + std::to_string(counts.degenerateFaces) +
                                   " degenerate and " + std::to_string(counts.zeroAreaFaces) +
                                   " zero-area faces removed");
    // Compact the representatives into the welded vertex set, in order of first use.
    std::vector<std::uint32_t> compact(n, kNone);
    for (auto& w : out.welded)
        for (auto& v : w) {
            if (compact[v] == kNone) {
                compact[v] = std::uint32_t(out.points.size());
                out.points.push_back(points[v]);
            }
            v = compact[v];
        }
    return out;
}

// Whether the welded mesh is closed; a closed one is turned outward (CGAL) when the options ask
// for it, else the file's winding is kept and it counts as closed only if consistently wound.
bool orientClosed(WeldedFaces& faces, const IngestOptions& options, RepairCounts& counts,
                  std::vector<std::string>& warnings) {
    if (!isEdgeClosed(faces.welded)) return false;
    if (!options.orientClosed) return isConsistentlyWound(faces.welded);
    const auto flips = computeOutwardFlips(faces.points, faces.welded);
    if (!flips) {
        warnings.push_back("closed but not orientable as a volume; winding kept");
        return false;
    }
    for (std::size_t t = 0; t < faces.welded.size(); ++t)
        if ((*flips)[t]) {
            std::swap(faces.welded[t][1], faces.welded[t][2]);
            std::swap(faces.raw[t][1], faces.raw[t][2]);
            ++counts.flippedFaces;
        }
    return true;
}

// Area-weighted normals of the welded vertices; where opposite faces cancel out, any incident
// face's normal; +Z for a vertex with neither.
std::vector<Eigen::Vector3f> weldedNormals(const WeldedFaces& faces) {
    std::vector<Eigen::Vector3d> areaNormals(faces.points.size(), Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> anyFaceNormal(faces.points.size(), Eigen::Vector3d::Zero());
    for (const auto& w : faces.welded) {
        const Eigen::Vector3d c = (faces.points[w[1]] - faces.points[w[0]]).cross(faces.points[w[2]] - faces.points[w[0]]);
        for (auto v : w) {
            areaNormals[v] += c;  // |c| is twice the area: weights by area
            anyFaceNormal[v] = c;
        }
    }
    std::vector<Eigen::Vector3f> normals(faces.points.size());
    for (std::size_t v = 0; v < normals.size(); ++v) {
        double length = areaNormals[v].norm();
        if (length > 0 && std::isfinite(length)) normals[v] = (areaNormals[v] / length).cast<float>();
        else if (length = anyFaceNormal[v].norm(); length > 0 && std::isfinite(length))
            normals[v] = (anyFaceNormal[v] / length).cast<float>();
        else normals[v] = Eigen::Vector3f::UnitZ();
    }
    return normals;
}

// The output's vertices and triangles: one vertex per distinct (welded position, UV, file
// normal). A file normal is kept, turned to the side of the computed one (counted); a missing
// or unusable one is the computed normal (counted).
void emitVertices(const RawMesh& raw, const WeldedFaces& faces, const std::vector<Eigen::Vector3f>& computed,
                  TriangleMesh& mesh, RepairCounts& counts) {
    const bool hasUvs = !raw.uvs.empty();
    const bool hasNormals = !raw.normals.empty();
    std::unordered_map<VertexKey, std::uint32_t, VertexKeyHash> outputIndex;
    std::vector<std::uint32_t> directIndex;
    if (!hasUvs && !hasNormals) directIndex.assign(faces.points.size(), kNone);
    else outputIndex.reserve(faces.points.size() * 2);
    mesh.triangles.resize(faces.raw.size());
    for (std::size_t t = 0; t < faces.raw.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t source = faces.raw[t][k];
            const std::uint32_t w = faces.welded[t][k];
            std::uint32_t* slot;
            if (!directIndex.empty()) {
                slot = &directIndex[w];
            } else {
                VertexKey key{w, {0, 0, 0, 0, 0}};
                Eigen::Vector3f normal = hasNormals ? raw.normals[source] : Eigen::Vector3f::Zero();
                if (!normal.allFinite() || normal.squaredNorm() < 1e-12f) normal.setZero();
                else normal.normalize();
                if (hasUvs) {
                    Eigen::Vector2f uv = raw.uvs[source];
                    if (!uv.allFinite()) uv.setZero();
                    std::memcpy(&key.bits[0], uv.data(), 8);
                }
                std::memcpy(&key.bits[2], normal.data(), 12);
                auto [it, inserted] = outputIndex.try_emplace(key, kNone);
                slot = &it->second;
            }
            if (*slot == kNone) {
                *slot = std::uint32_t(mesh.positions.size());
                mesh.positions.push_back(faces.points[w].cast<float>());
                Eigen::Vector3f normal = hasNormals ? raw.normals[source] : Eigen::Vector3f::Zero();
                if (normal.allFinite() && normal.squaredNorm() >= 1e-12f) {
                    normal.normalize();
                    if (normal.dot(computed[w]) < 0) {
                        normal = -normal;
                        ++counts.flippedNormals;
                    }
                } else {
                    normal = computed[w];
                    ++counts.recomputedNormals;
                }
                mesh.normals.push_back(normal);
                if (hasUvs) {
                    Eigen::Vector2f uv = raw.uvs[source];
                    mesh.uvs.push_back(uv.allFinite() ? uv : Eigen::Vector2f::Zero());
                }
            }
            mesh.triangles[t][k] = *slot;
        }
    }
}

// Materials and textures travel unchanged; at least one material, per-face materials only when
// there are several, texture references only where they resolve and the mesh has UVs.
void carryMaterials(RawMesh& raw, std::vector<std::uint32_t> faceMaterials, TriangleMesh& mesh) {
    mesh.materials = std::move(raw.materials);
    mesh.textures = std::move(raw.textures);
    if (mesh.materials.empty()) mesh.materials.emplace_back();
    for (auto& m : faceMaterials)
        if (m >= mesh.materials.size()) m = 0;
    if (mesh.materials.size() > 1) mesh.triangleMaterials = std::move(faceMaterials);
    for (auto& material : mesh.materials)
        if (material.baseColorTexture >= int(mesh.textures.size()) || raw.uvs.empty()) material.baseColorTexture = -1;
}

void reportOutput(const TriangleMesh& mesh, IngestReport& report) {
    report.verticesOut = mesh.positions.size();
    report.trianglesOut = mesh.triangles.size();
    report.materials = mesh.materials.size();
    report.textures = mesh.textures.size();
    report.closed = mesh.closed;
    Eigen::Vector3f outLo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f outHi = -outLo;
    for (const auto& p : mesh.positions) {
        outLo = outLo.cwiseMin(p);
        outHi = outHi.cwiseMax(p);
    }
    report.boundsMin = outLo;
    report.boundsMax = outHi;
}

}  // namespace

TriangleMesh repairMesh(RawMesh&& raw, const std::filesystem::path& file, const IngestOptions& options,
                        IngestReport& report) {
    RepairCounts& counts = report.repairs;
    counts = raw.repairs;
    report.warnings = std::move(raw.warnings);
    report.verticesIn = raw.positions.size();
    report.trianglesIn = raw.triangles.size() + counts.invalidIndexFaces;
    const std::size_t n = raw.positions.size();
    if (!raw.normals.empty() && raw.normals.size() != n) raw.normals.clear();
    if (!raw.uvs.empty() && raw.uvs.size() != n) raw.uvs.clear();
    if (raw.triangleMaterials.size() != raw.triangles.size()) raw.triangleMaterials.clear();
    if (raw.triangles.empty())
        throw InputError(file, counts.invalidIndexFaces ? "no valid triangle (every face had an index out of range)"
                                                        : "no triangles (points, lines or empty geometry only)");

    WeldedFaces faces = weldFaces(raw, finiteFaces(raw, file, options, counts), file, options, counts);
    TriangleMesh mesh;
    mesh.closed = orientClosed(faces, options, counts, report.warnings);
    emitVertices(raw, faces, weldedNormals(faces), mesh, counts);
    // Raw vertices no kept face uses, plus what a reader already knew (OBJ `v` lines no face
    // used never became raw vertices).
    std::vector<char> referenced(n, 0);
    for (const auto& f : faces.raw)
        for (auto v : f) referenced[v] = 1;
    counts.unreferencedVertices += std::uint64_t(std::count(referenced.begin(), referenced.end(), 0));
    carryMaterials(raw, std::move(faces.materials), mesh);
    reportOutput(mesh, report);
    if (mesh.triangles.size() > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) +
                                   " triangles (see --max-triangles)");
    return mesh;
}

}  // namespace vtex::ingest::detail
