// The malformed corpus: one hostile or broken input per failure class, built here. Each must
// be refused with an InputError naming the file and the problem — never a crash, a hang, an
// unbounded allocation or an output file. ("Loading is expected to fail, but not crash.")
#include "gltf_builder.h"
#include "run_vtex.h"
#include "scratch_dir.h"

#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include <zlib.h>
#include <limits>

namespace fs = std::filesystem;
using namespace vtex;
using vtex::test::GltfBuilder;

namespace {

fs::path dir() { return vtex::test::scratchDir("malformed"); }

// Loads `bytes` saved as `name` and expects an InputError whose message holds `expected`.
void expectRefused(const std::string& name, const std::string& bytes, const std::string& expected,
                   ingest::IngestOptions options = {}) {
    const fs::path path = dir() / name;
    test::writeBytes(path, bytes);
    try {
        ingest::loadMesh(path, options);
        ADD_FAILURE() << name << ": loaded, expected refusal containing '" << expected << "'";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path.string()), std::string::npos) << what;
        EXPECT_NE(what.find(expected), std::string::npos) << name << ": '" << what << "' lacks '" << expected << "'";
        EXPECT_EQ(what.find('\n'), std::string::npos);
    }
}

std::string triangleGlb(std::function<void(GltfBuilder&, int position)> edit = {}) {
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    const int idx = b.indices({0, 1, 2});
    b.meshNode({{"attributes", {{"POSITION", pos}}}, {"indices", idx}});
    if (edit) edit(b, pos);
    return b.glb();
}

TEST(Malformed, ValidBaselineLoads) {
    test::writeBytes(dir() / "baseline.glb", triangleGlb());
    EXPECT_EQ(ingest::loadMesh(dir() / "baseline.glb").triangles.size(), 1u);
}

TEST(Malformed, IndexOutOfRange) {
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    const int idx = b.indices({0, 1, 3});
    b.meshNode({{"attributes", {{"POSITION", pos}}}, {"indices", idx}});
    expectRefused("index_range.glb", b.glb(), "index 3 out of range");
}

TEST(Malformed, AccessorPastEndOfBufferView) {
    expectRefused("accessor_past_end.glb", triangleGlb([](GltfBuilder& b, int pos) { b.doc["accessors"][pos]["count"] = 4; }),
                  "run past the end of bufferView");
    expectRefused("accessor_offset_past_end.glb",
                  triangleGlb([](GltfBuilder& b, int pos) { b.doc["accessors"][pos]["byteOffset"] = 4; }),
                  "run past the end of bufferView");
}

TEST(Malformed, BufferViewPastEndOfBuffer) {
    expectRefused("view_past_end.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["bufferViews"][0]["byteLength"] = 4096; }),
                  "extends past the end of its buffer");
}

TEST(Malformed, CountTimesStrideOverflow) {
    // (count − 1) · stride wraps around 2^64 when computed naively; with the triangle limit
    // lifted, only the overflow-safe extent check stands between this and a wild read.
    ingest::IngestOptions options;
    options.maxTriangles = std::uint64_t(1) << 62;
    expectRefused("stride_overflow.glb", triangleGlb([](GltfBuilder& b, int pos) {
                      b.doc["bufferViews"][0]["byteStride"] = 16;
                      b.doc["accessors"][pos]["count"] = (std::uint64_t(1) << 60) + 1;
                  }),
                  "run past the end", options);
}

TEST(Malformed, MisalignedByteOffset) {
    expectRefused("misaligned.glb", triangleGlb([](GltfBuilder& b, int pos) {
                      b.doc["accessors"][pos]["byteOffset"] = 2;
                      b.doc["accessors"][pos]["count"] = 2;
                  }),
                  "misaligned");
}

TEST(Malformed, ClaimedCountOfTenToTheTwelve) {
    expectRefused("count_1e12.glb",
                  triangleGlb([](GltfBuilder& b, int pos) { b.doc["accessors"][pos]["count"] = 1000000000000ULL; }),
                  "exceeds the limit");
    // Without a bufferView an accessor is zeros: the count alone must not drive an allocation.
    expectRefused("count_1e12_noview.glb", triangleGlb([](GltfBuilder& b, int pos) {
                      b.doc["accessors"][pos].erase("bufferView");
                      b.doc["accessors"][pos]["count"] = 1000000000000ULL;
                  }),
                  "exceeds the limit");
}

TEST(Malformed, MissingBufferFile) {
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    b.meshNode({{"attributes", {{"POSITION", pos}}}});
    b.finishBuffer("missing.bin");
    expectRefused("missing_buffer.gltf", b.doc.dump(), "File not found");
}

TEST(Malformed, UriEscapingTheFolderIsRefused) {
    // A real file outside the input's folder, reachable by ../, by an absolute path and by a
    // symbolic link inside the folder: none may be read.
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    b.meshNode({{"attributes", {{"POSITION", pos}}}});
    const fs::path inner = dir() / "inner";
    fs::create_directories(inner);
    test::writeBytes(dir() / "outside.bin", b.bin);
    b.finishBuffer("../outside.bin");
    expectRefused("inner/dotdot.gltf", b.doc.dump(), "refused");
    b.finishBuffer((dir() / "outside.bin").string());
    expectRefused("inner/absolute.gltf", b.doc.dump(), "refused");
    fs::remove(inner / "link.bin");
    fs::create_symlink(dir() / "outside.bin", inner / "link.bin");
    b.finishBuffer("link.bin");
    expectRefused("inner/symlink.gltf", b.doc.dump(), "refused");
    // The same buffer inside the folder loads.
    test::writeBytes(inner / "inside.bin", b.bin);
    b.finishBuffer("inside.bin");
    test::writeBytes(inner / "inside.gltf", b.doc.dump());
    EXPECT_EQ(ingest::loadMesh(inner / "inside.gltf").triangles.size(), 1u);
}

// URIs are percent-encoded (a space is %20, as exporters write it): they resolve to the file
// with the decoded name, and an encoded traversal is refused as the plain one is (issue 16).
TEST(Malformed, PercentEncodedUrisResolveInsideTheFolderOnly) {
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    b.meshNode({{"attributes", {{"POSITION", pos}}}});
    const fs::path inner = dir() / "percent";
    fs::create_directories(inner);
    test::writeBytes(inner / "my buffer.bin", b.bin);
    b.finishBuffer("my%20buffer.bin");
    test::writeBytes(inner / "spaced.gltf", b.doc.dump());
    EXPECT_EQ(ingest::loadMesh(inner / "spaced.gltf").triangles.size(), 1u);
    test::writeBytes(dir() / "outside.bin", b.bin);
    b.finishBuffer("..%2Foutside.bin");
    expectRefused("percent/encoded_dotdot.gltf", b.doc.dump(), "refused");
}

TEST(Malformed, BadBase64InDataUri) {
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    b.meshNode({{"attributes", {{"POSITION", pos}}}});
    std::string encoded = test::base64(b.bin);
    encoded[5] = '!';
    b.finishBuffer("data:application/octet-stream;base64," + encoded);
    expectRefused("bad_base64.gltf", b.doc.dump(), "base64");
}

TEST(Malformed, NodeCycle) {
    expectRefused("cycle.glb", triangleGlb([](GltfBuilder& b, int) {
                      b.doc["nodes"].push_back({{"children", {0}}});
                      b.doc["nodes"][0]["children"] = {1};
                  }),
                  "cycle");
    expectRefused("self_cycle.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["nodes"][0]["children"] = {0}; }),
                  "cycle");
    // No scene and every node somebody's child: still a cycle, still refused.
    expectRefused("cycle_noscene.glb", triangleGlb([](GltfBuilder& b, int) {
                      b.doc.erase("scenes");
                      b.doc.erase("scene");
                      b.doc["nodes"].push_back({{"children", {0}}});
                      b.doc["nodes"][0]["children"] = {1};
                  }),
                  "cycle");
}

TEST(Malformed, NonFinitePositions) {
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        GltfBuilder b;
        std::vector<float> xyz = test::kTriangle;
        xyz[4] = bad;
        const int pos = b.positions(xyz);
        b.meshNode({{"attributes", {{"POSITION", pos}}}});
        expectRefused(std::isnan(bad) ? "nan.glb" : "inf.glb", b.glb(), "NaN or infinite");
    }
    expectRefused("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite");
    expectRefused("inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n", "NaN or infinite");
}

TEST(Malformed, EmptyTruncatedWrongMagic) {
    for (const char* name : {"empty.glb", "empty.gltf", "empty.obj", "empty.off", "empty.ply", "empty.stl"})
        expectRefused(name, "", "empty");
    const std::string glb = triangleGlb();
    for (std::size_t cut : {4u, 11u, 19u, 40u, unsigned(glb.size() - 4)})
        expectRefused("truncated_" + std::to_string(cut) + ".glb", glb.substr(0, cut), "truncated");
    std::string magic = glb;
    magic[0] = 'X';
    expectRefused("magic.glb", magic, "wrong magic");
}

TEST(Malformed, JsonOfTheWrongTypes) {
    expectRefused("type_name.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["nodes"][0]["name"] = 42; }), "must be a string");
    expectRefused("type_children.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["nodes"][0]["children"] = "0"; }),
                  "must be an array");
    expectRefused("type_count.glb", triangleGlb([](GltfBuilder& b, int pos) { b.doc["accessors"][pos]["count"] = "3"; }),
                  "must be a non-negative integer");
    expectRefused("type_negative.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["nodes"][0]["mesh"] = -1; }),
                  "must be a non-negative integer");
    expectRefused("type_root.gltf", "[1, 2, 3]", "not an object");
    expectRefused("not_json.gltf", "{\"asset\": {\"version\": \"2.0\"", "does not parse");
    expectRefused("deep.gltf", "{\"asset\":{\"version\":\"2.0\"},\"extras\":" + std::string(100000, '[') + std::string(100000, ']') + "}",
                  "nested deeper");
}

TEST(Malformed, GltfVersionOne) {
    expectRefused("version1.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["asset"]["version"] = "1.0"; }),
                  "2.x required");
}

TEST(Malformed, ObjIndices) {
    const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    expectRefused("obj_bad_index.obj", v + "f 1 2 x\n", "line 4: bad vertex index 'x'");
    expectRefused("obj_zero_index.obj", v + "f 0 1 2\n", "index 0");
    expectRefused("obj_negative.obj", v + "f -1 -2 -4\n", "line 4: vertex index -4 out of range");
    expectRefused("obj_enormous.obj", v + "f 1 2 99999999999999999999999\n", "out of range");
    expectRefused("obj_large.obj", v + "f 1 2 4000000000\n", "out of range");
    expectRefused("obj_uv_range.obj", v + "vt 0 0\nf 1/1 2/2 3/1\n", "texture coordinate index 2 out of range");
    expectRefused("obj_no_faces.obj", v, "no faces");
    expectRefused("obj_points_lines.obj", v + "p 1 2 3\nl 1 2\n", "points and lines only");
    expectRefused("obj_two_corners.obj", v + "f 1 2\n", "fewer than 3");
    expectRefused("obj_bad_number.obj", "v 0 0 zero\n", "bad number");
    expectRefused("obj_degenerate.obj", v + "f 1 1 1\n", "degenerate");
}

TEST(Malformed, HeaderCountsBeyondTheBytes) {
    expectRefused("huge.off", "OFF\n1000000000000 1 0\n0 0 0\n3 0 0 0\n", "more than the file");
    expectRefused("huge_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2000000000 0 1 2\n", "corners");
    expectRefused("huge.ply",
                  "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\nend_header\n",
                  "more than the file");
    std::string list = "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
    list += std::string("\xff\xff\xff\x7f", 4) + std::string(12, '\0');
    expectRefused("huge_list.ply", list, "runs past the end");
    std::string stl(84, '\0');
    stl[80] = '\x10';
    expectRefused("truncated.stl", stl + std::string(50, '\0'), "binary STL");
}

// Regressions found by the fuzzer (fuzz/fuzz_ingest.cpp), named after the bug.
TEST(Malformed, FuzzObjHugeIndexHashOverflow) {
    // A huge negative-relative index made the corner hash overflow a signed multiply (UBSan).
    expectRefused("fuzz_hash.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1609587929392839161\n", "out of range");
}

TEST(Malformed, FuzzStlTextThatIsNotSolidHangs) {
    // Text that is not "solid ..." went to OpenMesh's binary reader, which then looped over a
    // triangle count read from the text.
    expectRefused("fuzz_hang.stl",
                  "soli\xff" "d test\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n" + std::string(200, ' '),
                  "neither an ASCII STL");
}

TEST(Malformed, FuzzPlyHeaderGarbageHangs) {
    // A stray header line sent OpenMesh's PLY header parser into an endless loop; OpenMesh now
    // only reads a rewritten header, so the stray line is dropped and the (face-less) file is
    // refused for what it is.
    expectRefused("fuzz_hang.ply",
                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                  "ppop\r\nend_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n",
                  "no faces");
    expectRefused("fuzz_hang2.ply",
                  "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 12\nproperty list uchar int vertex_indices\xbc" "end_header\n" + std::string(8, '\0'),
                  "PLY");
    expectRefused("fuzz_hang3.ply",
                  "ply\nformat binary_little_endian nerated\nelement vertex 1\nproperty float x\nend_header\n" + std::string(4, '\0'),
                  "format version");
    expectRefused("fuzz_hang4.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\npropervy float x\nend_header\n",
                  "no properties");
}

TEST(Malformed, FuzzPlyTokenOutOfStepBecomesACornerCount) {
    // An extra token on a vertex line: OpenMesh reads tokens, not lines, so it took the token
    // for the first face's corner count and pushed 4·10⁹ handles (out of memory; found in CI).
    const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    expectRefused("fuzz_oom.ply", head + "0 0 0\n1 0 0\n0 1 0 4088888888888\n3 0 1 2\n", "record 0: '4088888888888' does not read as uint8");
    // Values are checked against their declared types: a negative count, a corner that is
    // not an integer, a coordinate that is not a number, a record cut short.
    expectRefused("negative_count.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n-1 0 1 2\n",
                  "negative list count");
    expectRefused("fraction.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", "'2.5' does not read as int32");
    expectRefused("word.ply", head + "0 0 zero\n1 0 0\n0 1 0\n3 0 1 2\n", "PLY 'vertex' record 0: 'zero' is not a number");
    expectRefused("short.ply", head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", "PLY 'face' record 0: truncated");
    expectRefused("no_corners.ply",
                  "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty uchar red\nend_header\n0 0 0\n1 0 0\n0 1 0\n3\n",
                  "faces without a vertex_indices list");
    // "property list" with three tokens was read as a five-token list (the fuzzer, at once).
    expectRefused("short_list.ply",
                  "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list vertex_indices\nend_header\n" + std::string(24, '\0'),
                  "unknown property type");
    // A coordinate beyond float's range is read as infinite and refused by name.
    expectRefused("overflow.ply", head + "0 0 0\n1e60 0 0\n0 1 0\n3 0 1 2\n", "infinite");
}

TEST(Malformed, OffValuesOpenMeshReadOutOfStep) {
    // A face colour of 4·10⁹ became the next face's corner count in OpenMesh (out of memory);
    // now the colour is read as a colour and the file is fine.
    const std::string square = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    const fs::path colourCount = dir() / "colour_count.off";
    test::writeBytes(colourCount, square + "3 0 1 2 4000000000\n3 0 2 3\n");
    EXPECT_EQ(ingest::loadMesh(colourCount).triangles.size(), 2u);
    // "nan" stopped OpenMesh's stream (then "no faces"); now the coordinate is refused by name.
    expectRefused("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", "NaN or infinite coordinate at vertex 1");
    // NOFF vertex lines without a normal were read across line ends.
    expectRefused("short_normal.off", "NOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "fewer than 6 numbers");
    expectRefused("keyword.off", "XOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "not an OFF file");
}

TEST(Malformed, FuzzOffGarbageTokenHangs) {
    // A token OpenMesh's ASCII OFF reader cannot extract made it loop forever.
    expectRefused("fuzz_hang.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2=v\n", "OFF face 0");
    expectRefused("fuzz_counts.off", "OFF 0 0\n0 1 0\n2000000000 0 1 2\n", "alone on its line");
    expectRefused("fuzz_hang2.off", "OFF\n3 1 0\n0 0 0\n0.5000.0 0 0\n0 1 0\n3 0 1 2\n", "OFF vertex 1: bad number");
}

TEST(Malformed, MaxTriangles) {
    ingest::IngestOptions options;
    options.maxTriangles = 1;
    expectRefused("too_many.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n", "--max-triangles", options);
    expectRefused("too_many.glb", triangleGlb([](GltfBuilder& b, int) { b.doc["nodes"].push_back({{"mesh", 0}}); b.doc["scenes"][0]["nodes"].push_back(1); }),
                  "--max-triangles", options);
}

TEST(Malformed, HostileTextureIsIgnoredNotDecoded) {
    // A PNG header claiming 100000 × 100000 pixels: refused by the size cap before any
    // allocation; the mesh still loads, with a warning, and without the texture.
    std::string png("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16);
    auto be32 = [&png](std::uint32_t v) { for (int s = 24; s >= 0; s -= 8) png.push_back(char((v >> s) & 0xff)); };
    be32(100000);
    be32(100000);
    png += std::string("\x08\x06\0\0\0", 5);
    const std::uint32_t crc = std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(png.data() + 12), 17));
    be32(crc);
    // An empty IDAT then IEND: libpng reads the header chunks up to the first IDAT.
    for (const char* chunk : {"IDAT", "IEND"}) {
        be32(0);
        png += chunk;
        be32(std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(chunk), 4)));
    }
    GltfBuilder b;
    const int pos = b.positions(test::kTriangle);
    const int uv = b.accessor(b.view(std::vector<float>{0, 0, 1, 0, 0, 1}), 5126, 3, "VEC2");
    std::vector<char> pngBytes(png.begin(), png.end());
    const int image = b.view(pngBytes);
    b.doc["images"] = {{{"bufferView", image}, {"mimeType", "image/png"}}};
    b.doc["textures"] = {{{"source", 0}}};
    b.doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
    b.meshNode({{"attributes", {{"POSITION", pos}, {"TEXCOORD_0", uv}}}, {"material", 0}});
    test::writeBytes(dir() / "huge_texture.glb", b.glb());
    ingest::IngestReport report;
    const auto mesh = ingest::loadMesh(dir() / "huge_texture.glb", {}, &report);
    EXPECT_TRUE(mesh.textures.empty());
    ASSERT_FALSE(report.warnings.empty());
    EXPECT_NE(report.warnings[0].find("exceeds the texture size limit"), std::string::npos) << report.warnings[0];
}

TEST(Malformed, CommandLineExitsThreeWithOneLineAndNoOutput) {
    const fs::path input = dir() / "cli_bad.glb";
    test::writeBytes(input, triangleGlb([](GltfBuilder& b, int pos) { b.doc["accessors"][pos]["count"] = 4; }));
    const fs::path output = dir() / "cli_out.glb";
    fs::remove(output);
    const auto result = test::runVtex({"ingest", input.string(), "-o", output.string(), "--report", (dir() / "cli.json").string()});
    EXPECT_EQ(result.exitStatus, 3) << result.err;
    EXPECT_EQ(test::lineCount(result.err), 1u) << result.err;
    EXPECT_NE(result.err.find(input.string()), std::string::npos);
    EXPECT_FALSE(fs::exists(output));
    // No temporary left beside the target either.
    for (const auto& entry : fs::directory_iterator(dir()))
        EXPECT_EQ(entry.path().filename().string().find("cli_out.glb."), std::string::npos) << entry.path();
    // inspect refuses it the same way.
    const auto inspect = test::runVtex({"inspect", input.string()});
    EXPECT_EQ(inspect.exitStatus, 3);
}

TEST(Malformed, CommandLineIngestAndInspectSucceed) {
    const fs::path input = dir() / "cli_good.obj";
    test::writeBytes(input, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const fs::path output = dir() / "cli_good.glb";
    const fs::path report = dir() / "cli_good.json";
    const auto result = test::runVtex({"ingest", input.string(), "-o", output.string(), "--report", report.string()});
    ASSERT_EQ(result.exitStatus, 0) << result.err;
    EXPECT_TRUE(result.out.empty());
    const auto json = nlohmann::json::parse(test::readText(report));
    EXPECT_EQ(json["triangles_out"], 4);
    EXPECT_EQ(json["closed"], true);
    const auto inspect = test::runVtex({"inspect", output.string(), "--json"});
    ASSERT_EQ(inspect.exitStatus, 0) << inspect.err;
    const auto summary = nlohmann::json::parse(inspect.out);
    EXPECT_EQ(summary["triangles_out"], 4);
    EXPECT_EQ(summary["canonical"], true);
    const auto human = test::runVtex({"inspect", output.string()});
    EXPECT_NE(human.out.find("triangles  4"), std::string::npos) << human.out;
    EXPECT_EQ(test::runVtex({"ingest", "--help"}).exitStatus, 0);
    EXPECT_EQ(test::runVtex({"ingest", input.string()}).exitStatus, 2);  // -o is required
}

}  // namespace
