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

    // Faces that use a NaN/Inf coordinate.
    std::vector<char> used(n, 0);
    std::vector<std::array<std::uint32_t, 3>> faces;
    std::vector<std::uint32_t> faceMaterials;
    faces.reserve(raw.triangles.size());
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
        for (std::uint32_t v : tri) used[v] = 1;
        faces.push_back(tri);
        faceMaterials.push_back(raw.triangleMaterials.empty() ? 0 : raw.triangleMaterials[t]);
    }
    if (faces.empty()) throw InputError(file, "no valid triangle (every face used a NaN or infinite coordinate)");

    // Bounding box of what is used, in double.
    std::vector<Eigen::Vector3d> points(n);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (std::size_t i = 0; i < n; ++i) {
        points[i] = raw.positions[i].cast<double>();
        if (!used[i]) continue;
        lo = lo.cwiseMin(points[i]);
        hi = hi.cwiseMax(points[i]);
    }
    const double diagonal = (hi - lo).norm();
    if (!(diagonal > 0) || !std::isfinite(diagonal))
        throw InputError(file, "every triangle is degenerate (the mesh has no extent)");

    // Weld, then drop degenerate and zero-area faces.
    const double tolerance = options.weldTolerance * diagonal;
    const std::vector<std::uint32_t> rep = weldVertices(points, used, lo, tolerance, diagonal);
    for (std::size_t i = 0; i < n; ++i)
        if (used[i] && rep[i] != i) ++counts.mergedVertices;
    // A triangle whose doubled area is at most tolerance² has no area at the mesh's scale (with
    // a zero tolerance: exactly zero).
    const double minDoubleArea = tolerance * tolerance;
    std::vector<std::array<std::uint32_t, 3>> kept;   // raw vertex indices
    std::vector<std::array<std::uint32_t, 3>> welded; // representative indices
    std::vector<std::uint32_t> keptMaterials;
    for (std::size_t t = 0; t < faces.size(); ++t) {
        const auto& f = faces[t];
        const std::array<std::uint32_t, 3> w{rep[f[0]], rep[f[1]], rep[f[2]]};
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) {
            ++counts.degenerateFaces;
            continue;
        }
        const double doubleArea = (points[w[1]] - points[w[0]]).cross(points[w[2]] - points[w[0]]).norm();
        if (!(doubleArea > minDoubleArea)) {
            ++counts.zeroAreaFaces;
            continue;
        }
        kept.push_back(f);
        welded.push_back(w);
        keptMaterials.push_back(faceMaterials[t]);
    }
    if (kept.empty())
        throw InputError(file, "no valid triangle left: " + std::to_string(counts.degenerateFaces) +
                                   " degenerate and " + std::to_string(counts.zeroAreaFaces) +
                                   " zero-area faces removed");
    faces.clear();
    faces.shrink_to_fit();

    // Compact the representatives into the welded vertex set.
    std::vector<std::uint32_t> compact(n, kNone);
    std::vector<Eigen::Vector3d> weldedPoints;
    for (auto& w : welded)
        for (auto& v : w) {
            if (compact[v] == kNone) {
                compact[v] = std::uint32_t(weldedPoints.size());
                weldedPoints.push_back(points[v]);
            }
            v = compact[v];
        }

    // Closed meshes: orient outward (CGAL), else keep the file's winding.
    bool closed = isEdgeClosed(welded);
    if (closed) {
        if (options.orientClosed) {
            if (auto flips = computeOutwardFlips(weldedPoints, welded)) {
                for (std::size_t t = 0; t < welded.size(); ++t)
                    if ((*flips)[t]) {
                        std::swap(welded[t][1], welded[t][2]);
                        std::swap(kept[t][1], kept[t][2]);
                        ++counts.flippedFaces;
                    }
            } else {
                closed = false;
                report.warnings.push_back("closed but not orientable as a volume; winding kept");
            }
        } else {
            closed = isConsistentlyWound(welded);
        }
    }

    // Area-weighted normals of the welded vertices.
    std::vector<Eigen::Vector3d> areaNormals(weldedPoints.size(), Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> anyFaceNormal(weldedPoints.size(), Eigen::Vector3d::Zero());
    for (const auto& w : welded) {
        const Eigen::Vector3d c =
            (weldedPoints[w[1]] - weldedPoints[w[0]]).cross(weldedPoints[w[2]] - weldedPoints[w[0]]);
        for (auto v : w) {
            areaNormals[v] += c;  // |c| is twice the area: weights by area
            anyFaceNormal[v] = c;
        }
    }
    auto computedNormal = [&](std::uint32_t v) -> Eigen::Vector3f {
        double length = areaNormals[v].norm();
        if (length > 0 && std::isfinite(length)) return (areaNormals[v] / length).cast<float>();
        // Opposite faces cancelled out: any incident face's normal will do.
        length = anyFaceNormal[v].norm();
        if (length > 0 && std::isfinite(length)) return (anyFaceNormal[v] / length).cast<float>();
        return Eigen::Vector3f::UnitZ();
    };

    // Output vertices: one per distinct (welded position, UV, file normal).
    TriangleMesh mesh;
    const bool hasUvs = !raw.uvs.empty();
    const bool hasNormals = !raw.normals.empty();
    std::unordered_map<VertexKey, std::uint32_t, VertexKeyHash> outputIndex;
    std::vector<std::uint32_t> directIndex;
    if (!hasUvs && !hasNormals) directIndex.assign(weldedPoints.size(), kNone);
    else outputIndex.reserve(weldedPoints.size() * 2);
    mesh.triangles.resize(kept.size());
    for (std::size_t t = 0; t < kept.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t source = kept[t][k];
            const std::uint32_t w = welded[t][k];
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
                mesh.positions.push_back(weldedPoints[w].cast<float>());
                const Eigen::Vector3f geometric = computedNormal(w);
                Eigen::Vector3f normal = hasNormals ? raw.normals[source] : Eigen::Vector3f::Zero();
                if (normal.allFinite() && normal.squaredNorm() >= 1e-12f) {
                    normal.normalize();
                    if (normal.dot(geometric) < 0) {
                        normal = -normal;
                        ++counts.flippedNormals;
                    }
                } else {
                    normal = geometric;
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
    std::vector<char> referenced(n, 0);
    for (const auto& f : kept)
        for (auto v : f) referenced[v] = 1;
    // Plus what a reader already knew (OBJ `v` lines no face used never became raw vertices).
    counts.unreferencedVertices += std::uint64_t(std::count(referenced.begin(), referenced.end(), 0));

    // Materials and textures travel unchanged; at least one material.
    mesh.materials = std::move(raw.materials);
    mesh.textures = std::move(raw.textures);
    if (mesh.materials.empty()) mesh.materials.emplace_back();
    for (auto& m : keptMaterials)
        if (m >= mesh.materials.size()) m = 0;
    if (mesh.materials.size() > 1) mesh.triangleMaterials = std::move(keptMaterials);
    for (auto& material : mesh.materials)
        if (material.baseColorTexture >= int(mesh.textures.size())) material.baseColorTexture = -1;
    if (!hasUvs)
        for (auto& material : mesh.materials) material.baseColorTexture = -1;
    mesh.closed = closed;

    // Report.
    report.verticesOut = mesh.positions.size();
    report.trianglesOut = mesh.triangles.size();
    report.materials = mesh.materials.size();
    report.textures = mesh.textures.size();
    report.closed = closed;
    Eigen::Vector3f outLo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f outHi = -outLo;
    for (const auto& p : mesh.positions) {
        outLo = outLo.cwiseMin(p);
        outHi = outHi.cwiseMax(p);
    }
    report.boundsMin = outLo;
    report.boundsMax = outHi;
    if (mesh.triangles.size() > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) +
                                   " triangles (see --max-triangles)");
    return mesh;
}

}  // namespace vtex::ingest::detail
