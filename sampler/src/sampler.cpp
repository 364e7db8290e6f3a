// Mesh → finest level: exact clipped areas, fitted ellipsoids, albedo, solid interior.
// F. Neyret 1994 §3 and §3.3; DESIGN.md, "Sampling (mesh → finest level)".
//
// Three parallel phases, deterministic whatever the thread count:
//  1. clip: triangles in fixed chunks, each piece of a triangle in a voxel becomes a record
//     (voxel key, triangle, area, colour);
//  2. scatter: records go to 4096 buckets by the top bits of their Morton key, chunk by chunk,
//     so each bucket is a contiguous key range and its records keep triangle order;
//  3. reduce: each bucket sorts its records by (voxel, triangle) and sums each voxel in that
//     order, so a voxel's value never depends on scheduling or on the sampled region.
// Then, for closed meshes, the interior is classified top-down over the octree: a node with no
// surface voxel below it is tested once (its centre, CGAL) and becomes one solid block.
#include "inside_test.h"
#include "surface_pass.h"

#include <vtex/core/error.h>
#include <vtex/core/memory_budget.h>
#include <vtex/octree/filtering.h>
#include <vtex/sampler/clip.h>
#include <vtex/sampler/sampler.h>

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

namespace vtex::sampler {

using namespace detail;

namespace {

bool isPowerOfTwo(std::uint32_t n) { return n != 0 && (n & (n - 1)) == 0; }

void checkOptions(const SampleOptions& options) {
    if (!isPowerOfTwo(options.resolution) || options.resolution > (1u << octree::kMaxLevel))
        throw std::invalid_argument("resolution must be a power of two from 1 to 2^20");
    if (options.region) {
        for (int a = 0; a < 3; ++a)
            if (options.region->max[a] > options.resolution || options.region->min[a] > options.region->max[a])
                throw std::invalid_argument("region outside the volume");
    }
    if (!(options.solidDensity >= 0) || !std::isfinite(options.solidDensity))
        throw std::invalid_argument("solid density must be finite and non-negative");
    if (options.cyclic && options.solid == SolidMode::On)
        throw std::invalid_argument("--solid on cannot be combined with --cyclic");
}

}  // namespace

void referenceMapping(const ingest::TriangleMesh& mesh, BoundsMode bounds, double& scale,
                      std::array<double, 3>& offset) {
    scale = 1;
    offset = {0, 0, 0};
    if (bounds == BoundsMode::Unit || mesh.positions.empty()) return;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = Eigen::Vector3d::Constant(-INFINITY);
    for (const auto& p : mesh.positions) {
        lo = lo.cwiseMin(p.cast<double>());
        hi = hi.cwiseMax(p.cast<double>());
    }
    if (bounds == BoundsMode::Auto && lo.minCoeff() >= 0 && hi.maxCoeff() <= 1) return;
    const double extent = (hi - lo).maxCoeff();
    if (!(extent > 0) || !std::isfinite(extent)) return;
    scale = 1.0 / extent;
    for (int a = 0; a < 3; ++a) offset[std::size_t(a)] = -lo[a] * scale;
}

std::uint64_t estimateSampleMemory(const ingest::TriangleMesh& mesh, const SampleOptions& options) {
    double scale;
    std::array<double, 3> offset;
    referenceMapping(mesh, options.bounds, scale, offset);
    const double n = double(options.resolution), k = scale * n;
    // Pieces of one triangle ≤ area·(|nx|+|ny|+|nz|) + perimeter·(number of axes) + 1 in voxel
    // units: bounded here by √3·area + 2·perimeter + 2.
    double pieces = 0;
    for (const auto& t : mesh.triangles) {
        if (t[0] >= mesh.positions.size() || t[1] >= mesh.positions.size() || t[2] >= mesh.positions.size())
            continue;
        const Vec3 a = mesh.positions[t[0]].cast<double>() * k, b = mesh.positions[t[1]].cast<double>() * k,
                   c = mesh.positions[t[2]].cast<double>() * k;
        const double area = 0.5 * (b - a).cross(c - a).norm();
        const double perimeter = (b - a).norm() + (c - b).norm() + (a - c).norm();
        pieces += 1.75 * area + 2 * perimeter + 2;
    }
    // Records twice (chunks and buckets), voxels at most one per piece, per-triangle data, and
    // a solid classification proportional to the surface. Then the volume's file, which writeVtl
    // builds in memory beside the volume (serializeVtl's VOXL section, 54 bytes a voxel, then the
    // container's copy of it): without it, a surface across the whole domain (fuzz_cli.py's
    // hill.obj at 4096³, 3·10⁷ voxels) peaked at 7.6 GiB against an estimate of 4.3 GiB.
    constexpr double kVtlBytesPerVoxel = 8 + 1 + 1 + 4 * 11;  // octree/src/volume.cpp, kBlockRecordSize
    const double bytes = pieces * (2.0 * sizeof(Record) + sizeof(VolumeBlock) + 16 + 2 * kVtlBytesPerVoxel) +
                         double(mesh.triangles.size()) * 64 + double(mesh.positions.size()) * 48 + (1 << 20);
    return std::uint64_t(std::min(bytes, 1.8e19));
}

namespace detail {

Buckets scatterRecords(std::vector<std::vector<Record>>& chunks, std::uint32_t L) {
    Buckets out;
    out.chunkCount = chunks.size();
    const std::uint32_t keyBits = 3 * L;
    const std::uint32_t bucketShift = keyBits > 12 ? keyBits - 12 : 0;
    out.bucketCount = std::size_t(1) << (keyBits - bucketShift);
    const std::size_t chunkCount = out.chunkCount, bucketCount = out.bucketCount;
    auto& offsets = out.offsets;
    offsets.assign(chunkCount * bucketCount + 1, 0);
    tbb::parallel_for(std::size_t(0), chunkCount, [&](std::size_t ci) {
        for (const auto& r : chunks[ci]) ++offsets[(r.key >> bucketShift) * chunkCount + ci + 1];
    });
    std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());  // bucket-major, then chunk
    out.records.resize(offsets.back());
    tbb::parallel_for(std::size_t(0), chunkCount, [&](std::size_t ci) {
        std::vector<std::uint64_t> cursor(bucketCount);
        for (std::size_t b = 0; b < bucketCount; ++b) cursor[b] = offsets[b * chunkCount + ci];
        for (const auto& r : chunks[ci]) out.records[cursor[r.key >> bucketShift]++] = r;
        std::vector<Record>().swap(chunks[ci]);
    });
    return out;
}

SurfaceResult reduceVoxels(Buckets& buckets, const std::vector<Vec3>& normals, std::uint32_t n, std::uint32_t L,
                           std::uint64_t fitThreshold, Progress& progress) {
    struct BucketOut {
        std::vector<VolumeBlock> voxels;
        double fitSum = 0, fitMax = 0;
        std::uint64_t fitCount = 0;
    };
    std::vector<BucketOut> outs(buckets.bucketCount);
    progress.start("sample: voxels", buckets.bucketCount);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, buckets.bucketCount, 4), [&](const auto& range) {
        std::vector<Vec3> voxelNormals;
        std::vector<double> weights;
        for (std::size_t b = range.begin(); b != range.end(); ++b) {
            const auto begin = buckets.records.begin() + std::ptrdiff_t(buckets.offsets[b * buckets.chunkCount]);
            const auto end = buckets.records.begin() + std::ptrdiff_t(buckets.offsets[(b + 1) * buckets.chunkCount]);
            std::sort(begin, end, [](const Record& x, const Record& y) { return x.key != y.key ? x.key < y.key : x.tri < y.tri; });
            BucketOut& out = outs[b];
            for (auto run = begin; run != end;) {
                auto runEnd = run;
                double area = 0;
                double rgb[3] = {0, 0, 0};
                voxelNormals.clear();
                weights.clear();
                while (runEnd != end && runEnd->key == run->key) {
                    const double a = runEnd->area;
                    area += a;
                    for (int c = 0; c < 3; ++c) rgb[c] += a * double(runEnd->rgb[std::size_t(c)]);
                    voxelNormals.push_back(normals[runEnd->tri]);
                    weights.push_back(a);
                    ++runEnd;
                }
                VolumeBlock block;
                block.key = run->key;
                block.level = std::uint8_t(L);
                block.data.density = float(area * double(n) * 0.5);  // (area/N²) / (2/N³)
                for (int c = 0; c < 3; ++c) block.data.albedo[std::size_t(c)] = float(rgb[c] / area);
                const auto fit = octree::Ellipsoid::fitNormals(voxelNormals, weights);
                if (fit) octree::packEllipsoid(*fit, block.data);
                else octree::packIsotropic(block.data);
                if (fit && mix64(run->key) <= fitThreshold) {
                    const double e = octree::fitError(*fit, voxelNormals, weights);
                    out.fitSum += e;
                    out.fitMax = std::max(out.fitMax, e);
                    ++out.fitCount;
                }
                if (block.data.density > 0) out.voxels.push_back(block);
                run = runEnd;
            }
            progress.advance(1);
        }
    });
    progress.finish();
    std::vector<Record>().swap(buckets.records);
    SurfaceResult result;
    std::size_t voxelCount = 0;
    for (const auto& b : outs) voxelCount += b.voxels.size();
    result.voxels.reserve(voxelCount);
    double fitSum = 0;
    for (auto& b : outs) {
        result.voxels.insert(result.voxels.end(), b.voxels.begin(), b.voxels.end());
        std::vector<VolumeBlock>().swap(b.voxels);
        fitSum += b.fitSum;
        result.fit.samples += b.fitCount;
        result.fit.max = std::max(result.fit.max, b.fitMax);
    }
    if (result.fit.samples > 0) result.fit.mean = fitSum / double(result.fit.samples);
    return result;
}

// The hash threshold of the voxels on which the fit error is measured: about `samples` of them.
// A function of the mesh's area alone (voxel units², summed in triangle order), not of what the
// sampling finds, so that a partial re-sampling selects the voxels a full one would: a surface of
// area A crosses about 1.5·A voxels (the mean of |nx| + |ny| + |nz| over directions is 3/2).
std::uint64_t fitThreshold(double totalArea, std::uint64_t samples) {
    const double expected = 1.5 * totalArea;
    if (samples == 0 || !(expected > double(samples))) return ~std::uint64_t(0);
    return std::uint64_t(double(samples) / expected * 18446744073709551615.0);
}


SourceView::SourceView(const ingest::TriangleMesh& mesh, const std::array<double, 3>& offset, double scale,
                       std::uint32_t n)
    : view(mesh, scale, offset, double(n)), normals(mesh.triangles.size()) {
    for (std::size_t t = 0; t < normals.size(); ++t) {
        const Vec3 cross = (view.vertex(t, 1) - view.vertex(t, 0)).cross(view.vertex(t, 2) - view.vertex(t, 0));
        const double norm = cross.norm();
        normals[t] = norm > 0 && std::isfinite(norm) ? Vec3(cross / norm) : Vec3::Zero();
        if (std::isfinite(norm)) totalArea += 0.5 * norm;
    }
}

}  // namespace detail

namespace {

// Ingest may split vertices along normal or UV seams: the mesh's triangles over its positions
// welded by exact position, as the inside test needs them.
struct WeldedMesh {
    std::vector<Vec3> positions;
    std::vector<std::array<std::uint32_t, 3>> triangles;
};
WeldedMesh weldByPosition(const ingest::TriangleMesh& mesh, const MeshView& view) {
    struct Hash {
        std::size_t operator()(const std::array<double, 3>& p) const {
            return std::size_t(mix64(std::bit_cast<std::uint64_t>(p[0]) ^
                                     mix64(std::bit_cast<std::uint64_t>(p[1]) ^ mix64(std::bit_cast<std::uint64_t>(p[2])))));
        }
    };
    WeldedMesh out;
    out.triangles.resize(mesh.triangles.size());
    std::unordered_map<std::array<double, 3>, std::uint32_t, Hash> index;
    std::vector<std::uint32_t> remap(view.positions().size());
    for (std::size_t i = 0; i < view.positions().size(); ++i) {
        const Vec3& p = view.positions()[i];
        const auto [it, inserted] = index.try_emplace({p.x(), p.y(), p.z()}, std::uint32_t(out.positions.size()));
        if (inserted) out.positions.push_back(p);
        remap[i] = it->second;
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) out.triangles[t][std::size_t(k)] = remap[mesh.triangles[t][std::size_t(k)]];
    return out;
}

// What a solid voxel holds: the density (16 per voxel unless given), an isotropic ellipsoid and
// the mesh's area-weighted mean colour.
octree::VoxelData solidVoxel(const MeshView& view, std::size_t triangleCount, double density) {
    octree::VoxelData solidData;
    solidData.density = float(density);
    octree::packIsotropic(solidData);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (std::size_t t = 0; t < triangleCount; ++t) {
        const double a = 0.5 * (view.vertex(t, 1) - view.vertex(t, 0)).cross(view.vertex(t, 2) - view.vertex(t, 0)).norm();
        sum += a * view.colour(t).factor.cast<double>();
        weight += a;
    }
    const Eigen::Vector3d albedo = weight > 0 ? Eigen::Vector3d(sum / weight) : Eigen::Vector3d::Ones();
    solidData.albedo = {float(albedo.x()), float(albedo.y()), float(albedo.z())};
    return solidData;
}

// The largest nodes inside `region` that hold no surface voxel (top-down: nodes with surface
// below are opened; the others are tested once), as (level, Morton key).
struct SolidCandidate {
    std::uint32_t level;
    std::uint64_t key;
};
std::vector<SolidCandidate> solidCandidates(const std::vector<VolumeBlock>& surface, std::uint32_t L, const VoxelBox& region) {
    auto hasSurface = [&](std::uint32_t level, std::uint64_t key) {
        const std::uint32_t shift = 3 * (L - level);
        const std::uint64_t lo = key << shift, hi = (key + 1) << shift;
        const auto it = std::lower_bound(surface.begin(), surface.end(), lo,
                                         [](const VolumeBlock& b, std::uint64_t k) { return b.key < k; });
        return it != surface.end() && it->key < hi;
    };
    std::vector<SolidCandidate> candidates, stack{{0, 0}};
    while (!stack.empty()) {
        const SolidCandidate node = stack.back();
        stack.pop_back();
        const auto c = octree::mortonDecode(node.key);
        const std::uint32_t s = L - node.level;
        bool disjoint = false, within = true;
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t lo = c[std::size_t(a)] << s, hi = (c[std::size_t(a)] + 1) << s;
            disjoint = disjoint || hi <= region.min[std::size_t(a)] || lo >= region.max[std::size_t(a)];
            within = within && lo >= region.min[std::size_t(a)] && hi <= region.max[std::size_t(a)];
        }
        if (disjoint) continue;
        if (within && !hasSurface(node.level, node.key)) {
            candidates.push_back(node);
        } else if (node.level < L) {
            for (std::uint64_t k = 0; k < 8; ++k) stack.push_back({node.level + 1, (node.key << 3) | k});
        }
    }
    return candidates;
}

// The solid interior of a closed mesh: every candidate node whose centre the inside test puts
// inside becomes a solid block. A mesh the test cannot take is left hollow, unless the user
// asked for --solid on.
void fillSolid(const ingest::TriangleMesh& mesh, const MeshView& view, const SampleOptions& options, const VoxelBox& region,
               octree::SparseVolume& volume, Progress& progress) {
    const WeldedMesh welded = weldByPosition(mesh, view);
    std::unique_ptr<detail::InsideTest> insideTest;
    try {
        insideTest = std::make_unique<detail::InsideTest>(welded.positions, welded.triangles);
    } catch (const std::runtime_error& e) {
        if (options.solid == SolidMode::On) throw InputError("<mesh>", std::string("--solid on: ") + e.what());
    }
    if (!insideTest) return;
    const std::uint32_t n = options.resolution, L = volume.info.levels;
    const double rhoSolid = options.solidDensity > 0 ? options.solidDensity : 16.0 * double(n);
    volume.info.solidDensity = float(rhoSolid);
    const octree::VoxelData solidData = solidVoxel(view, mesh.triangles.size(), rhoSolid);
    const std::vector<SolidCandidate> candidates = solidCandidates(volume.blocks, L, region);
    std::vector<std::uint8_t> isInside(candidates.size(), 0);
    progress.start("sample: solid", candidates.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 64), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            const auto c = octree::mortonDecode(candidates[i].key);
            const double size = std::ldexp(1.0, int(L - candidates[i].level));
            const Vec3 centre((c[0] + 0.5) * size, (c[1] + 0.5) * size, (c[2] + 0.5) * size);
            isInside[i] = insideTest->inside(centre) ? 1 : 0;
        }
        progress.advance(range.size());
    });
    progress.finish();
    for (std::size_t i = 0; i < candidates.size(); ++i)
        if (isInside[i])
            volume.blocks.push_back(VolumeBlock{candidates[i].key, std::uint8_t(candidates[i].level), octree::kBlockSolid, solidData});
    volume.sortBlocks();
}

}  // namespace

octree::SparseVolume sampleMesh(const ingest::TriangleMesh& mesh, const SampleOptions& options, Progress& progress) {
    checkOptions(options);
    if (options.maxMemoryBytes > 0)
        checkMemoryEstimate(options.source, "sampling at " + std::to_string(options.resolution) + "^3",
                            estimateSampleMemory(mesh, options), options.maxMemoryBytes);
    for (const auto& t : mesh.triangles)
        if (t[0] >= mesh.positions.size() || t[1] >= mesh.positions.size() || t[2] >= mesh.positions.size())
            throw std::invalid_argument("triangle index out of range");

    const std::uint32_t n = options.resolution;
    const std::uint32_t L = std::uint32_t(std::countr_zero(n));
    octree::SparseVolume volume;
    volume.info.levels = L;
    volume.info.cyclic = options.cyclic;
    referenceMapping(mesh, options.bounds, volume.info.scale, volume.info.offset);
    const SourceView source(mesh, volume.info.offset, volume.info.scale, n);
    const MeshView& view = source.view;
    const std::vector<Vec3>& normals = source.normals;
    const std::size_t triangleCount = mesh.triangles.size();
    volume.info.sourceTriangles = triangleCount;
    volume.info.sourceArea = source.totalArea / (double(n) * double(n));

    const bool regionOnly = options.region.has_value();
    const VoxelBox region = regionOnly ? *options.region : VoxelBox{{0, 0, 0}, {n, n, n}};
    const std::uint64_t threshold = fitThreshold(source.totalArea, options.fitErrorSamples);
    SurfaceResult surface = regionOnly ? sampleSurface(view, normals, n, options.cyclic, RegionFilter{region, options.cyclic}, threshold, progress)
                                       : sampleSurface(view, normals, n, options.cyclic, AllVoxels{}, threshold, progress);
    volume.blocks = std::move(surface.voxels);
    volume.info.fitError = surface.fit;

    // Solid interior.
    const bool solid = options.solid == SolidMode::On || (options.solid == SolidMode::Auto && mesh.closed && !options.cyclic);
    if (options.solid == SolidMode::On && !mesh.closed)
        throw InputError("<mesh>", "--solid on needs a closed (watertight) mesh");
    if (solid && triangleCount > 0) fillSolid(mesh, view, options, region, volume, progress);
    return volume;
}

}  // namespace vtex::sampler
