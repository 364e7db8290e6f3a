// The .vtl and .vto files: bit-exact round trips; corruption, truncation and future versions
// refused with the failing section named.
#include <vtex/core/error.h>
#include <vtex/octree/density_profile.h>
#include <vtex/octree/octree.h>

#include "../../octree/src/container.h"
#include "../../octree/src/vto_sections.h"
#include "random_volume.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <random>
#include <utility>

namespace vtex::octree {
namespace {

SparseVolume smallVolume() {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.05, 1.0);
    SparseVolume v;
    v.info.levels = 3;
    v.info.cyclic = true;
    v.info.scale = 0.5;
    v.info.offset = {0.25, 0.125, 0};
    v.info.sourceTriangles = 77;
    v.info.sourceArea = 1.25;
    v.info.fitError = {12, 0.01, 0.05};
    for (std::uint64_t key = 0; key < 512; key += 1 + key % 7) {
        VoxelData d;
        d.density = float(u(rng) * 4);
        packEllipsoid(Ellipsoid::fromAxes(Mat3::Identity(), Vec3(u(rng), u(rng), u(rng))), d);
        d.albedo = {float(u(rng)), float(u(rng)), float(u(rng))};
        v.blocks.push_back(VolumeBlock{key, 3, 0, d});
    }
    return v;
}

Octree smallOctree() {
    NullProgress progress;
    return buildOctree(smallVolume(), {}, progress);
}

template <class Parse>
void expectAllCorruptionRefused(const std::string& bytes, Parse parse) {
    std::mt19937 rng(2024);
    std::uniform_int_distribution<std::size_t> bit(0, bytes.size() * 8 - 1);
    for (int i = 0; i < 10000; ++i) {
        std::string flipped = bytes;
        const std::size_t b = bit(rng);
        flipped[b / 8] = char(flipped[b / 8] ^ (1 << (b % 8)));
        try {
            parse(flipped);
            ADD_FAILURE() << "bit " << b << " flipped, not detected";
            return;
        } catch (const InputError& e) {
            ASSERT_FALSE(e.location().empty()) << e.what();
        }
    }
    for (int k = 0; k < 64; ++k) {
        const std::size_t size = bytes.size() * std::size_t(k) / 64;
        EXPECT_THROW(parse(bytes.substr(0, size)), InputError) << "truncated to " << size;
    }
    EXPECT_THROW(parse(bytes + "x"), InputError);
}

TEST(VtlFormat, RoundTripIsBitExact) {
    const SparseVolume v = smallVolume();
    const std::string bytes = serializeVtl(v);
    const SparseVolume back = parseVtl(bytes, "mem.vtl");
    EXPECT_EQ(back, v);
    EXPECT_EQ(serializeVtl(back), bytes);
    const auto path = std::filesystem::path(VTEX_TEST_TMP) / "round.vtl";
    std::filesystem::create_directories(path.parent_path());
    writeVtl(v, path);
    EXPECT_EQ(readVtl(path), v);
}

TEST(VtoFormat, RoundTripIsBitExact) {
    const Octree tree = smallOctree();
    const std::string bytes = serializeVto(tree);
    const Octree back = parseVto(bytes, "mem.vto");
    EXPECT_EQ(back, tree);
    EXPECT_EQ(serializeVto(back), bytes);
    const auto path = std::filesystem::path(VTEX_TEST_TMP) / "round.vto";
    std::filesystem::create_directories(path.parent_path());
    writeVto(tree, path);
    EXPECT_EQ(readVto(path), tree);
}

// writeVto streams each level in pieces of 32768 nodes and writes the header last (issue 13):
// a tree whose finest level spans several pieces is written as the very bytes serializeVto makes.
TEST(VtoFormat, WrittenFileIsTheSerialisedBytes) {
    NullProgress progress;
    const Octree tree = buildOctree(test::randomVolume(6, 80000, 21), {}, progress);
    ASSERT_GT(tree.levels[6].size(), 2u * 32768u);
    const auto path = std::filesystem::path(VTEX_TEST_TMP) / "streamed.vto";
    std::filesystem::create_directories(path.parent_path());
    writeVto(tree, path);
    EXPECT_TRUE(readFileBytes(path) == serializeVto(tree));
}

TEST(VtoFormat, EverySingleBitFlipAndTruncationIsRefused) {
    const std::string bytes = serializeVto(smallOctree());
    ASSERT_LT(bytes.size(), 64u * 1024);
    expectAllCorruptionRefused(bytes, [](const std::string& b) { parseVto(b, "t.vto"); });
}

TEST(VtlFormat, EverySingleBitFlipAndTruncationIsRefused) {
    const std::string bytes = serializeVtl(smallVolume());
    expectAllCorruptionRefused(bytes, [](const std::string& b) { parseVtl(b, "t.vtl"); });
}

TEST(VtoFormat, ErrorsNameTheFailingSection) {
    const std::string bytes = serializeVto(smallOctree());
    // A flipped byte in the last level's payload.
    std::string corrupt = bytes;
    corrupt[bytes.size() - 3] ^= 0x10;
    try {
        parseVto(corrupt, "c.vto");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(e.location(), "section 'LV03'");
        EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos);
    }
    // A future version.
    std::string future = bytes;
    future[8] = 2;
    try {
        parseVto(future, "f.vto");
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(e.location(), "header");
        EXPECT_NE(std::string(e.what()).find("newer"), std::string::npos) << e.what();
    }
    // Not a .vto at all: a .vtl.
    EXPECT_THROW(parseVto(serializeVtl(smallVolume()), "x.vto"), InputError);
    // checkFile reports per-section status without throwing.
    const FileCheck check = checkFile(corrupt, std::string_view("VTEX.VTO", 8), kVtoVersion);
    ASSERT_TRUE(check.headerOk);
    EXPECT_FALSE(check.sections.back().checksumOk);
    EXPECT_TRUE(check.sections.front().checksumOk);
}

TEST(VtoFormat, ConsistentButWrongContentIsRefused) {
    // Valid checksums around an impossible tree: the validator, not only the checksum, refuses.
    Octree tree = smallOctree();
    tree.levels[3][0].childMask = 1;  // a finest-level node with children
    EXPECT_THROW(parseVto(serializeVto(tree), "bad.vto"), InputError);
    tree = smallOctree();
    tree.levels[2][0].data.density = -1;
    EXPECT_THROW(parseVto(serializeVto(tree), "bad.vto"), InputError);
    SparseVolume v = smallVolume();
    std::swap(v.blocks[0], v.blocks[1]);  // out of order
    EXPECT_THROW(parseVtl(serializeVtl(v), "bad.vtl"), InputError);
}

// What parseVto says of `tree`'s bytes: "section 'X': problem", or "accepted".
std::string refusalOf(const Octree& tree) {
    try {
        parseVto(serializeVto(tree), "bad.vto");
    } catch (const InputError& e) {
        return std::string(e.location()) + ": " + e.what();
    }
    return "accepted";
}

// What `vtex build --source` stores for renders (the MEAS section): a tree with a record.
SourceMeasures sampleMeasures() {
    SourceMeasures m;
    m.version = 0x1234abcd;
    m.geometryHash = 0xfedcba9876543210ull;
    m.fileHash = 0x0123456789abcdefull;
    m.tau = 1.5;
    m.tolerance = 0.02;
    m.faithfulCoarsest = 1;
    m.faithfulFinest = 3;
    m.meshLevel = 2;
    m.levelScales = {0.72, 0.81, 0.93};
    m.shadowLevels = {1};
    m.ownShares = {0.001, 0.02, 0.29, 0.64};
    return m;
}

// The record goes through the file bit for bit, whole (readVto) and opened a level at a time
// (openVto), every bit flip of it is refused, and a tree without one writes what it did before.
TEST(VtoFormat, StoredSourceMeasuresRoundTrip) {
    Octree tree = smallOctree();
    const std::string without = serializeVto(tree);
    tree.measures = sampleMeasures();
    const std::string bytes = serializeVto(tree);
    EXPECT_GT(bytes.size(), without.size());
    const Octree back = parseVto(bytes, "mem.vto");
    ASSERT_TRUE(back.measures);
    EXPECT_EQ(*back.measures, sampleMeasures());
    EXPECT_EQ(serializeVto(back), bytes);
    const auto path = std::filesystem::path(VTEX_TEST_TMP) / "measured.vto";
    std::filesystem::create_directories(path.parent_path());
    writeVto(tree, path);
    EXPECT_TRUE(readFileBytes(path) == bytes);
    const auto opened = openVto(path);
    ASSERT_TRUE(opened->measures);
    EXPECT_EQ(*opened->measures, sampleMeasures());
    EXPECT_FALSE(parseVto(without, "mem.vto").measures);
    expectAllCorruptionRefused(bytes, [](const std::string& b) { parseVto(b, "t.vto"); });
}

// A record written before the own shares (revision 1) ends after its shadow levels: it is read,
// without shares (its version then makes a render measure again); anything after the shares'
// count but the shares is refused.
TEST(VtoFormat, ARecordWithoutOwnSharesIsRead) {
    const Octree tree = smallOctree();
    SourceMeasures m = sampleMeasures();
    m.ownShares.clear();
    std::string bytes = detail::measuresBytes(m);
    ASSERT_EQ(bytes.substr(bytes.size() - 4), std::string(4, '\0'));  // the shares' count, 0
    EXPECT_EQ(detail::parseVtoMeasures(bytes, tree, "t.vto"), m);
    EXPECT_EQ(detail::parseVtoMeasures(bytes.substr(0, bytes.size() - 4), tree, "t.vto"), m);
    for (const std::size_t cut : {1, 2, 3}) EXPECT_THROW(detail::parseVtoMeasures(bytes.substr(0, bytes.size() - cut), tree, "t.vto"), InputError);
    EXPECT_THROW(detail::parseVtoMeasures(detail::measuresBytes(sampleMeasures()) + "x", tree, "t.vto"), InputError);
}

// Checksummed but impossible records are refused naming the section, by both readers.
TEST(VtoFormat, ImpossibleSourceMeasuresAreRefused) {
    const auto refusal = [](const SourceMeasures& m) {
        Octree tree = smallOctree();
        tree.measures = m;
        return refusalOf(tree);
    };
    // Each case breaks one field of a valid record.
    using Break = void (*)(SourceMeasures&);
    const std::pair<const char*, Break> cases[] = {
        {"mesh level past the tree's levels 0–3", [](SourceMeasures& m) { m.meshLevel = 4; }},
        {"negative shadow level", [](SourceMeasures& m) { m.shadowLevels = {-1}; }},
        {"NaN level scale", [](SourceMeasures& m) { m.levelScales[1] = std::numeric_limits<double>::quiet_NaN(); }},
        {"more scales than levels", [](SourceMeasures& m) { m.levelScales.assign(5, 1.0); }},
        {"a share past 1", [](SourceMeasures& m) { m.ownShares[2] = 1.5; }},
        {"NaN share", [](SourceMeasures& m) { m.ownShares[0] = std::numeric_limits<double>::quiet_NaN(); }},
        {"more shares than levels", [](SourceMeasures& m) { m.ownShares.assign(5, 0.5); }},
        {"tau 0", [](SourceMeasures& m) { m.tau = 0; }},
        {"negative tolerance", [](SourceMeasures& m) { m.tolerance = -1; }},
    };
    for (const auto& [what, breakIt] : cases) {
        SourceMeasures m = sampleMeasures();
        breakIt(m);
        EXPECT_EQ(refusal(m).find("section 'MEAS'"), 0u) << what << ": " << refusal(m);
    }
    EXPECT_EQ(refusal(sampleMeasures()), "accepted");
    // openVto checks the record when it opens the file, before any level.
    Octree tree = smallOctree();
    tree.measures = sampleMeasures();
    tree.measures->faithfulFinest = 9;
    const auto path = std::filesystem::path(VTEX_TEST_TMP) / "bad_measures.vto";
    std::filesystem::create_directories(path.parent_path());
    writeVto(tree, path);
    try {
        openVto(path);
        FAIL();
    } catch (const InputError& e) {
        EXPECT_EQ(e.location(), "section 'MEAS'");
    }
}

// The density profile's layer means (the PROF section): the build stores what the profile
// would measure, they go through the file bit for bit by both readers, and checksummed but
// impossible ones are refused naming the section.
TEST(VtoFormat, StoredLayerMeansRoundTripAndImpossibleOnesAreRefused) {
    Octree tree = smallOctree();
    ASSERT_TRUE(tree.layerMeans);
    EXPECT_EQ(*tree.layerMeans, measureLayerMeans(tree));
    EXPECT_EQ(tree.layerMeans->level, tree.levelCount() - 1);  // levels 0–3: the profile level is the finest
    const std::string bytes = serializeVto(tree);
    const Octree back = parseVto(bytes, "mem.vto");
    ASSERT_TRUE(back.layerMeans);
    EXPECT_EQ(*back.layerMeans, *tree.layerMeans);
    EXPECT_EQ(serializeVto(back), bytes);
    const auto path = std::filesystem::path(VTEX_TEST_TMP) / "profiled.vto";
    std::filesystem::create_directories(path.parent_path());
    writeVto(tree, path);
    ASSERT_TRUE(openVto(path)->layerMeans);
    EXPECT_EQ(*openVto(path)->layerMeans, *tree.layerMeans);
    Octree without = tree;
    without.layerMeans.reset();
    EXPECT_LT(serializeVto(without).size(), bytes.size());
    EXPECT_FALSE(parseVto(serializeVto(without), "mem.vto").layerMeans);
    expectAllCorruptionRefused(bytes, [](const std::string& b) { parseVto(b, "t.vto"); });

    const auto refusal = [](const LayerMeans& m) {
        Octree t = smallOctree();
        t.layerMeans = m;
        return refusalOf(t);
    };
    const auto refusedAtProf = [&](const LayerMeans& m) { return refusal(m).find("section 'PROF'") == 0; };
    LayerMeans m = *tree.layerMeans;
    m.level = 4;  // the tree has levels 0–3
    for (auto& axis : m.axis) axis.assign(16, 1.0);
    EXPECT_TRUE(refusedAtProf(m)) << refusal(m);
    m = *tree.layerMeans;
    m.axis[2][1] = -0.5;
    EXPECT_TRUE(refusedAtProf(m)) << refusal(m);
    m = *tree.layerMeans;
    m.axis[0][0] = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(refusedAtProf(m)) << refusal(m);
    m = *tree.layerMeans;
    m.level = 2;  // 8 values an axis where level 2 has 4
    EXPECT_TRUE(refusedAtProf(m)) << refusal(m);
    EXPECT_EQ(refusal(*tree.layerMeans), "accepted");
}

}  // namespace
}  // namespace vtex::octree

namespace vtex::octree {
namespace {

std::string refusal(std::string_view bytes) {
    try {
        parseVtl(bytes, "bad.vtl");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

// Checksummed but wrong content (issue 14, item 8): values are validated, not only checksums,
// and a container holds each of its own sections once and nothing else.
TEST(VtlFormat, ValuesAndSectionsAreValidatedNotOnlyChecksums) {
    const SparseVolume good = smallVolume();
    EXPECT_EQ(refusal(serializeVtl(good)), "");
    const auto withFirst = [&](auto&& change) {
        SparseVolume v = good;
        change(v.blocks.front().data);
        return refusal(serializeVtl(v));  // serialised with valid checksums
    };
    EXPECT_NE(withFirst([](VoxelData& d) { d.rotation = {0, 0, 0, 0}; }).find("unit quaternion"), std::string::npos);
    EXPECT_NE(withFirst([](VoxelData& d) { d.sigma = {0, 0, 0}; }).find("sigma"), std::string::npos);
    EXPECT_NE(withFirst([](VoxelData& d) { d.albedo[1] = -0.5f; }).find("albedo"), std::string::npos);
    EXPECT_NE(withFirst([](VoxelData& d) { d.albedo[2] = 3e38f; }).find("albedo"), std::string::npos);
    // A second HEAD, and a section no reader knows, both with valid checksums.
    const std::string bytes = serializeVtl(good);
    const auto sections = detail::readContainer(bytes, "VTEX.VTL", kVtlVersion, "good.vtl");
    std::vector<detail::OutSection> out;
    for (const auto& s : sections) out.push_back({s.tag, std::string(s.payload)});
    auto twice = out;
    twice.push_back(out.front());
    EXPECT_NE(refusal(detail::writeContainer("VTEX.VTL", kVtlVersion, twice)).find("duplicate section"), std::string::npos);
    auto unknown = out;
    unknown.push_back({"XTRA", "hello"});
    EXPECT_NE(refusal(detail::writeContainer("VTEX.VTL", kVtlVersion, unknown)).find("unknown section"), std::string::npos);
}

}  // namespace vtex::octree
