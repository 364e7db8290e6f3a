// The partial recompute (sampler.h, updateRegion): the voxels of a region re-sampled, the others
// kept from the earlier volume, the fit error measured again on the voxels a full sampling would
// measure it on.
#include "surface_pass.h"

#include <vtex/core/error.h>
#include <vtex/sampler/sampler.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <string>
#include <unordered_set>

namespace vtex::sampler {
namespace {

using namespace detail;

// The voxels of a sorted key list; a triangle is clipped only if its bounds (voxel units) reach
// a bin of 8³ voxels that holds one of them.
class SelectedVoxels {
public:
    SelectedVoxels(std::vector<std::uint64_t> keys, std::uint32_t n, bool cyclic)
        : mKeys(std::move(keys)), mN(n), mCyclic(cyclic) {
        for (const std::uint64_t key : mKeys) {
            const auto c = octree::mortonDecode(key);
            mBins.insert(binKey(c[0] >> kBinShift, c[1] >> kBinShift, c[2] >> kBinShift));
        }
    }

    bool triangle(const Vec3& lo, const Vec3& hi) const {
        std::int64_t from[3], to[3];
        for (int a = 0; a < 3; ++a) {
            // Wrapped pieces of a cyclic texel may land anywhere in x and y: clip such triangles.
            if (mCyclic && a < 2 && (lo[a] < 0 || hi[a] >= double(mN))) return true;
            // Voxel v holds a piece only if v ≤ hi and v + 1 ≥ lo.
            from[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(lo[a])) - 1, 0, std::int64_t(mN) - 1) >> kBinShift;
            to[a] = std::clamp<std::int64_t>(std::int64_t(std::floor(hi[a])), 0, std::int64_t(mN) - 1) >> kBinShift;
        }
        if ((to[0] - from[0] + 1) * (to[1] - from[1] + 1) * (to[2] - from[2] + 1) > 512) return true;
        for (std::int64_t z = from[2]; z <= to[2]; ++z)
            for (std::int64_t y = from[1]; y <= to[1]; ++y)
                for (std::int64_t x = from[0]; x <= to[0]; ++x)
                    if (mBins.count(binKey(std::uint32_t(x), std::uint32_t(y), std::uint32_t(z)))) return true;
        return false;
    }
    bool voxel(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
        return std::binary_search(mKeys.begin(), mKeys.end(), octree::mortonEncode(x, y, z));
    }

private:
    static constexpr int kBinShift = 3;
    static std::uint64_t binKey(std::uint32_t x, std::uint32_t y, std::uint32_t z) { return octree::mortonEncode(x, y, z); }
    std::vector<std::uint64_t> mKeys;
    std::uint32_t mN;
    bool mCyclic;
    std::unordered_set<std::uint64_t> mBins;
};

// Refuses an earlier volume that a full sampling with `options` would not have made.
void checkCompatible(const octree::SparseVolume& old, const octree::SparseVolume& part, const SampleOptions& options,
                     const std::filesystem::path& oldFile) {
    if (old.info.levels != part.info.levels)
        throw InputError(oldFile, "sampled at " + std::to_string(1u << old.info.levels) + "^3, not " +
                                      std::to_string(options.resolution) + "^3: cannot be updated at this resolution");
    if (old.info.cyclic != part.info.cyclic)
        throw InputError(oldFile, std::string("sampled ") + (old.info.cyclic ? "with" : "without") +
                                      " --cyclic: cannot be updated " + (part.info.cyclic ? "with" : "without") + " it");
    if (old.info.scale != part.info.scale || old.info.offset != part.info.offset)
        throw InputError(oldFile, "its mesh was mapped to the unit cube otherwise (another --bounds, or the edit moved the "
                                  "mesh's bounds under --bounds fit): re-sample in full");
    const auto solid = [](const octree::SparseVolume& v) {
        return v.info.solidDensity != 0 ||
               std::any_of(v.blocks.begin(), v.blocks.end(), [](const octree::VolumeBlock& b) { return b.isSolid(); });
    };
    if (solid(old) || solid(part))
        throw InputError(oldFile, "has a solid interior, which a partial update does not classify again: re-sample in full");
}

// Everything of a triangle that the sampling reads: its corners, their texture coordinates and its
// material (the materials and textures themselves are compared whole).
bool sameTriangle(const ingest::TriangleMesh& a, std::size_t i, const ingest::TriangleMesh& b, std::size_t j) {
    const std::uint32_t ma = a.triangleMaterials.empty() ? 0 : a.triangleMaterials[i];
    const std::uint32_t mb = b.triangleMaterials.empty() ? 0 : b.triangleMaterials[j];
    if (ma != mb) return false;
    const bool uvs = a.uvs.size() == a.positions.size();
    for (int k = 0; k < 3; ++k) {
        const std::uint32_t u = a.triangles[i][std::size_t(k)], v = b.triangles[j][std::size_t(k)];
        if (a.positions[u] != b.positions[v] || (uvs && a.uvs[u] != b.uvs[v])) return false;
    }
    return true;
}

bool sameLooks(const ingest::TriangleMesh& a, const ingest::TriangleMesh& b) {
    const auto sameMaterial = [](const ingest::Material& x, const ingest::Material& y) {
        return x.baseColorFactor == y.baseColorFactor && x.baseColorTexture == y.baseColorTexture;
    };
    const auto sameImage = [](const ingest::Image& x, const ingest::Image& y) {
        return x.width == y.width && x.height == y.height && x.rgba == y.rgba;
    };
    return (a.uvs.size() == a.positions.size()) == (b.uvs.size() == b.positions.size()) &&
           std::equal(a.materials.begin(), a.materials.end(), b.materials.begin(), b.materials.end(), sameMaterial) &&
           std::equal(a.textures.begin(), a.textures.end(), b.textures.begin(), b.textures.end(), sameImage);
}

// Grows [lo, hi] (voxel units) by triangle t of `mesh` under the mapping.
void growBounds(const ingest::TriangleMesh& mesh, std::size_t t, double scale, const std::array<double, 3>& offset,
                double n, Vec3& lo, Vec3& hi) {
    for (const std::uint32_t v : mesh.triangles[t]) {
        if (v >= mesh.positions.size()) continue;  // sampleMesh refuses the mesh
        for (int a = 0; a < 3; ++a) {
            const double p = (double(mesh.positions[v][a]) * scale + offset[std::size_t(a)]) * n;
            lo[a] = std::min(lo[a], p);
            hi[a] = std::max(hi[a], p);
        }
    }
}

}  // namespace

std::optional<octree::VoxelBox> changedRegion(const ingest::TriangleMesh& before, const ingest::TriangleMesh& after,
                                              const SampleOptions& options) {
    double scaleBefore, scaleAfter;
    std::array<double, 3> offsetBefore, offsetAfter;
    referenceMapping(before, options.bounds, scaleBefore, offsetBefore);
    referenceMapping(after, options.bounds, scaleAfter, offsetAfter);
    if (scaleBefore != scaleAfter || offsetBefore != offsetAfter || !sameLooks(before, after)) return std::nullopt;
    // The triangles that differ: index by index when the counts agree (an edit that moves
    // vertices), else all but the common prefix and suffix (one block inserted or removed). Either
    // way the others keep their order, so every voxel they alone touch sums the same pieces in
    // the same order.
    const std::size_t nb = before.triangles.size(), na = after.triangles.size();
    std::vector<std::size_t> changedBefore, changedAfter;
    if (nb == na) {
        for (std::size_t t = 0; t < nb; ++t)
            if (!sameTriangle(before, t, after, t)) {
                changedBefore.push_back(t);
                changedAfter.push_back(t);
            }
    } else {
        std::size_t prefix = 0, suffix = 0;
        while (prefix < std::min(nb, na) && sameTriangle(before, prefix, after, prefix)) ++prefix;
        while (suffix < std::min(nb, na) - prefix && sameTriangle(before, nb - 1 - suffix, after, na - 1 - suffix)) ++suffix;
        for (std::size_t t = prefix; t < nb - suffix; ++t) changedBefore.push_back(t);
        for (std::size_t t = prefix; t < na - suffix; ++t) changedAfter.push_back(t);
    }
    const std::uint32_t n = options.resolution;
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const std::size_t t : changedBefore) growBounds(before, t, scaleBefore, offsetBefore, double(n), lo, hi);
    for (const std::size_t t : changedAfter) growBounds(after, t, scaleAfter, offsetAfter, double(n), lo, hi);
    octree::VoxelBox box;
    if (changedBefore.empty() && changedAfter.empty()) return box;
    for (int a = 0; a < 3; ++a) {
        // Voxel v holds a piece of a triangle only if v ≤ its upper bound and v + 1 ≥ its lower
        // bound; a cyclic texel wraps pieces beyond [0, N) in x and y to the far side.
        const bool wraps = options.cyclic && a < 2 && (lo[a] < 0 || hi[a] >= double(n));
        if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || wraps) {
            box.min[std::size_t(a)] = 0;
            box.max[std::size_t(a)] = n;
            continue;
        }
        box.min[std::size_t(a)] = std::uint32_t(std::clamp(std::floor(lo[a]) - 1, 0.0, double(n)));
        box.max[std::size_t(a)] = std::uint32_t(std::clamp(std::floor(hi[a]) + 1, 0.0, double(n)));
    }
    return box;
}

octree::SparseVolume updateRegion(const ingest::TriangleMesh& mesh, const octree::SparseVolume& old,
                                  const SampleOptions& options, const std::filesystem::path& oldFile, Progress& progress) {
    if (!options.region) throw std::invalid_argument("updateRegion needs a region");
    const VoxelBox region = *options.region;
    octree::SparseVolume merged = sampleMesh(mesh, options, progress);
    checkCompatible(old, merged, options, oldFile);
    // Outside the region the earlier voxels (all on the finest level: no solid blocks). Both lists
    // are in key order and disjoint: a merge keeps it without sorting 10⁶ blocks again.
    std::vector<octree::VolumeBlock> kept;
    kept.reserve(old.blocks.size());
    for (const auto& block : old.blocks) {
        const auto c = octree::mortonDecode(block.key);
        if (!region.contains(c[0], c[1], c[2])) kept.push_back(block);
    }
    std::vector<octree::VolumeBlock> inside = std::move(merged.blocks);
    merged.blocks.clear();
    merged.blocks.reserve(kept.size() + inside.size());
    const auto byKey = [](const octree::VolumeBlock& a, const octree::VolumeBlock& b) { return a.key < b.key; };
    std::merge(kept.begin(), kept.end(), inside.begin(), inside.end(), std::back_inserter(merged.blocks), byKey);
    // The fit error over the voxels a full sampling measures it on, from their pieces alone.
    const std::uint32_t n = options.resolution;
    const SourceView source(mesh, merged.info.offset, merged.info.scale, n);
    const std::uint64_t threshold = fitThreshold(source.totalArea, options.fitErrorSamples);
    std::vector<std::uint64_t> measured;
    for (const auto& block : merged.blocks)
        if (mix64(block.key) <= threshold) measured.push_back(block.key);
    const SelectedVoxels selected(std::move(measured), n, options.cyclic);
    merged.info.fitError = sampleSurface(source.view, source.normals, n, options.cyclic, selected, threshold, progress).fit;
    return merged;
}

}  // namespace vtex::sampler
