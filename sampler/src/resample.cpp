// The partial recompute (sampler.h, updateRegion): the voxels of a region re-sampled, the others
// kept from the earlier volume, the fit error measured again on the voxels a full sampling would
// measure it on.
#include "surface_pass.h"

#include <vtex/core/error.h>
#include <vtex/sampler/sampler.h>

#include <algorithm>
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

}  // namespace

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
