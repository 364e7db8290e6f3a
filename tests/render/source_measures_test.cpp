// What a render measures of a texel against its source at load, stored by `vtex build --source`
// (render::measureSource, the .vto's MEAS section): a texel carrying it renders the very image
// the load's measuring gives, without measuring; a record for another source, τ, tolerance or
// version of the rules is not taken; and the command line stores it and renders with it.
#include "bush_field.h"
#include "fixtures.h"
#include "run_vtex.h"

#include <vtex/render/source_visibility.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

using namespace vtex::render;
using namespace vtex::render::test;
using vtex::test::runVtex;
namespace fs = std::filesystem;

namespace {

const Eigen::Vector3d kEye(2.2, -2.4, 2.0);  // footprints from the volume's levels to the mesh's

bool sameBytes(const Image& a, const Image& b) {
    return a.rgba.size() == b.rgba.size() && std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)) == 0;
}

// `texel` with `measures` stored in a copy of its tree.
SourcedTexel withMeasures(const SourcedTexel& texel, const vtex::octree::SourceMeasures& measures) {
    auto tree = std::make_shared<vtex::octree::Octree>(*texel.tree);
    tree->measures = measures;
    return SourcedTexel{texel.mesh, tree};
}

}  // namespace

TEST(SourceMeasures, StoredMeasuresRenderTheImageTheLoadMeasures) {
    const SourcedTexel& bush = smallBush();
    const RenderOptions options;
    const RenderResult measured = renderQuiet(bushField(kEye, 48), options);
    ASSERT_EQ(measured.stats.sourceMeasures, std::vector<std::string>{"measured"});
    ASSERT_GT(measured.stats.meshSegments, 0);  // the hybrid's mesh is in the image too
    const auto m = measureSource(*bush.tree, *bush.mesh, 1.0, options.hybridTolerance);
    EXPECT_EQ(m, measureSource(*bush.tree, *bush.mesh, 1.0, options.hybridTolerance));  // deterministic
    EXPECT_EQ(m.version, sourceMeasuresVersion());
    EXPECT_EQ(m.geometryHash, sourceGeometryHash(*bush.mesh));
    const RenderResult stored = renderQuiet(bushField(kEye, 48, withMeasures(bush, m)), options);
    EXPECT_EQ(stored.stats.sourceMeasures, std::vector<std::string>{"stored"});
    EXPECT_EQ(stored.stats.levelScales, measured.stats.levelScales);
    EXPECT_EQ(stored.stats.shadowLevels, measured.stats.shadowLevels);
    EXPECT_EQ(stored.stats.meshLevels, measured.stats.meshLevels);
    EXPECT_TRUE(sameBytes(stored.image, measured.image));
}

// A record is taken only when it is what the load would measure now: the same version of the
// rules, the same geometry (one vertex moved is another source), τ and tolerance, and the
// default options it was measured with (hybrid and level fit on).
TEST(SourceMeasures, ARecordForAnotherSourceTauToleranceOrVersionIsNotTaken) {
    const SourcedTexel& bush = smallBush();
    const RenderOptions defaults;
    const auto m = measureSource(*bush.tree, *bush.mesh, 1.0, defaults.hybridTolerance);
    const auto taken = [&](const SourcedTexel& texel, const RenderOptions& options, double tau = 1) {
        Scene scene = bushField(kEye, 16, texel);
        scene.texels[0].tau = tau;
        return renderQuiet(scene, options).stats.sourceMeasures.at(0);
    };
    EXPECT_EQ(taken(withMeasures(bush, m), defaults), "stored");
    EXPECT_EQ(taken(withMeasures(bush, m), defaults, 2.0), "measured");
    RenderOptions tolerance;
    tolerance.hybridTolerance = 0.03;
    EXPECT_EQ(taken(withMeasures(bush, m), tolerance), "measured");
    RenderOptions volumeOnly;
    volumeOnly.hybrid = false;
    EXPECT_EQ(taken(withMeasures(bush, m), volumeOnly), "measured");
    RenderOptions unfitted;
    unfitted.fitLevels = false;
    EXPECT_EQ(taken(withMeasures(bush, m), unfitted), "measured");
    auto other = m;
    other.version ^= 1;
    EXPECT_EQ(taken(withMeasures(bush, other), defaults), "measured");
    auto moved = std::make_shared<vtex::ingest::TriangleMesh>(*bush.mesh);
    moved->positions[0].x() += 1e-3f;
    EXPECT_NE(sourceGeometryHash(*moved), m.geometryHash);
    EXPECT_EQ(taken(SourcedTexel{moved, withMeasures(bush, m).tree}, defaults), "measured");
    EXPECT_EQ(taken(bush, defaults), "measured");
}

// End to end: `vtex build --source` stores the measures, `vtex render` takes them, draws the same
// image and, seen from afar, reads a fraction of the file, where measuring read all of it;
// `--tau` stores them for another τ, which a scene of τ 1 then measures again.
TEST(SourceMeasures, BuildWithItsSourceStoresWhatTheRenderTakes) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "source_measures";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const auto run = [](const std::vector<std::string>& args) {
        const auto r = runVtex(args);
        EXPECT_EQ(r.exitStatus, 0) << r.err;
    };
    const std::string d = dir.string() + "/";
    run({"pattern", "bush", "--leaves", "4000", "-o", d + "bush.glb", "-q"});
    run({"sample", d + "bush.glb", "-r", "128", "-o", d + "bush.vtl", "-q"});
    run({"build", d + "bush.vtl", "-o", d + "plain.vto", "-q"});
    run({"build", d + "bush.vtl", "-o", d + "stored.vto", "--source", d + "bush.glb", "-q"});
    run({"build", d + "bush.vtl", "-o", d + "tau2.vto", "--source", d + "bush.glb", "--tau", "2", "-q"});
    std::ofstream(dir / "ground.obj") << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";
    for (const std::string volume : {"plain", "stored", "tau2"})
        std::ofstream(dir / (volume + ".toml"))
            << "[camera]\nposition = [6.6, -7.2, 6.0]\nlook_at = [0, 0, 0.4]\nwidth = 48\nheight = 36\n"
               "[[light]]\ntype = \"directional\"\ndirection = [-1, -0.5, -1]\ncolor = [3, 3, 3]\n"
               "[[texel]]\nname = \"bush\"\nvolume = \""
            << volume
            << ".vto\"\nsource = \"bush.glb\"\n"
               "[[surface]]\nmesh = \"ground.obj\"\ntexel = \"bush\"\nheight = 1.0\nrepeat = [2, 2]\n";
    struct Rendered {
        std::string stats;
        Image image;
    };
    const auto render = [&](const std::string& name) {
        run({"render", d + name + ".toml", "-o", d + name + ".exr", "--stats", d + name + ".json", "-q"});
        return Rendered{vtex::test::readText(dir / (name + ".json")), readExr(dir / (name + ".exr"))};
    };
    const Rendered plain = render("plain"), stored = render("stored"), tau2 = render("tau2");
    EXPECT_NE(plain.stats.find("\"measured\""), std::string::npos) << plain.stats;
    EXPECT_NE(stored.stats.find("\"stored\""), std::string::npos) << stored.stats;
    EXPECT_NE(tau2.stats.find("\"measured\""), std::string::npos) << tau2.stats;
    EXPECT_TRUE(sameBytes(plain.image, stored.image));
    EXPECT_TRUE(sameBytes(plain.image, tau2.image));
    const auto bytesRead = [](const std::string& stats) {
        const auto at = stats.find("\"vto_bytes_read\": ");
        return at == std::string::npos ? 0ull : std::stoull(stats.substr(at + 18));
    };
    // 4000 leaves at 128³ are faithful to the finest level, which the load's measure reads
    // (the whole file); the far view itself reads levels 0–6, up to the profile's (a quarter).
    EXPECT_EQ(bytesRead(plain.stats), fs::file_size(dir / "plain.vto"));
    EXPECT_GT(bytesRead(stored.stats), 0u);
    EXPECT_LT(bytesRead(stored.stats), fs::file_size(dir / "stored.vto") / 3);
}
