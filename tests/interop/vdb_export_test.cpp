// `vtex export texel.vto -o texel.vdb`: the file read back with OpenVDB's own reader, every value
// checked against the octree (its own expansion of the level, not the exporter's walk), the
// tiles, the transform, the metadata; bad usage and bad input refused without touching the output.
#include "run_vtex.h"
#include "texel_fixture.h"

#include <vtex/core/version.h>
#include <vtex/interop/vdb.h>

#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

namespace vtex::interop {
namespace {

namespace fs = std::filesystem;
namespace vdb = openvdb;

const char* const kSggx[6] = {"sggx_xx", "sggx_yy", "sggx_zz", "sggx_xy", "sggx_xz", "sggx_yz"};

fs::path tmp(const std::string& name) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "vdb_export";
    fs::create_directories(dir);
    return dir / name;
}

// The fixture's octree, written once as a .vto.
const fs::path& fixtureVto() {
    static const fs::path path = [] {
        const fs::path p = tmp("texel.vto");
        octree::writeVto(test::exportTestOctree(), p);
        return p;
    }();
    return path;
}

vdb::GridPtrVecPtr readGrids(const fs::path& file, vdb::MetaMap::Ptr* fileMeta = nullptr) {
    vdb::initialize();
    vdb::io::File in(file.string());
    in.open();
    vdb::GridPtrVecPtr grids = in.getGrids();
    if (fileMeta) *fileMeta = in.getMetadata();
    in.close();
    return grids;
}

template <class Grid>
typename Grid::Ptr grid(const vdb::GridPtrVecPtr& grids, const std::string& name) {
    for (const vdb::GridBase::Ptr& g : *grids)
        if (g->getName() == name) return vdb::gridPtrCast<Grid>(g);
    return nullptr;
}

// Every voxel `level` stands for (Octree::expandLevel) is active in every grid with the octree's
// values, and nothing else is active.
void expectLevelMatches(const vdb::GridPtrVecPtr& grids, const octree::Octree& tree, std::uint32_t level,
                        const std::string& suffix, double tau, double scale,
                        const std::optional<octree::Vec3>& along = std::nullopt) {
    const auto density = grid<vdb::FloatGrid>(grids, "density" + suffix);
    const auto albedo = grid<vdb::Vec3SGrid>(grids, "albedo" + suffix);
    ASSERT_TRUE(density && albedo) << "level " << level;
    std::vector<vdb::FloatGrid::Ptr> sggx;
    for (const char* name : kSggx) {
        sggx.push_back(grid<vdb::FloatGrid>(grids, name + suffix));
        ASSERT_TRUE(sggx.back()) << name << suffix;
    }
    const auto expected = tree.expandLevel(level);
    EXPECT_EQ(density->activeVoxelCount(), expected.size()) << "level " << level;
    EXPECT_EQ(albedo->activeVoxelCount(), expected.size());
    for (const auto& s : sggx) EXPECT_TRUE(s->tree().hasSameTopology(density->tree())) << s->getName();
    EXPECT_TRUE(albedo->tree().hasSameTopology(density->tree()));
    const int rows[6] = {0, 1, 2, 0, 0, 1}, cols[6] = {0, 1, 2, 1, 2, 2};
    auto d = density->getConstAccessor();
    auto a = albedo->getConstAccessor();
    for (const octree::VolumeBlock& v : expected) {
        const auto xyz = octree::mortonDecode(v.key);
        const vdb::Coord ijk{int(xyz[0]), int(xyz[1]), int(xyz[2])};
        ASSERT_TRUE(d.isValueOn(ijk)) << "level " << level << " voxel " << ijk;
        const octree::Mat3 s = octree::unpackS(v.data).matrix();
        const double projected = along ? std::sqrt(along->dot(s * *along)) : 1.0;
        EXPECT_FLOAT_EQ(d.getValue(ijk), float(tau / scale * double(v.data.density) * projected)) << ijk;
        const vdb::Vec3s rgb = a.getValue(ijk);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(rgb[c], v.data.albedo[std::size_t(c)]) << ijk;
        for (int e = 0; e < 6; ++e)
            EXPECT_NEAR(sggx[std::size_t(e)]->tree().getValue(ijk), s(rows[e], cols[e]), 1e-6) << kSggx[e] << ijk;
    }
}

TEST(VdbExport, EveryVoxelOfTheFinestLevelReadsBackAsInTheOctree) {
    const fs::path out = tmp("finest.vdb");
    const auto r = test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--tau", "2.5", "--scale",
                                  "0.5", "--translate", "1,-2,3"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    const octree::Octree tree = octree::readVto(fixtureVto());
    const auto grids = readGrids(out);
    EXPECT_EQ(grids->size(), 8u);
    expectLevelMatches(grids, tree, 5, "", 2.5, 0.5);
    EXPECT_EQ(grid<vdb::FloatGrid>(grids, "density")->getGridClass(), vdb::GRID_FOG_VOLUME);
}

TEST(VdbExport, DensityAlongADirectionIsTheAnisotropicExtinction) {
    const fs::path out = tmp("along.vdb");
    const auto r =
        test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--tau", "2", "--along", "0,3,4"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    const auto grids = readGrids(out);
    expectLevelMatches(grids, octree::readVto(fixtureVto()), 5, "", 2.0, 1.0, octree::Vec3(0, 0.6, 0.8));
    const auto density = grid<vdb::FloatGrid>(grids, "density");
    EXPECT_EQ(density->metaValue<std::string>("vtex_density_along"), "0.000000,0.600000,0.800000");
    // The solid's sphere has Â = 1 in every direction: its tiles keep τ·ρ.
    EXPECT_FLOAT_EQ(density->tree().getValue(vdb::Coord(3, 9, 15)), 15.f);
    EXPECT_EQ(test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--along", "0,0,0"}).exitStatus, 2);
}

TEST(VdbExport, ConstantRegionsAreTiles) {
    const fs::path out = tmp("tiles.vdb");
    ASSERT_EQ(test::runVtex({"export", fixtureVto().string(), "-o", out.string()}).exitStatus, 0);
    const auto density = grid<vdb::FloatGrid>(readGrids(out), "density");
    ASSERT_TRUE(density);
    // The 16³ solid leaf is 8 tiles of 8³ (OpenVDB's smallest tile is a whole leaf node); the
    // 4³ block and the surface voxels are leaf-node voxels.
    EXPECT_EQ(density->tree().activeTileCount(), 8u);
    EXPECT_EQ(density->activeVoxelCount() - density->tree().activeLeafVoxelCount(), 16u * 16 * 16);
    EXPECT_TRUE(density->tree().isValueOn(vdb::Coord(3, 9, 15)));
    EXPECT_FALSE(density->tree().probeConstLeaf(vdb::Coord(3, 9, 15))) << "inside a tile, not a leaf node";
    EXPECT_FLOAT_EQ(density->tree().getValue(vdb::Coord(3, 9, 15)), 7.5f);
    const auto xx = grid<vdb::FloatGrid>(readGrids(out), "sggx_xx");
    const auto xy = grid<vdb::FloatGrid>(readGrids(out), "sggx_xy");
    EXPECT_FLOAT_EQ(xx->tree().getValue(vdb::Coord(3, 9, 15)), 1.f) << "the solid's sphere: S = identity";
    EXPECT_EQ(xy->tree().getValue(vdb::Coord(3, 9, 15)), 0.f);
}

TEST(VdbExport, TransformPlacesTheUnitCube) {
    const fs::path out = tmp("placed.vdb");
    ASSERT_EQ(test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--level", "3", "--scale", "2",
                             "--translate", "10,20,30"})
                  .exitStatus,
              0);
    const auto grids = readGrids(out);
    for (const vdb::GridBase::Ptr& g : *grids) {
        const vdb::math::Transform& t = g->transform();
        EXPECT_TRUE(t.isLinear());
        EXPECT_NEAR(t.voxelSize()[0], 2.0 / 8, 1e-12) << g->getName();
        // Voxel i covers [i − ½, i + ½] in index space: the cube's corners are −½ and N − ½.
        const vdb::Vec3d lo = t.indexToWorld(vdb::Vec3d(-0.5, -0.5, -0.5));
        const vdb::Vec3d hi = t.indexToWorld(vdb::Vec3d(7.5, 7.5, 7.5));
        EXPECT_NEAR((lo - vdb::Vec3d(10, 20, 30)).length(), 0, 1e-12);
        EXPECT_NEAR((hi - vdb::Vec3d(12, 22, 32)).length(), 0, 1e-12);
    }
    expectLevelMatches(grids, octree::readVto(fixtureVto()), 3, "", 1.0, 2.0);

    // Blender's convention: voxel i over [i, i+1] of index space, the same world box.
    ASSERT_EQ(test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--level", "3", "--scale", "2",
                             "--translate", "10,20,30", "--voxel-centres", "blender"})
                  .exitStatus,
              0);
    const auto blender = readGrids(out);  // kept: a range-for over *readGrids() would dangle
    for (const vdb::GridBase::Ptr& g : *blender) {
        const vdb::math::Transform& t = g->transform();
        EXPECT_NEAR((t.indexToWorld(vdb::Vec3d(0, 0, 0)) - vdb::Vec3d(10, 20, 30)).length(), 0, 1e-12);
        EXPECT_NEAR((t.indexToWorld(vdb::Vec3d(8, 8, 8)) - vdb::Vec3d(12, 22, 32)).length(), 0, 1e-12);
        EXPECT_EQ(g->metaValue<std::string>("vtex_voxel_centres"), "blender");
    }
}

TEST(VdbExport, MetadataNamesVersionRuleAndLevel) {
    const fs::path out = tmp("meta.vdb");
    ASSERT_EQ(test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--level", "2", "--tau", "3"})
                  .exitStatus,
              0);
    vdb::MetaMap::Ptr fileMeta;
    const auto grids = readGrids(out, &fileMeta);
    ASSERT_EQ(grids->size(), 8u);
    for (const vdb::GridBase::Ptr& g : *grids) {
        EXPECT_EQ(g->metaValue<std::string>("vtex_version").rfind(std::string(kVersion) + " (commit ", 0), 0u);
        EXPECT_EQ(g->metaValue<std::string>("vtex_filter_rule"), "sggx");
        EXPECT_EQ(g->metaValue<std::string>("vtex_source"), "texel.vto");
        EXPECT_EQ(g->metaValue<int>("vtex_level"), 2);
        EXPECT_EQ(g->metaValue<int>("vtex_finest_level"), 5);
        EXPECT_EQ(g->metaValue<double>("vtex_tau"), 3.0);
        EXPECT_FALSE(g->metaValue<std::string>("vtex_quantity").empty()) << g->getName();
    }
    EXPECT_EQ(fileMeta->metaValue<std::string>("vtex_levels"), "2");
    EXPECT_EQ(fileMeta->metaValue<std::string>("vtex_filter_rule"), "sggx");
}

TEST(VdbExport, AllLevelsAreSuffixedGridsInOneFile) {
    const fs::path out = tmp("all.vdb");
    ASSERT_EQ(test::runVtex({"export", fixtureVto().string(), "-o", out.string(), "--levels", "all"}).exitStatus, 0);
    const octree::Octree tree = octree::readVto(fixtureVto());
    vdb::MetaMap::Ptr fileMeta;
    const auto grids = readGrids(out, &fileMeta);
    EXPECT_EQ(grids->size(), 8u * tree.levelCount());
    EXPECT_FALSE(grid<vdb::FloatGrid>(grids, "density")) << "with several levels every name is suffixed";
    for (std::uint32_t level = 0; level < tree.levelCount(); ++level) {
        const std::string suffix = "_L" + std::to_string(level);
        expectLevelMatches(grids, tree, level, suffix, 1.0, 1.0);
        EXPECT_NEAR(grid<vdb::FloatGrid>(grids, "density" + suffix)->voxelSize()[0], 1.0 / (1 << level), 1e-15);
    }
    EXPECT_EQ(fileMeta->metaValue<std::string>("vtex_levels"), "0,1,2,3,4,5");
}

TEST(VdbExport, AnEmptyTexelGivesEmptyGrids) {
    octree::SparseVolume empty;
    empty.info.levels = 2;
    NullProgress progress;
    const fs::path vto = tmp("empty.vto"), out = tmp("empty.vdb");
    octree::writeVto(octree::buildOctree(empty, {}, progress), vto);
    ASSERT_EQ(test::runVtex({"export", vto.string(), "-o", out.string()}).exitStatus, 0);
    const auto grids = readGrids(out);
    ASSERT_EQ(grids->size(), 8u);
    for (const vdb::GridBase::Ptr& g : *grids) EXPECT_EQ(g->activeVoxelCount(), 0u) << g->getName();
}

TEST(VdbExport, BadUsageIsRefusedBeforeAnyOutput) {
    const fs::path out = tmp("refused.vdb");
    fs::remove(out);
    const std::string in = fixtureVto().string();
    const std::vector<std::vector<std::string>> cases = {
        {"export", in, "-o", out.string(), "--level", "6"},                      // the octree has 0–5
        {"export", in, "-o", tmp("refused.vdbx").string()},                      // unknown output kind
        {"export", in, "-o", tmp("refused.exr").string()},
        {"export", in, "-o", out.string(), "--level", "2", "--levels", "all"},  // one or the other
        {"export", in, "-o", out.string(), "--levels", "some"},
        {"export", in, "-o", out.string(), "--translate", "1,2"},
        {"export", in, "-o", out.string(), "--scale", "0"},
        {"export", tmp("texel.vtl").string(), "-o", out.string()},               // not an octree
    };
    for (const auto& args : cases) {
        const auto r = test::runVtex(args);
        EXPECT_EQ(r.exitStatus, 2) << args[3] << " " << (args.size() > 4 ? args[4] : "") << ": " << r.err;
        EXPECT_EQ(test::lineCount(r.err), r.err.find("Run 'vtex") == std::string::npos ? 1u : 2u) << r.err;
        EXPECT_FALSE(fs::exists(out));
    }
    const auto r = test::runVtex({"export", in, "-o", out.string(), "--level", "6"});
    EXPECT_NE(r.err.find("no level 6"), std::string::npos) << r.err;
}

TEST(VdbExport, AnUnreadableOctreeIsNamedAndTheOutputKept) {
    const fs::path bad = tmp("bad.vto"), out = tmp("kept.vdb");
    std::ofstream(bad, std::ios::binary) << "VTEX.VTO but not really";
    std::ofstream(out, std::ios::binary) << "earlier";
    for (const fs::path& input : {bad, tmp("missing.vto")}) {
        const auto r = test::runVtex({"export", input.string(), "-o", out.string()});
        EXPECT_EQ(r.exitStatus, 3) << r.err;
        EXPECT_NE(r.err.find(input.string()), std::string::npos) << r.err;
        EXPECT_EQ(test::lineCount(r.err), 1u) << r.err;
        EXPECT_EQ(test::readText(out), "earlier");
    }
    for (const auto& entry : fs::directory_iterator(out.parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(VdbExport, AnOutputThatIsTheInputIsRefused) {
    const auto r = test::runVtex({"export", fixtureVto().string(), "-o", fixtureVto().string()});
    EXPECT_EQ(r.exitStatus, 3) << r.err;  // the input itself, refused as every command refuses it
    const fs::path link = tmp("link.vdb");
    fs::remove(link);
    fs::create_symlink(fixtureVto(), link);
    const auto linked = test::runVtex({"export", fixtureVto().string(), "-o", link.string()});
    EXPECT_EQ(linked.exitStatus, 3) << linked.err;
    EXPECT_NO_THROW(octree::readVto(fixtureVto()));
}

}  // namespace
}  // namespace vtex::interop
