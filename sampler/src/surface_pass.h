// The surface passes of the sampler (sampler.cpp's phases 1–3), shared by sampleMesh and the
// partial recompute (resample.cpp): clip the triangles a filter lets through, scatter the
// pieces into buckets, reduce each voxel. Internal to vtex_sampler.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/ingest/mesh.h>
#include <vtex/primitive/ellipsoid.h>
#include <vtex/octree/filtering.h>
#include <vtex/octree/volume.h>
#include <vtex/sampler/clip.h>

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

namespace vtex::sampler::detail {

using octree::VolumeBlock;
using octree::VoxelBox;
using Vec3 = Eigen::Vector3d;

struct Record {
    std::uint64_t key;
    std::uint32_t tri;
    float area;                // voxel units²
    std::array<float, 3> rgb;  // mean linear colour over the piece
};

inline std::uint64_t mix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

// Everything the clip phase needs to know about one triangle.
struct TriangleColour {
    Eigen::Vector3f factor{1, 1, 1};
    const ingest::Image* texture = nullptr;
};

class MeshView {
public:
    MeshView(const ingest::TriangleMesh& mesh, double scale, const std::array<double, 3>& offset, double n)
        : mMesh(mesh) {
        mPositions.resize(mesh.positions.size());
        for (std::size_t i = 0; i < mesh.positions.size(); ++i)
            for (int a = 0; a < 3; ++a)
                mPositions[i][a] = (double(mesh.positions[i][a]) * scale + offset[std::size_t(a)]) * n;
        mHasUv = mesh.uvs.size() == mesh.positions.size();
    }

    const std::vector<Vec3>& positions() const { return mPositions; }
    Vec3 vertex(std::size_t t, int k) const { return mPositions[mMesh.triangles[t][std::size_t(k)]]; }

    TriangleColour colour(std::size_t t) const {
        TriangleColour c;
        const std::size_t m = mMesh.triangleMaterials.empty() ? 0 : mMesh.triangleMaterials[t];
        if (m < mMesh.materials.size()) {
            const auto& material = mMesh.materials[m];
            c.factor = material.baseColorFactor.head<3>();
            const int tex = material.baseColorTexture;
            if (mHasUv && tex >= 0 && std::size_t(tex) < mMesh.textures.size()) {
                const auto& image = mMesh.textures[std::size_t(tex)];
                if (image.width > 0 && image.height > 0 &&
                    image.rgba.size() == std::size_t(image.width) * std::size_t(image.height) * 4)
                    c.texture = &image;
            }
        }
        return c;
    }

    // Mean linear colour over a piece of triangle t: the texture sampled at the centroid of each
    // fan triangle of the piece, weighted by its area.
    Eigen::Vector3f pieceColour(std::size_t t, const TriangleColour& c, const ClipPolygon& piece) const {
        if (!c.texture) return c.factor;
        const Vec3 a = vertex(t, 0), e0 = vertex(t, 1) - a, e1 = vertex(t, 2) - a;
        const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
        const double denom = d00 * d11 - d01 * d01;
        const auto& tri = mMesh.triangles[t];
        const Eigen::Vector2f uv0 = mMesh.uvs[tri[0]], uv1 = mMesh.uvs[tri[1]], uv2 = mMesh.uvs[tri[2]];
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        double total = 0;
        for (int i = 1; i + 1 < piece.count; ++i) {
            const Vec3& p0 = piece.v[0];
            const Vec3& p1 = piece.v[std::size_t(i)];
            const Vec3& p2 = piece.v[std::size_t(i + 1)];
            const double w = 0.5 * (p1 - p0).cross(p2 - p0).norm();
            const Vec3 d = (p0 + p1 + p2) / 3.0 - a;
            const double d20 = d.dot(e0), d21 = d.dot(e1);
            const double beta = denom > 0 ? (d11 * d20 - d01 * d21) / denom : 1.0 / 3;
            const double gamma = denom > 0 ? (d00 * d21 - d01 * d20) / denom : 1.0 / 3;
            const Eigen::Vector2f uv =
                float(1 - beta - gamma) * uv0 + float(beta) * uv1 + float(gamma) * uv2;
            sum += float(w) * ingest::sampleBaseColour(*c.texture, uv.x(), uv.y());
            total += w;
        }
        if (total <= 0) return c.factor.cwiseProduct(ingest::sampleBaseColour(*c.texture, uv0.x(), uv0.y()));
        return c.factor.cwiseProduct(sum / float(total));
    }

private:
    const ingest::TriangleMesh& mMesh;
    std::vector<Vec3> mPositions;
    bool mHasUv = false;
};

// Pieces below this area (voxel units²) are slivers of exact arithmetic (collinear points on a
// cutting plane), not surface: at N = 2^20 it is 1e-24 of the unit cube's face.
constexpr double kMinPieceArea = 1e-12;


// Every voxel.
struct AllVoxels {
    bool triangle(const Vec3&, const Vec3&) const { return true; }
    bool voxel(std::uint32_t, std::uint32_t, std::uint32_t) const { return true; }
};

// The voxels of a box; a triangle whose bounds miss it (voxel units) is not clipped (with cyclic
// x and y its pieces may wrap in from anywhere: always clipped).
struct RegionFilter {
    VoxelBox region;
    bool cyclic = false;
    bool triangle(const Vec3& lo, const Vec3& hi) const {
        if (cyclic) return true;
        for (int a = 0; a < 3; ++a)
            if (hi[a] < double(region.min[std::size_t(a)]) || lo[a] > double(region.max[std::size_t(a)])) return false;
        return true;
    }
    bool voxel(std::uint32_t x, std::uint32_t y, std::uint32_t z) const { return region.contains(x, y, z); }
};

// Phase 1: clip. Triangles in fixed chunks; each piece of a triangle in a voxel the filter keeps
// becomes a record.
template <class Filter>
std::vector<std::vector<Record>> clipPieces(const MeshView& view, const std::vector<Vec3>& normals, std::uint32_t n,
                                            bool cyclic, const Filter& filter, Progress& progress) {
    const std::size_t triangleCount = normals.size();
    const std::size_t chunkSize = std::max<std::size_t>(1024, (triangleCount + 255) / 256);
    const std::size_t chunkCount = (triangleCount + chunkSize - 1) / chunkSize;
    std::vector<std::vector<Record>> chunks(chunkCount);
    progress.start("sample: clip", triangleCount);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunkCount, 1), [&](const auto& range) {
        for (std::size_t ci = range.begin(); ci != range.end(); ++ci) {
            auto& out = chunks[ci];
            const std::size_t end = std::min(triangleCount, (ci + 1) * chunkSize);
            for (std::size_t t = ci * chunkSize; t < end; ++t) {
                if (normals[t].isZero()) continue;
                const Vec3 a = view.vertex(t, 0), b = view.vertex(t, 1), c = view.vertex(t, 2);
                if (!filter.triangle(a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c))) continue;
                const TriangleColour colour = view.colour(t);
                clipTriangleToGrid(a, b, c, n, cyclic,
                                   [&](std::uint32_t x, std::uint32_t y, std::uint32_t z, const ClipPolygon& piece) {
                                       if (!filter.voxel(x, y, z)) return;
                                       const double area = piece.area();
                                       if (!(area > kMinPieceArea)) return;
                                       const Eigen::Vector3f rgb = view.pieceColour(t, colour, piece);
                                       out.push_back(Record{octree::mortonEncode(x, y, z), std::uint32_t(t),
                                                            float(area), {rgb.x(), rgb.y(), rgb.z()}});
                                   });
            }
            progress.advance(end - ci * chunkSize);
        }
    });
    progress.finish();
    return chunks;
}

// Phase 2: the records in 4096 buckets by the top bits of their key, chunk by chunk.
struct Buckets {
    std::vector<Record> records;
    std::vector<std::uint64_t> offsets;  ///< bucket b's records: [offsets[b·chunks], offsets[(b+1)·chunks])
    std::size_t bucketCount = 0, chunkCount = 0;
};
Buckets scatterRecords(std::vector<std::vector<Record>>& chunks, std::uint32_t L);

struct SurfaceResult {
    std::vector<VolumeBlock> voxels;
    octree::FitErrorStats fit;
};

// Phase 3: each bucket sorted by (voxel, triangle) and summed voxel by voxel in that order; the
// fit error measured on the voxels whose key hashes at most to `fitThreshold`, summed per bucket
// in key order, then over the buckets in order (so any pass that measures the same voxels, from
// the same pieces, sums the same doubles in the same order).
// Phase 3: each bucket sorted by (voxel, triangle) and summed voxel by voxel in that order; the
// fit error measured on the voxels whose key hashes at most to `fitThreshold`, summed per bucket
// in key order, then over the buckets in order (so any pass that measures the same voxels, from
// the same pieces, sums the same doubles in the same order).
SurfaceResult reduceVoxels(Buckets& buckets, const std::vector<Vec3>& normals, std::uint32_t n, std::uint32_t L,
                           std::uint64_t fitThreshold, Progress& progress);

template <class Filter>
SurfaceResult sampleSurface(const MeshView& view, const std::vector<Vec3>& normals, std::uint32_t n, bool cyclic,
                            const Filter& filter, std::uint64_t fitThreshold, Progress& progress) {
    const std::uint32_t L = std::uint32_t(std::countr_zero(n));
    auto chunks = clipPieces(view, normals, n, cyclic, filter, progress);
    Buckets buckets = scatterRecords(chunks, L);
    return reduceVoxels(buckets, normals, n, L, fitThreshold, progress);
}

/// The hash threshold of the voxels on which the fit error is measured (see sampler.cpp).
std::uint64_t fitThreshold(double totalArea, std::uint64_t samples);

/// What every pass needs of the mesh: its mapping to voxel units, the triangles' unit normals
/// (zero for a degenerate one) and their total area in voxel units (summed in triangle order).
struct SourceView {
    SourceView(const ingest::TriangleMesh& mesh, const std::array<double, 3>& offset, double scale, std::uint32_t n);
    MeshView view;
    std::vector<Vec3> normals;
    double totalArea = 0;
};

}  // namespace vtex::sampler::detail
