// What a render measures of a texel against its source at load, stored by `vtex build --source`
// (render::measureSource, the .vto's MEAS section): a texel carrying it renders the very image
// the load's measuring gives, without measuring; a record for another source, τ, tolerance or
// version of the rules is not taken; and the command line stores it and renders with it.
#include "bush_field.h"
#include "fixtures.h"
#include "run_vtex.h"

#include "../../render/src/footprint.h"
#include "../../render/src/texel_runtime.h"

#include <vtex/core/error.h>
#include <vtex/render/source_visibility.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

using namespace vtex::render;
using namespace vtex::render::test;
using vtex::test::runVtex;
namespace fs = std::filesystem;

namespace {

const Eigen::Vector3d kEye(1.55, -1.3, 1.4);  // footprints from the volume's levels to the mesh's

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
    EXPECT_TRUE(sameImageBytes(stored.image, measured.image));
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

// End to end: `vtex build --source` stores the measures and the source file's hash; `vtex render`
// takes them and draws the same image. Seen from afar, where no ray can ask for the mesh level,
// it reads neither the source mesh nor the finest levels the measure read (all of the file,
// 4000 leaves at 128³ being faithful to the finest level); nearer, it reads the mesh at load.
// `--tau` stores them for another τ, which a scene of τ 1 then measures again, and a source file
// replaced by another mesh is measured again.
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
    run({"pattern", "bush", "--leaves", "4000", "--seed", "2", "-o", d + "other.glb", "-q"});
    run({"sample", d + "bush.glb", "-r", "128", "-o", d + "bush.vtl", "-q"});
    run({"build", d + "bush.vtl", "-o", d + "plain.vto", "-q"});
    run({"build", d + "bush.vtl", "-o", d + "stored.vto", "--source", d + "bush.glb", "-q"});
    run({"build", d + "bush.vtl", "-o", d + "tau2.vto", "--source", d + "bush.glb", "--tau", "2", "-q"});
    std::ofstream(dir / "ground.obj") << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n";
    const auto scene = [&](const std::string& name, const std::string& volume, const std::string& source,
                           const std::string& eye) {
        std::ofstream(dir / (name + ".toml"))
            << "[camera]\nposition = " << eye << "\nlook_at = [0, 0, 0.4]\nwidth = 48\nheight = 36\n"
            << "[[light]]\ntype = \"directional\"\ndirection = [-1, -0.5, -1]\ncolor = [3, 3, 3]\n"
            << "[[texel]]\nname = \"bush\"\nvolume = \"" << volume << ".vto\"\nsource = \"" << source << ".glb\"\n"
            << "[[surface]]\nmesh = \"ground.obj\"\ntexel = \"bush\"\nheight = 1.0\nrepeat = [2, 2]\n";
    };
    const std::string far = "[6.6, -7.2, 6.0]", near = "[0.9, -1.0, 0.9]";
    scene("plain", "plain", "bush", far);
    scene("stored", "stored", "bush", far);
    scene("tau2", "tau2", "bush", far);
    scene("other", "stored", "other", far);
    scene("near-plain", "plain", "bush", near);
    scene("near-stored", "stored", "bush", near);
    struct Rendered {
        nlohmann::json stats;
        Image image;
    };
    const auto render = [&](const std::string& name) {
        run({"render", d + name + ".toml", "-o", d + name + ".exr", "--stats", d + name + ".json", "-q"});
        return Rendered{nlohmann::json::parse(vtex::test::readText(dir / (name + ".json"))), readExr(dir / (name + ".exr"))};
    };
    const Rendered plain = render("plain"), stored = render("stored"), tau2 = render("tau2"), other = render("other");
    const Rendered nearPlain = render("near-plain"), nearStored = render("near-stored");
    const auto says = [](const Rendered& r, const char* measures, bool loaded) {
        return r.stats["source_measures"] == nlohmann::json::array({measures}) &&
               r.stats["source_loaded"] == nlohmann::json::array({loaded});
    };
    EXPECT_TRUE(says(plain, "measured", true)) << plain.stats.dump();
    EXPECT_TRUE(says(stored, "stored", false)) << stored.stats.dump();
    EXPECT_TRUE(says(tau2, "measured", true)) << tau2.stats.dump();
    EXPECT_TRUE(says(other, "measured", true)) << other.stats.dump();
    EXPECT_TRUE(says(nearPlain, "measured", true)) << nearPlain.stats.dump();
    EXPECT_TRUE(says(nearStored, "stored", true)) << nearStored.stats.dump();
    EXPECT_GT(nearStored.stats["mesh_segments"].get<double>(), 0);
    EXPECT_TRUE(sameImageBytes(plain.image, stored.image));
    EXPECT_TRUE(sameImageBytes(plain.image, tau2.image));
    EXPECT_TRUE(sameImageBytes(nearPlain.image, nearStored.image));
    const auto bytesRead = [](const Rendered& r) { return r.stats["vto_bytes_read"].get<std::uint64_t>(); };
    EXPECT_EQ(bytesRead(plain), fs::file_size(dir / "plain.vto"));
    EXPECT_GT(bytesRead(stored), 0u);
    EXPECT_LT(bytesRead(stored), fs::file_size(dir / "stored.vto") / 3);  // levels 0–6, up to the profile's
}

// The source read when first asked for (SourceHandle, what a far view with stored measures holds
// instead of the mesh): read once however many pixels ask at once, and a failed read passes its
// error on and is tried again by the next ray, as a damaged level is.
TEST(SourceMeasures, ALazySourceIsReadOnceAndAFailedReadIsTriedAgain) {
    const SourcedTexel& bush = smallBush();
    std::atomic<int> reads{0};
    std::atomic<bool> fail{true};
    const vtex::render::detail::SourceHandle handle(
        [&] {
            ++reads;
            if (fail) throw vtex::InputError("bush.glb", "not there yet");
            return bush.mesh;
        },
        bush.tree->info.source);
    ASSERT_TRUE(handle);
    EXPECT_FALSE(handle.loaded());
    EXPECT_THROW(*handle, vtex::InputError);
    EXPECT_FALSE(handle.loaded());
    fail = false;
    std::atomic<int> hits{0};
    tbb::parallel_for(0, 256, [&](int i) {
        const double x = (i % 16 + 0.5) / 16, y = (i / 16 + 0.5) / 16;
        if (handle->intersect(Vec3(x, y, 1), Vec3(x, y, 0), 0)) ++hits;
    });
    EXPECT_EQ(reads.load(), 2);  // the failed read and one more
    EXPECT_TRUE(handle.loaded());
    EXPECT_GT(hits.load(), 0);
    EXPECT_EQ(&handle.mesh(), bush.mesh.get());
}

// The bound a far view's lazy source rests on (finestRequestedLevels). Its camera part, alone with
// the shadow lattice off: no camera span asks for a finer level, and where the volume is marched
// below the mesh level the bound is within a level and a half of the finest level marched (not a
// bound loose enough to hold anywhere). With the defaults the lattice's node rays add level 4 (8
// nodes a cell, one level allowed for a finer neighbour), and where the bound is not past the mesh
// level no ray traces the mesh.
TEST(SourceMeasures, NoRayAsksForALevelFinerThanTheBound) {
    for (const Eigen::Vector3d& eye : {Eigen::Vector3d(9, -10, 8), Eigen::Vector3d(2.2, -2.4, 2.0), Eigen::Vector3d(0.5, -0.6, 1.3)}) {
        const Scene scene = bushField(eye, 48);
        const auto geometry = vtex::render::detail::buildSceneGeometry(scene);
        const double spread = vtex::render::detail::coneSpread(scene.camera.fovY, scene.camera.height, 1);
        RenderOptions cameraOnly;
        cameraOnly.approximations.shadowCacheResolution = 0;
        const double camera = vtex::render::detail::finestRequestedLevels(scene, geometry, spread, cameraOnly).at(0);
        const RenderResult r = renderQuiet(scene, cameraOnly);
        int finest = -1;
        for (std::size_t l = 0; l < r.stats.levelHistogram.size(); ++l)
            if (r.stats.levelHistogram[l] > 0) finest = int(l);
        const double meshLevel = r.stats.meshLevels.at(0);
        EXPECT_LE(finest, std::ceil(camera)) << "eye " << eye.transpose();
        if (finest >= 0 && finest < meshLevel) {
            EXPECT_LT(camera, finest + 1.5) << "eye " << eye.transpose();
        }
        const RenderOptions defaults;
        const double bound = vtex::render::detail::finestRequestedLevels(scene, geometry, spread, defaults).at(0);
        EXPECT_EQ(bound, std::max(camera, 4.0));
        const RenderResult d = renderQuiet(scene, defaults);
        if (bound <= meshLevel) {
            EXPECT_EQ(d.stats.meshSegments, 0.0) << "eye " << eye.transpose();
        }
        std::cout << "eye " << eye.transpose() << ": bound " << bound << " (camera " << camera << "), finest level marched "
                  << finest << ", mesh level " << meshLevel << ", mesh segments " << d.stats.meshSegments << "\n";
    }
}
