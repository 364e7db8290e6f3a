// The partial recompute (updateRegion): an edited source re-sampled only where it changed equals
// a full re-sampling bit for bit, fit error included; earlier volumes sampled otherwise refused.
#include "meshes.h"

#include "run_vtex.h"

#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

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

// changedRegion finds the region from the two meshes alone: for moved leaves the one the test
// derives from the leaves it moved; for leaves added or removed one that updateRegion turns into
// the full sampling's bytes; none when the look of the triangles changed.
TEST(UpdateRegion, TheChangedRegionOfTwoMeshesGivesTheFullSampling) {
    const auto bush = makePattern("bush", {});
    NullProgress progress;
    const std::uint32_t n = 64;
    const Edit moved = moveLeaves(bush, 20, Eigen::Vector3f(0.5f, 0.55f, 0.9f), Eigen::Vector3f(0.004f, -0.003f, 0.002f), n);
    EXPECT_EQ(changedRegion(bush, moved.mesh, optionsFor(n)), moved.region);
    EXPECT_EQ(changedRegion(bush, bush, optionsFor(n)), octree::VoxelBox{});
    // 20 leaves fewer from the middle of the list (their triangles too), and 20 more at its end.
    ingest::TriangleMesh fewer = bush, more = bush;
    const auto middle = fewer.triangles.begin() + 8 * 1000;
    fewer.triangles.erase(middle, middle + 8 * 20);
    fewer.triangleMaterials.erase(fewer.triangleMaterials.begin() + 8 * 1000, fewer.triangleMaterials.begin() + 8 * 1020);
    for (std::size_t t = 0; t < 8 * 20; ++t) {
        more.triangles.push_back(bush.triangles[t]);
        for (auto& v : more.triangles.back()) {
            more.positions.push_back(bush.positions[v] + Eigen::Vector3f(0.01f, 0.0f, 0.0f));
            more.normals.push_back(bush.normals[v]);
            if (!bush.uvs.empty()) more.uvs.push_back(bush.uvs[v]);
            v = std::uint32_t(more.positions.size() - 1);
        }
        more.triangleMaterials.push_back(bush.triangleMaterials[t]);
    }
    const auto before = sampleMesh(bush, optionsFor(n), progress);
    const std::vector<const ingest::TriangleMesh*> edits{&moved.mesh, &fewer, &more};
    for (const ingest::TriangleMesh* edited : edits) {
        const auto region = changedRegion(bush, *edited, optionsFor(n));
        ASSERT_TRUE(region.has_value());
        EXPECT_FALSE(region->isEmpty());
        SampleOptions options = optionsFor(n);
        options.region = region;
        const auto full = sampleMesh(*edited, optionsFor(n), progress);
        EXPECT_EQ(octree::serializeVtl(updateRegion(*edited, before, options, "before.vtl", progress)),
                  octree::serializeVtl(full));
    }
    ingest::TriangleMesh recoloured = bush;
    recoloured.materials[0].baseColorFactor.x() *= 0.5f;
    EXPECT_FALSE(changedRegion(bush, recoloured, optionsFor(n)).has_value());
    ingest::TriangleMesh grown = bush;
    grown.positions[0] += Eigen::Vector3f(0.5f, 0.5f, 0.5f);  // out of the unit cube: fitted again
    SampleOptions fit = optionsFor(n);
    EXPECT_FALSE(changedRegion(bush, grown, fit).has_value());
}

// The same through the command line: `vtex sample --update OLD.vtl --region …` writes the bytes
// a full `vtex sample` writes, and `vtex build` of it, in full or `--update OLD.vto`, the same
// .vto; bad regions are bad usage naming the flag, and nothing is written by a refused update.
TEST(UpdateRegionCli, SampleUpdateWritesTheFullSamplingsBytes) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "update_region";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const auto bush = makePattern("bush", {});
    const Edit edit = moveLeaves(bush, 20, Eigen::Vector3f(0.5f, 0.55f, 0.9f), Eigen::Vector3f(0.004f, -0.003f, 0.002f), 64);
    ingest::writeMeshGlb(bush, dir / "old.glb");
    ingest::writeMeshGlb(edit.mesh, dir / "new.glb");
    const auto path = [&](const char* name) { return (dir / name).string(); };
    const auto run = [](std::vector<std::string> args) {
        const auto r = vtex::test::runVtex(args);
        EXPECT_EQ(r.exitStatus, 0) << r.err;
        return r;
    };
    run({"sample", path("old.glb"), "-o", path("old.vtl"), "-r", "64", "-q"});
    run({"sample", path("new.glb"), "-o", path("full.vtl"), "-r", "64", "-q"});
    std::string region;
    for (const auto& v : {edit.region.min, edit.region.max})
        for (const auto c : v) {
            if (!region.empty()) region.push_back(',');
            region.append(std::to_string(c));
        }
    run({"sample", path("new.glb"), "-o", path("updated.vtl"), "--update", path("old.vtl"), "--region", region, "-q"});
    EXPECT_EQ(vtex::test::readText(dir / "updated.vtl"), vtex::test::readText(dir / "full.vtl"));
    EXPECT_NE(vtex::test::readText(dir / "old.vtl"), vtex::test::readText(dir / "full.vtl"));
    run({"build", path("full.vtl"), "-o", path("full.vto"), "-q"});
    run({"build", path("updated.vtl"), "-o", path("updated.vto"), "-q"});
    EXPECT_EQ(vtex::test::readText(dir / "updated.vto"), vtex::test::readText(dir / "full.vto"));
    // `vtex build --update`: the earlier octree's builder resumed, the region filtered again.
    run({"build", path("old.vtl"), "-o", path("old.vto"), "-q"});
    const auto rebuilt = run({"build", path("updated.vtl"), "-o", path("rebuilt.vto"), "--update", path("old.vto"),
                              "--region", region});
    EXPECT_NE(rebuilt.err.find("updated"), std::string::npos) << rebuilt.err;
    EXPECT_EQ(vtex::test::readText(dir / "rebuilt.vto"), vtex::test::readText(dir / "full.vto"));
    const auto otherFilter = vtex::test::runVtex({"build", path("updated.vtl"), "-o", path("bad.vto"), "--update",
                                                  path("old.vto"), "--region", region, "--filter", "neyret"});
    EXPECT_EQ(otherFilter.exitStatus, 3) << otherFilter.err;
    EXPECT_NE(otherFilter.err.find("old.vto"), std::string::npos) << otherFilter.err;
    const auto badRegion = vtex::test::runVtex({"build", path("updated.vtl"), "-o", path("bad.vto"), "--update",
                                                path("old.vto"), "--region", "0,0,0,65,1,1"});
    EXPECT_EQ(badRegion.exitStatus, 2) << badRegion.err;
    EXPECT_NE(badRegion.err.find("--region"), std::string::npos) << badRegion.err;
    // The earlier octree is read whole and checked: a damaged level no region needs still fails.
    std::string damaged = vtex::test::readText(dir / "old.vto");
    damaged[damaged.size() - 5] = char(damaged[damaged.size() - 5] ^ 0x01);
    std::ofstream(dir / "old.vto", std::ios::binary | std::ios::trunc) << damaged;
    const auto corrupt = vtex::test::runVtex({"build", path("updated.vtl"), "-o", path("bad.vto"), "--update",
                                              path("old.vto"), "--region", region});
    EXPECT_EQ(corrupt.exitStatus, 3) << corrupt.err;
    EXPECT_FALSE(fs::exists(dir / "bad.vto"));

    for (const std::string bad : {"0,0,0,65,1,1", "3,0,0,3,1,1", "1,2,3", "1,2,3,4,5,x", "-1,0,0,2,2,2"}) {
        const auto r = vtex::test::runVtex({"sample", path("new.glb"), "-o", path("bad.vtl"), "--update", path("old.vtl"),
                                      "--region", bad});
        EXPECT_EQ(r.exitStatus, 2) << bad << ": " << r.err;
        EXPECT_NE(r.err.find("--region"), std::string::npos) << r.err;
    }
    const auto alone = vtex::test::runVtex({"sample", path("new.glb"), "-o", path("bad.vtl"), "--region", region});
    EXPECT_EQ(alone.exitStatus, 2) << alone.err;
    const auto other = vtex::test::runVtex({"sample", path("new.glb"), "-o", path("bad.vtl"), "--update", path("old.vtl"),
                                      "--region", "0,0,0,8,8,8", "-r", "32"});
    EXPECT_EQ(other.exitStatus, 3) << other.err;
    EXPECT_NE(other.err.find("old.vtl"), std::string::npos) << other.err;
    EXPECT_FALSE(fs::exists(dir / "bad.vtl"));
    const auto inPlace = vtex::test::runVtex({"sample", path("new.glb"), "-o", path("old.vtl"), "--update", path("old.vtl"),
                                        "--region", region});
    EXPECT_EQ(inPlace.exitStatus, 3) << inPlace.err;
    EXPECT_NE(vtex::test::readText(dir / "old.vtl"), vtex::test::readText(dir / "full.vtl"));  // left as it was
}

}  // namespace
}  // namespace vtex::sampler
