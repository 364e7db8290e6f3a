/// @file
/// @brief A small texel for the export tests: a constant solid block large enough to be an
/// OpenVDB tile, a small one that is not, and rotated anisotropic surface voxels.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/octree/octree.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

namespace vtex::test {

/// Level 5 (32³). Finest x in [0, 16): a solid block at level 1 (one leaf standing for 16³
/// voxels); x in [28, 32), y, z in [0, 4): a solid block at level 3 (4³ voxels); x in [16, 28):
/// about 600 surface voxels with random rotations, shapes, densities and albedos.
inline octree::SparseVolume exportTestVolume() {
    using namespace octree;
    SparseVolume v;
    v.info.levels = 5;
    v.info.solidDensity = 7.5f;
    VoxelData solid;
    solid.density = 7.5f;
    packIsotropic(solid);
    solid.albedo = {0.25f, 0.5f, 0.75f};
    v.blocks.push_back(VolumeBlock{mortonEncode(0, 0, 0), 1, kBlockSolid, solid});
    VoxelData small = solid;
    small.albedo = {0.9f, 0.1f, 0.2f};
    v.blocks.push_back(VolumeBlock{mortonEncode(7, 0, 0), 3, kBlockSolid, small});

    std::mt19937 rng(17);
    std::uniform_real_distribution<double> u(0.05, 1.0);
    std::uniform_int_distribution<std::uint32_t> x(16, 27), yz(0, 31);
    for (int i = 0; i < 700; ++i) {
        VoxelData d;
        d.density = float(u(rng) * 20);
        const Eigen::Quaterniond q(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
        packEllipsoid(Ellipsoid::fromAxes(q.normalized().toRotationMatrix(), Vec3(u(rng), 0.3 * u(rng), u(rng))), d);
        d.albedo = {float(u(rng)), float(u(rng)), float(u(rng))};
        v.blocks.push_back(VolumeBlock{mortonEncode(x(rng), yz(rng), yz(rng)), 5, 0, d});
    }
    // Random keys repeat: keep one block per voxel.
    v.sortBlocks();
    std::vector<VolumeBlock> unique;
    for (const VolumeBlock& b : v.blocks)
        if (unique.empty() || v.finestKey(unique.back()) != v.finestKey(b) || unique.back().level != b.level)
            unique.push_back(b);
    v.blocks = std::move(unique);
    return v;
}

inline octree::Octree exportTestOctree() {
    NullProgress progress;
    return octree::buildOctree(exportTestVolume(), {}, progress);
}

}  // namespace vtex::test
