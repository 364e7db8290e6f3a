// The partial recompute (updateRegion): an edited source re-sampled only where it changed equals
// a full re-sampling bit for bit, fit error included; earlier volumes sampled otherwise refused.
#include "meshes.h"

#include <vtex/core/error.h>
#include <vtex/octree/octree.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace vtex::sampler {
namespace {

// The bush pattern writes each leaf as 9 vertices (centre, 8 on the rim) and 8 triangles.
constexpr std::size_t kLeafVertices = 9;

struct Edit {
    ingest::TriangleMesh mesh;
    octree::VoxelBox region;  ///< the voxels the moved leaves touch, before and after
};

// Moves the `count` leaves whose centres lie nearest to `at` by `offset` (reference units, the
// bush lies in the unit cube), and the region of an N³ grid their triangles touch then and now:
// voxel v holds a piece of a triangle only if v ≤ its upper bound and v + 1 ≥ its lower bound.
Edit moveLeaves(const ingest::TriangleMesh& bush, std::size_t count, const Eigen::Vector3f& at,
                const Eigen::Vector3f& offset, std::uint32_t n) {
    const std::size_t leaves = bush.positions.size() / kLeafVertices;
    std::vector<std::size_t> order(leaves);
    for (std::size_t l = 0; l < leaves; ++l) order[l] = l;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return (bush.positions[a * kLeafVertices] - at).norm() < (bush.positions[b * kLeafVertices] - at).norm();
    });
    Edit edit{bush, {}};
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = Eigen::Vector3d::Constant(-INFINITY);
    for (std::size_t i = 0; i < count; ++i)
        for (std::size_t v = order[i] * kLeafVertices; v < (order[i] + 1) * kLeafVertices; ++v) {
            edit.mesh.positions[v] += offset;
            for (const Eigen::Vector3f& p : {bush.positions[v], edit.mesh.positions[v]}) {
                lo = lo.cwiseMin(p.cast<double>() * n);
                hi = hi.cwiseMax(p.cast<double>() * n);
            }
        }
    for (int a = 0; a < 3; ++a) {
        edit.region.min[std::size_t(a)] = std::uint32_t(std::clamp(std::floor(lo[a]) - 1, 0.0, double(n)));
        edit.region.max[std::size_t(a)] = std::uint32_t(std::clamp(std::floor(hi[a]) + 1, 0.0, double(n)));
    }
    return edit;
}

SampleOptions optionsFor(std::uint32_t n) {
    SampleOptions o;
    o.resolution = n;
    return o;
}

TEST(UpdateRegion, OnePercentOfTheBushMovedEqualsAFullResamplingBitForBit) {
    const auto bush = makePattern("bush", {});
    NullProgress progress;
    for (const std::uint32_t n : {64u, 128u}) {
        const Edit edit = moveLeaves(bush, 20, Eigen::Vector3f(0.5f, 0.55f, 0.9f), Eigen::Vector3f(0.004f, -0.003f, 0.002f), n);
        const octree::SparseVolume before = sampleMesh(bush, optionsFor(n), progress);
        const octree::SparseVolume full = sampleMesh(edit.mesh, optionsFor(n), progress);
        SampleOptions options = optionsFor(n);
        options.region = edit.region;
        const octree::SparseVolume updated = updateRegion(edit.mesh, before, options, "before.vtl", progress);
        ASSERT_NE(before.blocks, full.blocks) << n;  // the edit changed something
        EXPECT_EQ(updated.blocks, full.blocks) << n;
        EXPECT_EQ(updated.info, full.info) << n;
        EXPECT_EQ(octree::serializeVtl(updated), octree::serializeVtl(full)) << n;
        // The fit error is measured on about as many voxels as asked.
        EXPECT_GT(full.info.fitError.samples, 2000u);
        EXPECT_LT(full.info.fitError.samples, 8192u);
        // The region is a small part of the volume, and it holds every voxel that changed.
        std::uint64_t regionVoxels = 1;
        for (int a = 0; a < 3; ++a) regionVoxels *= edit.region.max[std::size_t(a)] - edit.region.min[std::size_t(a)];
        EXPECT_LT(regionVoxels, std::uint64_t(n) * n * n / 50) << n;
    }
}

TEST(UpdateRegion, ARegionTooSmallForTheEditIsNotTheFullSampling) {
    // The property the equality rests on is the region's: leaving out voxels the edit touches
    // keeps their old values, which the comparison must see.
    const auto bush = makePattern("bush", {});
    NullProgress progress;
    const Edit edit = moveLeaves(bush, 20, Eigen::Vector3f(0.5f, 0.55f, 0.9f), Eigen::Vector3f(0.004f, -0.003f, 0.002f), 64);
    const auto before = sampleMesh(bush, optionsFor(64), progress);
    SampleOptions options = optionsFor(64);
    options.region = edit.region;
    options.region->max[0] = options.region->min[0] + 1;
    EXPECT_NE(updateRegion(edit.mesh, before, options, "before.vtl", progress).blocks,
              sampleMesh(edit.mesh, optionsFor(64), progress).blocks);
}

TEST(UpdateRegion, AnEarlierVolumeSampledOtherwiseIsRefusedNamingIt) {
    const auto bush = makePattern("bush", {});
    NullProgress progress;
    const auto before = sampleMesh(bush, optionsFor(32), progress);
    const auto expectRefused = [&](const SampleOptions& options, const ingest::TriangleMesh& mesh, const char* why) {
        try {
            updateRegion(mesh, before, options, "before.vtl", progress);
            ADD_FAILURE() << why << ": not refused";
        } catch (const InputError& e) {
            EXPECT_EQ(e.file(), "before.vtl") << why;
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    SampleOptions other = optionsFor(64);
    other.region = octree::VoxelBox{{0, 0, 0}, {8, 8, 8}};
    expectRefused(other, bush, "32^3, not 64^3");
    SampleOptions cyclic = optionsFor(32);
    cyclic.cyclic = true;
    cyclic.region = other.region;
    expectRefused(cyclic, bush, "--cyclic");
    SampleOptions fit = optionsFor(32);
    fit.bounds = BoundsMode::Fit;
    fit.region = other.region;
    expectRefused(fit, bush, "mapped to the unit cube otherwise");
    // A closed mesh's interior depends on the whole surface.
    const auto box = test::boxMesh(test::Vec3(0.2, 0.2, 0.2), test::Vec3(0.7, 0.6, 0.5));
    SampleOptions solid = optionsFor(32);
    solid.bounds = BoundsMode::Unit;
    solid.region = other.region;
    SampleOptions full = solid;
    full.region.reset();
    const auto solidBefore = sampleMesh(box, full, progress);
    ASSERT_GT(solidBefore.info.solidDensity, 0.0f);
    try {
        updateRegion(box, solidBefore, solid, "before.vtl", progress);
        ADD_FAILURE() << "solid interior not refused";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("solid interior"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace vtex::sampler
