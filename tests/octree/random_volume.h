/// @file
/// @brief Random sparse volumes for the octree tests: random voxels (density, ellipsoid,
/// albedo) at random distinct positions of the finest level.
#pragma once

#include <vtex/octree/octree.h>

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

}  // namespace vtex::octree::test
