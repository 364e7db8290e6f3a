// `vtex run` with an edited source: the sample stage re-samples only the region the changed
// triangles touch (sampler::changedRegion, updateRegion), the build stage filters again only the
// region's ancestors (OctreeBuilder::resume), and the volume, the octree and the image are the
// bytes a run from scratch makes.
#include "run_vtex.h"

#include <vtex/ingest/ingest.h>
#include <vtex/pipelines/pipeline.h>
#include <vtex/sampler/patterns.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace {

// A project: the bush as a file source, sampled at 64³, on one quad seen from near enough that
// the render uses every level (the texel is sampled at its full resolution).
fs::path makeBushProject(const std::string& name, const vtex::ingest::TriangleMesh& bush) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "partial" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    vtex::ingest::writeMeshGlb(bush, dir / "bush.glb");
    std::ofstream(dir / "quad.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    std::ofstream(dir / "scene.toml") << "[camera]\nposition = [0.5, -0.6, 1.2]\nlook_at = [0.5, 0.5, 0.5]\nwidth = 64\n"
                                         "height = 48\n[[light]]\ntype = \"directional\"\ndirection = [-1, 0.5, -1]\n"
                                         "[[texel]]\nname = \"t\"\nvolume = \"bound.vto\"\n"
                                         "[[surface]]\nmesh = \"quad.obj\"\ntexel = \"t\"\nheight = 1\n";
    std::ofstream(dir / "pipeline.toml") << "[pipeline]\noutput = \"out\"\n[[source]]\nname = \"bush\"\nfile = \"bush.glb\"\n"
                                            "[[texel]]\nname = \"bush\"\nsource = \"bush\"\nresolution = 64\n"
                                            "[[render]]\nname = \"near\"\nscene = \"scene.toml\"\ntexels = { t = \"bush\" }\n";
    return dir;
}

vtex::pipelines::RunReport run(const fs::path& dir) {
    return vtex::pipelines::runPipeline(vtex::pipelines::loadPipeline(dir / "pipeline.toml"), {});
}

nlohmann::json details(const vtex::pipelines::RunReport& report, const std::string& kind) {
    for (const auto& s : report.stages)
        if (s.kind == kind) return nlohmann::json::parse(s.detailsJson.empty() ? "{}" : s.detailsJson);
    return {};
}

// The bush with the 20 leaves (1 %) nearest to a point moved: each leaf is 9 vertices.
vtex::ingest::TriangleMesh movedLeaves(vtex::ingest::TriangleMesh bush) {
    const Eigen::Vector3f at(0.5f, 0.55f, 0.9f);
    std::vector<std::size_t> leaves(bush.positions.size() / 9);
    for (std::size_t l = 0; l < leaves.size(); ++l) leaves[l] = l;
    std::sort(leaves.begin(), leaves.end(),
              [&](std::size_t a, std::size_t b) { return (bush.positions[9 * a] - at).norm() < (bush.positions[9 * b] - at).norm(); });
    for (std::size_t i = 0; i < 20; ++i)
        for (std::size_t v = 9 * leaves[i]; v < 9 * leaves[i] + 9; ++v) bush.positions[v] += Eigen::Vector3f(0.004f, -0.003f, 0.002f);
    return bush;
}

TEST(PartialSample, AnEditedSourceIsResampledOnlyWhereItChangedAndGivesARunFromScratchsBytes) {
    const auto bush = vtex::sampler::makePattern("bush", {});
    const auto edited = movedLeaves(bush);
    const fs::path dir = makeBushProject("edited", bush);
    ASSERT_TRUE(run(dir).succeeded());
    const std::string before = vtex::test::readText(dir / "out" / "samples" / "bush.vtl");
    EXPECT_TRUE(details(run(dir), "sample")["updated_region"].is_null());  // cached: the first run's, in full

    vtex::ingest::writeMeshGlb(edited, dir / "bush.glb");
    const auto report = run(dir);
    ASSERT_TRUE(report.succeeded());
    const auto sample = details(report, "sample");
    ASSERT_TRUE(sample["updated_region"].is_array()) << sample.dump();
    const auto& r = sample["updated_region"];
    const double share = double(r[3].get<int>() - r[0].get<int>()) * (r[4].get<int>() - r[1].get<int>()) *
                         (r[5].get<int>() - r[2].get<int>()) / (64.0 * 64 * 64);
    EXPECT_LT(share, 0.02) << sample.dump();

    const fs::path fresh = makeBushProject("fresh", edited);
    ASSERT_TRUE(run(fresh).succeeded());
    const std::string after = vtex::test::readText(dir / "out" / "samples" / "bush.vtl");
    EXPECT_NE(after, before);
    EXPECT_EQ(after, vtex::test::readText(fresh / "out" / "samples" / "bush.vtl"));
    EXPECT_EQ(vtex::test::readText(dir / "out" / "builds" / "bush.vto"),
              vtex::test::readText(fresh / "out" / "builds" / "bush.vto"));
    EXPECT_EQ(vtex::test::readText(dir / "out" / "renders" / "near.exr"),
              vtex::test::readText(fresh / "out" / "renders" / "near.exr"));

    // A damaged earlier volume is not started from: the stage samples in full, the same bytes.
    vtex::ingest::writeMeshGlb(bush, dir / "bush.glb");
    ASSERT_TRUE(run(dir).succeeded());
    std::ofstream(dir / "out" / "samples" / "bush.vtl", std::ios::binary | std::ios::app) << "x";
    vtex::ingest::writeMeshGlb(edited, dir / "bush.glb");
    const auto damaged = run(dir);
    ASSERT_TRUE(damaged.succeeded());
    EXPECT_TRUE(details(damaged, "sample")["updated_region"].is_null());
    EXPECT_EQ(vtex::test::readText(dir / "out" / "samples" / "bush.vtl"), after);
}

}  // namespace
