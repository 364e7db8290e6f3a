/// @file
/// @brief Random sparse volumes for the octree tests: random voxels (density, ellipsoid,
/// albedo) at random distinct positions of the finest level, and scattered voxels over a slab.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/voxel.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <random>
#include <vector>

namespace vtex::octree::test {

inline VoxelData randomVoxel(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.05, 1.0);
    VoxelData d;
    d.density = float(u(rng) * 10);
    Eigen::Quaterniond q(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    packEllipsoid(Ellipsoid::fromAxes(q.normalized().toRotationMatrix(), Vec3(u(rng), u(rng), u(rng))), d);
    d.albedo = {float(u(rng)), float(u(rng)), float(u(rng))};
    return d;
}

/// Up to `count` random voxels of a 2^levels grid (duplicates dropped); the header's
/// sourceTriangles is the seed, so two volumes' headers differ.
inline SparseVolume randomVolume(std::uint32_t levels, std::size_t count, unsigned seed) {
    std::mt19937 rng(seed);
    SparseVolume v;
    v.info.levels = levels;
    v.info.sourceTriangles = seed;
    std::uniform_int_distribution<std::uint32_t> c(0, (1u << levels) - 1);
    std::vector<std::uint64_t> keys;
    for (std::size_t i = 0; i < count; ++i) keys.push_back(mortonEncode(c(rng), c(rng), c(rng)));
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (const auto k : keys) v.blocks.push_back(VolumeBlock{k, std::uint8_t(levels), 0, randomVoxel(rng)});
    return v;
}

/// An octree of 2^levels voxels a side: scattered voxels, each position kept with probability
/// `fraction` and made by voxel(x, y, z, rng), over a solid isotropic slab of density 3 at z in
/// [slabBegin, slabEnd), whose constant blocks the compression stores as leaves above the finest
/// level.
template <class MakeVoxel>
Octree scatteredOverSlab(std::uint32_t levels, std::uint32_t slabBegin, std::uint32_t slabEnd, float fraction,
                         unsigned seed, MakeVoxel&& voxel) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    SparseVolume v;
    v.info.levels = levels;
    const std::uint32_t n = 1u << levels;
    for (std::uint32_t z = 0; z < n; ++z)
        for (std::uint32_t y = 0; y < n; ++y)
            for (std::uint32_t x = 0; x < n; ++x) {
                const bool slab = z >= slabBegin && z < slabEnd;
                if (!slab && u(rng) > fraction) continue;
                VoxelData d;
                if (slab) {
                    d.density = 3.0f;
                    packIsotropic(d);
                    d.albedo = {0.5f, 0.5f, 0.5f};
                } else {
                    d = voxel(x, y, z, rng);
                }
                v.blocks.push_back(VolumeBlock{mortonEncode(x, y, z), std::uint8_t(levels), 0, d});
            }
    v.sortBlocks();
    NullProgress progress;
    return buildOctree(v, BuildOptions{}, progress);
}

}  // namespace vtex::octree::test
