// Renders read of a .vto only what they use (octree::openVto): a far view of a 256³ bush reads
// its coarse levels alone and draws the same image, byte for byte, as the tree read whole; the
// reference reads the header alone.
#include "fixtures.h"

#include <vtex/octree/density_profile.h>
#include <vtex/octree/octree.h>
#include <vtex/render/reference.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include "../../octree/src/container.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace vtex::render;
using namespace vtex::render::test;
namespace fs = std::filesystem;

namespace {

struct BushFile {
    fs::path path;
    std::shared_ptr<const vtex::ingest::TriangleMesh> mesh;
    /// Bytes read once the header and levels 0 … ℓ are: prefix[ℓ + 1]; prefix[0] the header alone.
    std::vector<std::uint64_t> prefix;
};

const BushFile& bushFile() {
    static const BushFile file = [] {
        BushFile f;
        f.mesh = std::make_shared<const vtex::ingest::TriangleMesh>(vtex::sampler::makePattern("bush", {}));
        vtex::sampler::SampleOptions sampling;
        sampling.resolution = 256;
        vtex::NullProgress progress;
        const auto tree = vtex::octree::buildOctree(vtex::sampler::sampleMesh(*f.mesh, sampling, progress), {}, progress);
        f.path = fs::path(VTEX_TEST_TMP) / "lazy_levels" / "bush256.vto";
        fs::create_directories(f.path.parent_path());
        vtex::octree::writeVto(tree, f.path);
        // The section sizes from the serialised bytes: header and table, HEAD, STAT, PROF (what
        // openVto reads at once), then LV00 …
        const std::string bytes = vtex::octree::serializeVto(tree);
        vtex::octree::detail::ByteReader count(std::string_view(bytes).substr(12, 4));
        const std::uint32_t sections = count.u32();
        std::uint64_t sum = vtex::octree::detail::kHeaderSize + vtex::octree::detail::kTableEntrySize * sections;
        for (std::uint32_t i = 0; i < sections; ++i) {
            const std::size_t at = vtex::octree::detail::kHeaderSize + vtex::octree::detail::kTableEntrySize * i;
            const std::string_view tag = std::string_view(bytes).substr(at, 4);
            if (tag.substr(0, 2) == "LV") f.prefix.push_back(sum);  // before each level: the header, then levels 0 … ℓ − 1
            vtex::octree::detail::ByteReader r(std::string_view(bytes).substr(at + 16, 8));
            sum += r.u64();
        }
        f.prefix.push_back(sum);
        return f;
    }();
    return file;
}

// The bush field's ground (20×20 unit quads) from `eye`, the texel read from its file (lazy) or
// given read whole (eager).
Scene bushField(const Eigen::Vector3d& eye, bool lazy, int width, int height) {
    Scene scene = baseScene(eye, Eigen::Vector3d(0, 0, 0.5), 40, width);
    scene.camera.height = height;
    scene.lights[0].direction = Eigen::Vector3d(-1, -0.5, -1).normalized();
    TexelDef t;
    t.name = "bush";
    if (lazy) t.volume = bushFile().path;
    else t.octree = std::make_shared<const vtex::octree::Octree>(vtex::octree::readVto(bushFile().path));
    t.material.specular = Color::Zero();
    scene.texels.push_back(t);
    addSurface(scene, gridMesh(-10, -10, 10, 10, 0, 20), 0, 1.0);
    return scene;
}

// The deepest level whose section `stats` says was read: levels are read whole and in order, so
// the bytes read are the header and levels 0 … ℓ; −2 if they are no such sum.
int deepestLevelRead(const RenderStats& stats) {
    const auto& prefix = bushFile().prefix;
    const auto at = std::find(prefix.begin(), prefix.end(), stats.vtoBytesRead);
    return at == prefix.end() ? -2 : int(at - prefix.begin()) - 1;
}

int deepestLevelMarched(const RenderStats& stats) {
    int deepest = -1;
    for (std::size_t l = 0; l < stats.levelHistogram.size(); ++l)
        if (stats.levelHistogram[l] > 0) deepest = int(l);
    return deepest;
}

TEST(LazyLevels, AFarViewReadsOnlyItsCoarseLevelsAndDrawsTheImageOfTheTreeReadWhole) {
    const auto& file = bushFile();
    const std::uint64_t fileSize = fs::file_size(file.path);
    ASSERT_EQ(file.prefix.back(), fileSize);
    const Eigen::Vector3d far(36.725582, -63.610577, 42.907051);  // bench/bush_field.py, 85 units
    const RenderResult lazy = renderQuiet(bushField(far, true, 96, 72));
    const RenderResult eager = renderQuiet(bushField(far, false, 96, 72));
    EXPECT_TRUE(sameImageBytes(lazy.image, eager.image));
    EXPECT_EQ(lazy.stats.vtoFileBytes, fileSize);
    EXPECT_EQ(eager.stats.vtoBytesRead, 0u);  // given in memory
    const int deepest = deepestLevelRead(lazy.stats);
    EXPECT_GE(deepest, deepestLevelMarched(lazy.stats));
    EXPECT_GE(deepestLevelMarched(lazy.stats), 1);  // it marched the texel
    // The coarse levels' density profile (octree::DensityProfile) comes with the file (its PROF
    // section), so the view reads no level as deep as the profile's: before that section it read
    // level 6 for the profile alone. The finest two levels, which hold the bulk, are not read.
    EXPECT_LT(deepest, vtex::octree::DensityProfile::kProfileLevel);
    EXPECT_LT(lazy.stats.vtoBytesRead, fileSize / 10);
}

// A texel with its source: the hybrid's faithful levels are measured from the coarsest level
// finer and the measurement stops at the first level past them (texel_runtime.cpp), so the
// far view still reads no level deeper than the mesh level's next (5 and 6 on this bush), not
// the finest two that hold nearly all the file. Before, the measurement read every level.
TEST(LazyLevels, ATexelWithItsSourceReadsOnlyTheLevelsItMeasuresAndMarches) {
    Scene scene = bushField(Eigen::Vector3d(36.725582, -63.610577, 42.907051), true, 96, 72);
    scene.texels[0].sourceData = bushFile().mesh;
    const RenderResult lazy = renderQuiet(scene);
    ASSERT_EQ(lazy.stats.meshLevels.size(), 1u);
    const int meshLevel = int(lazy.stats.meshLevels[0]);
    EXPECT_GE(meshLevel, 3);
    const int deepest = deepestLevelRead(lazy.stats);
    EXPECT_GE(deepest, 0);
    EXPECT_LE(deepest, meshLevel + 1);
    EXPECT_LT(lazy.stats.vtoBytesRead, fs::file_size(bushFile().path) / 10);
}

TEST(LazyLevels, ANearerViewReadsDeeperLevelsAndStillDrawsTheSameImage) {
    const Eigen::Vector3d near(1.784539, -3.090912, 2.560608);
    const RenderResult lazy = renderQuiet(bushField(near, true, 160, 120));
    const RenderResult eager = renderQuiet(bushField(near, false, 160, 120));
    EXPECT_TRUE(sameImageBytes(lazy.image, eager.image));
    const int deepest = deepestLevelRead(lazy.stats);
    EXPECT_GE(deepest, deepestLevelMarched(lazy.stats));
    EXPECT_GE(deepestLevelMarched(lazy.stats), 6);
    EXPECT_LT(lazy.stats.vtoBytesRead, fs::file_size(bushFile().path));
}

TEST(LazyLevels, TheReferenceReadsTheHeaderAlone) {
    Scene scene = bushField(Eigen::Vector3d(1.784539, -3.090912, 2.560608), true, 16, 12);
    scene.texels[0].sourceData = bushFile().mesh;
    ReferenceOptions options;
    options.spp = 1;
    vtex::NullProgress progress;
    const RenderResult result = renderReference(scene, options, progress);
    EXPECT_EQ(result.stats.vtoBytesRead, bushFile().prefix.front());
    EXPECT_EQ(result.stats.vtoFileBytes, fs::file_size(bushFile().path));
}

}  // namespace
