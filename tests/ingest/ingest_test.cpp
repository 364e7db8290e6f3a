// What ingest must get right on valid input: transforms, primitive modes, accessor kinds,
// repairs, orientation, formats and the canonical .glb round trip (the base quad mesh:
// base_mesh_test.cpp).
#include "gltf_builder.h"

#include <vtex/core/error.h>
#include <vtex/ingest/base_mesh.h>
#include <vtex/ingest/ingest.h>

#include <gtest/gtest.h>

#include <set>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace fs = std::filesystem;
using namespace vtex;
using namespace vtex::ingest;
using vtex::test::GltfBuilder;

namespace {

fs::path tmp(const std::string& name) { return test::tmpFile("ingest", name); }

TriangleMesh loadText(const std::string& name, const std::string& bytes, IngestReport* report = nullptr,
                      IngestOptions options = {}) {
    const fs::path path = tmp(name);
    test::writeBytes(path, bytes);
    return loadMesh(path, options, report);
}

// The file's own frame: these tests check what the reader does with glTF's nodes and
// primitives, before any turn of its +Y up to vtex's +Z (Ingest.GltfIsTurnedFromYUpToZUp).
IngestOptions fileFrame() {
    IngestOptions options;
    options.up = 'z';
    return options;
}

Eigen::Vector3f faceNormal(const TriangleMesh& m, std::size_t t) {
    const auto& tri = m.triangles[t];
    return (m.positions[tri[1]] - m.positions[tri[0]]).cross(m.positions[tri[2]] - m.positions[tri[0]]).normalized();
}

// An axis-aligned unit cube as 12 triangles; inward=true winds every face the wrong way.
std::string cubeObj(bool inward) {
    std::string s = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
    const int faces[6][4] = {{1, 4, 3, 2}, {5, 6, 7, 8}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 4, 8, 7}, {4, 1, 5, 8}};
    for (const auto& f : faces) {
        if (inward) s += "f " + std::to_string(f[3]) + " " + std::to_string(f[2]) + " " + std::to_string(f[1]) + " " + std::to_string(f[0]) + "\n";
        else s += "f " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + " " + std::to_string(f[3]) + "\n";
    }
    return s;
}

void expectOutward(const TriangleMesh& m) {
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    for (const auto& p : m.positions) centre += p;
    centre /= float(m.positions.size());
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const auto& tri = m.triangles[t];
        const Eigen::Vector3f c = (m.positions[tri[0]] + m.positions[tri[1]] + m.positions[tri[2]]) / 3;
        EXPECT_GT(faceNormal(m, t).dot(c - centre), 0) << "triangle " << t << " points inward";
        for (auto v : tri) EXPECT_GT(m.normals[v].dot(faceNormal(m, t)), 0) << "normal disagrees with winding";
    }
}

TEST(Ingest, GlbRoundTripIsExactAndCanonical) {
    TriangleMesh mesh;
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.5f}};
    mesh.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    mesh.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
    mesh.triangleMaterials = {0, 1};
    mesh.materials.resize(2);
    mesh.materials[1].baseColorFactor = {0.5f, 0.25f, 1.0f, 1.0f};
    mesh.materials[1].baseColorTexture = 0;
    mesh.textures.push_back({2, 1, {255, 0, 0, 255, 0, 255, 0, 128}});
    const fs::path path = tmp("roundtrip.glb");
    writeMeshGlb(mesh, path);
    IngestReport report;
    const TriangleMesh back = loadMesh(path, {}, &report);
    ASSERT_EQ(back.triangles.size(), 2u);
    ASSERT_EQ(back.positions.size(), 4u);
    EXPECT_EQ(report.repairs.recomputedNormals, 0u);
    ASSERT_EQ(back.textures.size(), 1u);
    EXPECT_EQ(back.textures[0].width, 2);
    EXPECT_EQ(back.textures[0].rgba, mesh.textures[0].rgba);
    ASSERT_EQ(back.materials.size(), 2u);
    EXPECT_FLOAT_EQ(back.materials[1].baseColorFactor[1], 0.25f);
    EXPECT_EQ(back.materials[1].baseColorTexture, 0);
    ASSERT_EQ(back.triangleMaterials.size(), 2u);
    // Writing what was read gives the same bytes: the canonical form is a fixed point.
    EXPECT_EQ(encodeMeshGlb(back), encodeMeshGlb(loadMesh(path)));
    for (std::size_t t = 0; t < 2; ++t)
        if (back.triangleMaterials[t] == 1) {
            std::vector<Eigen::Vector3f> corners;
            for (auto v : back.triangles[t]) corners.push_back(back.positions[v]);
            EXPECT_TRUE(std::find(corners.begin(), corners.end(), Eigen::Vector3f(1, 1, 0.5f)) != corners.end());
        }
}

// glTF is +Y up (its specification, §3.4; Blender's exporter writes it): a point (x, y, z) of the
// file is (x, −z, y) in vtex's +Z-up frame, its normals alike; vtex's own .glb is already +Z up
// and round-trips unchanged; --up overrides either, for any format.
TEST(Ingest, GltfIsTurnedFromYUpToZUp) {
    GltfBuilder b;
    // A triangle standing in glTF's up direction: its apex at y = 2, its normal +z (toward the
    // glTF viewer).
    const int pos = b.positions(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 2, 0});
    const int nrm = b.accessor(b.view(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}), 5126, 3, "VEC3");
    b.meshNode({{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}});
    IngestReport report;
    const TriangleMesh m = loadText("standing.gltf", b.gltfEmbedded(), &report);
    EXPECT_EQ(report.up, 'y');
    EXPECT_FLOAT_EQ(report.boundsMax.z(), 2.0f);  // the apex is up
    EXPECT_FLOAT_EQ(report.boundsMax.y(), 0.0f);
    for (const auto& n : m.normals) EXPECT_TRUE(n.isApprox(Eigen::Vector3f(0, -1, 0), 1e-6f)) << n.transpose();
    EXPECT_NE(toJson(report).find("\"up\": \"y\""), std::string::npos);
    // Written by vtex and read back: the same coordinates, not turned again.
    const fs::path canonical = tmp("standing-canonical.glb");
    writeMeshGlb(m, canonical);
    IngestReport again;
    EXPECT_EQ(loadMesh(canonical, {}, &again).positions, m.positions);
    EXPECT_EQ(again.up, 'z');
    // --up x: +X is turned to +Z, for an OBJ too.
    IngestOptions xUp;
    xUp.up = 'x';
    IngestReport obj;
    loadText("x-up.obj", "v 0 0 0\nv 3 0 0\nv 0 1 0\nf 1 2 3\n", &obj, xUp);
    EXPECT_FLOAT_EQ(obj.boundsMax.z(), 3.0f);
    EXPECT_FLOAT_EQ(obj.boundsMax.x(), 0.0f);
}

// A real glTF of known up axis (issue 16): Khronos' ClearCoatTest, in Debian's
// assimp-testmodels, is a board of labelled spheres standing upright, facing the glTF viewer:
// tall along glTF's +Y, thin along +Z. Ingested, it stands along vtex's +Z, its face toward −y;
// read as it is (--up z), it would lie on its back.
TEST(Ingest, RealGltfModelStandsAlongZ) {
    const fs::path model = "/usr/share/assimp/models/glTF2/ClearCoat-glTF/ClearCoatTest.gltf";
    if (!fs::exists(model)) GTEST_SKIP() << "assimp-testmodels not installed";
    IngestReport turned, asIs;
    loadMesh(model, {}, &turned);
    IngestOptions noTurn;
    noTurn.up = 'z';
    loadMesh(model, noTurn, &asIs);
    const Eigen::Vector3f standing = turned.boundsMax - turned.boundsMin, lying = asIs.boundsMax - asIs.boundsMin;
    std::cout << "ClearCoatTest extent: " << standing.transpose() << " (turned), " << lying.transpose() << " (as is)\n";
    EXPECT_EQ(turned.up, 'y');
    // The board is thin across its face and tall: after the turn the thin axis is y, and its
    // height is along z.
    EXPECT_LT(standing.y(), 0.5f * standing.z());
    EXPECT_LT(standing.y(), 0.5f * standing.x());
    EXPECT_GT(lying.y(), 2.0f * lying.z());  // as is, it lies on its back
    // The turn is (x, y, z) → (x, −z, y): the height is the file's y extent.
    EXPECT_NEAR(standing.z(), lying.y(), 1e-4f * lying.y());
    EXPECT_NEAR(turned.boundsMin.y(), -asIs.boundsMax.z(), 1e-4f * lying.maxCoeff());
}

// --fit cell: the largest side of the bounding box becomes 1, centred in x and y, base at z = 0,
// the same factor on every axis; recorded in the report.
TEST(Ingest, FitCellScalesUniformlyIntoTheUnitCube) {
    IngestOptions options;
    options.fitCell = true;
    IngestReport report;
    const TriangleMesh m = loadText("fit.obj", "v 10 20 5\nv 14 20 5\nv 10 22 7\nf 1 2 3\n", &report, options);
    EXPECT_DOUBLE_EQ(report.fitScale, 0.25);
    EXPECT_FLOAT_EQ(report.boundsMin.x(), 0.0f);
    EXPECT_FLOAT_EQ(report.boundsMax.x(), 1.0f);
    EXPECT_FLOAT_EQ(report.boundsMin.y(), 0.25f);  // 2 of 4 wide, centred
    EXPECT_FLOAT_EQ(report.boundsMax.y(), 0.75f);
    EXPECT_FLOAT_EQ(report.boundsMin.z(), 0.0f);
    EXPECT_FLOAT_EQ(report.boundsMax.z(), 0.5f);
    for (const auto& p : m.positions) EXPECT_TRUE((p.array() >= 0).all() && (p.array() <= 1).all()) << p.transpose();
    EXPECT_NE(toJson(report).find("\"cell\""), std::string::npos);
}

TEST(Ingest, NodeTransformsAreBakedWithNormalsByInverseTranspose) {
    GltfBuilder b;
    const int pos = b.positions(vtex::test::kTriangle);
    const int nrm = b.accessor(b.view(std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}), 5126, 3, "VEC3");
    // Parent translates by (10,0,0); child rotates 90° about x and scales y by 2.
    b.doc["meshes"] = {{{"primitives", {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}}}}}};
    const double s = std::sqrt(0.5);
    b.doc["nodes"] = {{{"translation", {10, 0, 0}}, {"children", {1}}},
                      {{"mesh", 0}, {"rotation", {s, 0, 0, s}}, {"scale", {1, 2, 1}}}};
    b.doc["scenes"] = {{{"nodes", {0}}}};
    const TriangleMesh m = loadText("trs.gltf", b.gltfEmbedded(), nullptr, fileFrame());
    ASSERT_EQ(m.triangles.size(), 1u);
    // (0,1,0) → scale (0,2,0) → rotate about x (0,0,2) → translate (10,0,2).
    bool seen = false;
    for (const auto& p : m.positions) seen |= p.isApprox(Eigen::Vector3f(10, 0, 2), 1e-5f);
    EXPECT_TRUE(seen);
    // The plane z=0 becomes the plane y=0 with normal (0,-1,0)... after rotation +z → -y.
    for (const auto& n : m.normals) EXPECT_TRUE(n.isApprox(Eigen::Vector3f(0, -1, 0), 1e-5f)) << n.transpose();
    EXPECT_GT(faceNormal(m, 0).dot(m.normals[m.triangles[0][0]]), 0.99f);
}

TEST(Ingest, MatrixWithMirrorFlipsWinding) {
    GltfBuilder b;
    const int pos = b.positions(vtex::test::kTriangle);
    b.meshNode({{"attributes", {{"POSITION", pos}}}},
               {{"matrix", {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}});
    const TriangleMesh m = loadText("mirror.gltf", b.gltfEmbedded(), nullptr, fileFrame());
    ASSERT_EQ(m.triangles.size(), 1u);
    // Mirrored in x, the triangle still faces +z because its winding was flipped.
    EXPECT_GT(faceNormal(m, 0).z(), 0.99f);
    EXPECT_GT(m.normals[0].z(), 0.99f);
}

TEST(Ingest, StripsFansAndNonIndexed) {
    const std::vector<float> quad = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    for (int mode : {5, 6}) {
        GltfBuilder b;
        const int pos = b.positions(quad);
        std::vector<std::uint32_t> order = mode == 5 ? std::vector<std::uint32_t>{0, 1, 2, 3}
                                                     : std::vector<std::uint32_t>{0, 1, 3, 2};
        const int idx = b.indices(order);
        b.meshNode({{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"mode", mode}});
        IngestReport report;
        const TriangleMesh m = loadText("mode" + std::to_string(mode) + ".glb", b.glb(), &report, fileFrame());
        ASSERT_EQ(m.triangles.size(), 2u) << "mode " << mode;
        for (std::size_t t = 0; t < 2; ++t) EXPECT_GT(faceNormal(m, t).z(), 0.99f) << "mode " << mode;
    }
    GltfBuilder b;
    const int pos = b.positions(quad);
    b.meshNode({{"attributes", {{"POSITION", pos}}}, {"mode", 0}});  // points: skipped
    const int pos2 = b.positions(vtex::test::kTriangle);
    b.meshNode({{"attributes", {{"POSITION", pos2}}}});  // non-indexed triangles
    IngestReport report;
    const TriangleMesh m = loadText("mixed.glb", b.glb(), &report);
    EXPECT_EQ(m.triangles.size(), 1u);
    EXPECT_FALSE(report.warnings.empty());
}

TEST(Ingest, ComponentTypesNormalizedStrideAndSparse) {
    GltfBuilder b;
    // Positions as normalized unsigned shorts, interleaved with padding (stride 8).
    std::vector<std::uint16_t> interleaved = {0, 0, 0, 7, 65535, 0, 0, 7, 0, 65535, 0, 7};
    const int view = b.view(interleaved, 8);
    const int pos = b.accessor(view, 5123, 3, "VEC3", {{"normalized", true}});
    // Indices as unsigned bytes.
    const int idx = b.accessor(b.view(std::vector<std::uint8_t>{0, 1, 2, 0}), 5121, 3, "SCALAR");
    b.meshNode({{"attributes", {{"POSITION", pos}}}, {"indices", idx}});
    // A second primitive: sparse positions over a zero accessor (no bufferView).
    const int sparseIdx = b.view(std::vector<std::uint16_t>{1, 2});
    const int sparseVal = b.view(std::vector<float>{2, 0, 0, 0, 2, 0});
    const int pos2 = b.accessor(-1, 5126, 3, "VEC3",
                                {{"sparse", {{"count", 2},
                                             {"indices", {{"bufferView", sparseIdx}, {"componentType", 5123}}},
                                             {"values", {{"bufferView", sparseVal}}}}}});
    b.meshNode({{"attributes", {{"POSITION", pos2}}}});
    // Signed normalized bytes for the second primitive's normals: (0,0,127) → (0,0,1).
    IngestReport report;
    const TriangleMesh m = loadText("types.glb", b.glb(), &report);
    ASSERT_EQ(m.triangles.size(), 2u);
    bool unit = false, sparse = false;
    for (const auto& p : m.positions) {
        unit |= p.isApprox(Eigen::Vector3f(1, 0, 0));
        sparse |= p.isApprox(Eigen::Vector3f(2, 0, 0));
    }
    EXPECT_TRUE(unit);
    EXPECT_TRUE(sparse);
}

TEST(Ingest, ClosedMeshIsOrientedOutward) {
    for (bool inward : {false, true}) {
        IngestReport report;
        const TriangleMesh m = loadText(inward ? "cube_in.obj" : "cube_out.obj", cubeObj(inward), &report);
        EXPECT_TRUE(m.closed);
        EXPECT_TRUE(report.closed);
        EXPECT_EQ(m.triangles.size(), 12u);
        EXPECT_EQ(report.repairs.flippedFaces, inward ? 12u : 0u);
        expectOutward(m);
    }
    // A cube with one face wound the other way is fixed face by face.
    std::string mixed = cubeObj(false);
    mixed.replace(mixed.find("f 1 4 3 2"), 9, "f 2 3 4 1");
    IngestReport report;
    const TriangleMesh m = loadText("cube_mixed.obj", mixed, &report);
    EXPECT_TRUE(m.closed);
    EXPECT_EQ(report.repairs.flippedFaces, 2u);
    expectOutward(m);
    // An open box (5 faces) is not closed and keeps its winding.
    std::string open = cubeObj(true);
    open = open.substr(0, open.rfind("f "));
    const TriangleMesh o = loadText("open.obj", open, &report);
    EXPECT_FALSE(o.closed);
    EXPECT_EQ(report.repairs.flippedFaces, 0u);
}

TEST(Ingest, RepairsAreCounted) {
    // Duplicate vertices (within tolerance), a degenerate and a zero-area face, an unused vertex.
    const std::string obj =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1e-9 0 0\nv 1 1 0\nv 2 0 0\nv 5 5 5\n"
        "f 4 2 3\nf 2 5 3\nf 1 2 4\nf 1 2 6\n";
    IngestReport report;
    const TriangleMesh m = loadText("repairs.obj", obj, &report);
    EXPECT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(report.repairs.mergedVertices, 1u);
    EXPECT_EQ(report.repairs.degenerateFaces, 1u);
    EXPECT_EQ(report.repairs.zeroAreaFaces, 1u);
    EXPECT_EQ(report.repairs.unreferencedVertices, 3u);  // v1 (merged away: its only face became degenerate), v6, v7
    EXPECT_EQ(report.trianglesIn, 4u);
    EXPECT_EQ(report.trianglesOut, 2u);
    // The report names them.
    const std::string json = toJson(report);
    EXPECT_NE(json.find("\"zero_area_faces\": 1"), std::string::npos) << json;
    EXPECT_NE(json.find("\"closed\": false"), std::string::npos);
}

TEST(Ingest, DropInvalidCountsInsteadOfRefusing) {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nf 1 2 3\nf 1 2 9\nf 1 2 4\n";
    EXPECT_THROW(loadText("invalid_strict.obj", obj), InputError);
    IngestOptions options;
    options.dropInvalidFaces = true;
    IngestReport report;
    const TriangleMesh m = loadText("invalid_drop.obj", obj, &report, options);
    EXPECT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(report.repairs.invalidIndexFaces, 1u);
    EXPECT_EQ(report.repairs.nonFiniteFaces, 1u);
}

TEST(Ingest, NormalsFromFileWhenValidElseComputed) {
    // Vertex 1's normal is zero (invalid) and vertex 2's points against the winding.
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 0\nvn 0 0 -1\nf 1//1 2//2 3//3\n";
    IngestReport report;
    const TriangleMesh m = loadText("normals.obj", obj, &report);
    EXPECT_EQ(report.repairs.recomputedNormals, 1u);
    EXPECT_EQ(report.repairs.flippedNormals, 1u);
    for (const auto& n : m.normals) EXPECT_TRUE(n.isApprox(Eigen::Vector3f(0, 0, 1)));
}

TEST(Ingest, ObjMaterialsNegativeIndicesAndPolygons) {
    test::writeBytes(tmp("objmat/m.mtl"), "newmtl red\nKd 1 0 0\nnewmtl half\nKd 0.5 0.5 0.5\nd 0.5\n");
    const std::string obj =
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nusemtl red\nf -5 -4 -3 -2\nusemtl half\nf 2 5 3\n";
    test::writeBytes(tmp("objmat/a.obj"), obj);
    IngestReport report;
    const TriangleMesh m = loadMesh(tmp("objmat/a.obj"), {}, &report);
    ASSERT_EQ(m.triangles.size(), 3u);
    ASSERT_EQ(m.triangleMaterials.size(), 3u);
    const Material& red = m.materials[m.triangleMaterials[0]];
    EXPECT_FLOAT_EQ(red.baseColorFactor[0], 1.0f);
    EXPECT_FLOAT_EQ(red.baseColorFactor[1], 0.0f);
    const Material& half = m.materials[m.triangleMaterials[2]];
    EXPECT_FLOAT_EQ(half.baseColorFactor[3], 0.5f);
}

// MTL files from Windows name textures with backslashes (assimp's spider.mtl: `map_Kd
// .\wal67ar_small.jpg`, issue 16): they resolve inside the input's folder, and `..\` still
// leaves it and is refused like `../`.
TEST(Ingest, MtlPathsWithBackslashesResolveAndStillCannotLeaveTheFolder) {
    const fs::path jpg = "/usr/share/assimp/models/OBJ/wal67ar_small.jpg";
    if (!fs::exists(jpg)) GTEST_SKIP() << "assimp-testmodels is not installed (scripts/test.sh installs it)";
    fs::create_directories(tmp("objwin/models"));
    fs::copy_file(jpg, tmp("objwin/models/tex.jpg"), fs::copy_options::overwrite_existing);
    fs::copy_file(jpg, tmp("objwin/secret.jpg"), fs::copy_options::overwrite_existing);
    test::writeBytes(tmp("objwin/models/m.mtl"), "newmtl in\nmap_Kd .\\tex.jpg\nnewmtl out\nmap_Kd ..\\secret.jpg\n");
    test::writeBytes(tmp("objwin/models/a.obj"), "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                                 "usemtl in\nf 1 2 3\nusemtl out\nf 1 3 4\n");
    IngestReport report;
    const TriangleMesh m = loadMesh(tmp("objwin/models/a.obj"), {}, &report);
    ASSERT_EQ(m.textures.size(), 1u) << "the backslashed texture inside the folder is read, the other not";
    std::size_t refused = 0;
    for (const auto& w : report.warnings) refused += w.find("secret.jpg") != std::string::npos;
    EXPECT_EQ(refused, 1u);
    // The real file: every texture of spider.mtl is found.
    IngestReport spider;
    const TriangleMesh s = loadMesh("/usr/share/assimp/models/OBJ/spider.obj", {}, &spider);
    EXPECT_GE(s.textures.size(), 3u);
    for (const auto& w : spider.warnings) EXPECT_EQ(w.find("not found inside"), std::string::npos) << w;
}

TEST(Ingest, OffPlyAndStl) {
    // A unit square, counter-clockwise seen from +z, in each format.
    IngestReport report;
    TriangleMesh m = loadText("sq.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", &report);
    ASSERT_EQ(m.triangles.size(), 2u);
    for (std::size_t t = 0; t < 2; ++t) EXPECT_GT(faceNormal(m, t).z(), 0.99f);
    m = loadText("sq.ply",
                 "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
    ASSERT_EQ(m.triangles.size(), 2u);
    for (std::size_t t = 0; t < 2; ++t) EXPECT_GT(faceNormal(m, t).z(), 0.99f);
    // Binary STL: 80-byte header, count, then normal + 3 vertices + attribute per triangle.
    std::string stl(80, ' ');
    auto put = [&stl](auto v) { stl.append(reinterpret_cast<const char*>(&v), sizeof v); };
    put(std::uint32_t(2));
    const float tris[2][9] = {{0, 0, 0, 1, 0, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 0, 1, 0}};
    for (const auto& t : tris) {
        for (float f : {0.f, 0.f, 1.f}) put(f);
        for (float f : t) put(f);
        put(std::uint16_t(0));
    }
    m = loadText("sq.stl", stl, &report);
    ASSERT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.positions.size(), 4u);  // welded
    for (std::size_t t = 0; t < 2; ++t) EXPECT_GT(faceNormal(m, t).z(), 0.99f);
}

TEST(Ingest, PlyListsBesideTheCornersAndBigEndianBinary) {
    // Two triangles of the unit square, each face also carrying a texcoord list and a colour,
    // and the vertices an unused property between the coordinates and the normals. OpenMesh's
    // own reader takes a list other than the corners for one value and reads the rest of the
    // file out of step; what reaches it now is only the values the mesh needs.
    const std::string header =
        "ply\nformat FORMAT 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar quality\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 2\n"
        "property list uchar int vertex_indices\nproperty list uchar float texcoord\nproperty uchar red\nend_header\n";
    const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const int faces[2][3] = {{0, 1, 2}, {0, 2, 3}};
    std::string ascii = header;
    ascii.replace(ascii.find("FORMAT"), 6, "ascii");
    for (const auto& c : corners) ascii += std::to_string(c[0]) + " " + std::to_string(c[1]) + " 0 7 0 0 1\n";
    for (const auto& f : faces)
        ascii += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) +
                 " 6 0 0 1 0 1 1 255\n";
    std::string binary = header;
    binary.replace(binary.find("FORMAT"), 6, "binary_big_endian");
    auto put = [&binary](auto value) {
        char b[sizeof value];
        std::memcpy(b, &value, sizeof value);
        std::reverse(b, b + sizeof value);  // the test machine is little-endian (x86-64)
        binary.append(b, sizeof value);
    };
    for (const auto& c : corners) {
        put(c[0]), put(c[1]), put(0.f), put(std::uint8_t(7)), put(0.f), put(0.f), put(1.f);
    }
    for (const auto& f : faces) {
        put(std::uint8_t(3)), put(std::int32_t(f[0])), put(std::int32_t(f[1])), put(std::int32_t(f[2]));
        put(std::uint8_t(6));
        for (float t : {0.f, 0.f, 1.f, 0.f, 1.f, 1.f}) put(t);
        put(std::uint8_t(255));
    }
    for (const auto& [name, bytes] : {std::pair{"lists_ascii.ply", ascii}, std::pair{"lists_big.ply", binary}}) {
        SCOPED_TRACE(name);
        IngestReport report;
        const TriangleMesh m = loadText(name, bytes, &report);
        ASSERT_EQ(m.triangles.size(), 2u);
        ASSERT_EQ(m.positions.size(), 4u);
        float area = 0;
        for (std::size_t t = 0; t < 2; ++t) {
            const Eigen::Vector3f a = m.positions[m.triangles[t][0]], b = m.positions[m.triangles[t][1]],
                                  c = m.positions[m.triangles[t][2]];
            area += 0.5f * (b - a).cross(c - a).z();
        }
        EXPECT_FLOAT_EQ(area, 1.0f);  // both faces, counter-clockwise seen from +z
    }
}

TEST(Ingest, OffFaceColoursCommentsAndNoffNormals) {
    // A plain OFF may give faces a colour; OpenMesh's reader left it on the stream, so the
    // next face took the colour for its corner count. NOFF normals are the file's, not computed.
    IngestReport report;
    TriangleMesh m = loadText("colours.off",
                              "OFF\n# a unit square\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                              "3 0 1 2 255 0 0\n3 0 2 3 0.5 0.5 0.5 1\n",
                              &report);
    ASSERT_EQ(m.triangles.size(), 2u);
    for (std::size_t t = 0; t < 2; ++t) EXPECT_GT(faceNormal(m, t).z(), 0.99f);
    m = loadText("normals.off",
                 "NOFF\n3 1 0\n0 0 0 0 0.6 0.8\n1 0 0 0 0.6 0.8\n0 1 0 0 0.6 0.8 1 1 1\n3 0 1 2\n", &report);
    ASSERT_EQ(m.normals.size(), 3u);
    for (const auto& n : m.normals) EXPECT_LT((n - Eigen::Vector3f(0, 0.6f, 0.8f)).norm(), 1e-6f);
}

TEST(Ingest, TextFormatsReadDecimalsBeyondFloatAlike) {
    // One triangle whose first corner's x is `x`, in each text format. Below float's range a
    // value is 0 (OBJ read 1e-400 as +inf and refused the file); above it, ±inf, refused.
    auto files = [](const std::string& x) {
        return std::vector<std::pair<std::string, std::string>>{
            {"tiny.obj", "v " + x + " 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
            {"tiny.off", "OFF\n3 1 0\n" + x + " 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
            {"tiny.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
                             x + " 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"}};
    };
    for (const auto& [name, bytes] : files("1e-400")) {
        const TriangleMesh m = loadText(name, bytes);
        ASSERT_EQ(m.triangles.size(), 1u) << name;
        EXPECT_EQ(std::count_if(m.positions.begin(), m.positions.end(), [](const auto& p) { return p.x() == 0.0f; }), 2)
            << name;
    }
    for (const auto& [name, bytes] : files("-1e999")) {
        try {
            loadText(name, bytes);
            ADD_FAILURE() << name << ": loaded";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("NaN or infinite"), std::string::npos) << e.what();
        }
    }
}

TEST(Ingest, MaxTrianglesIsEnforced) {
    IngestOptions options;
    options.maxTriangles = 11;
    EXPECT_THROW(loadText("cube_limit.obj", cubeObj(false), nullptr, options), InputError);
    options.maxTriangles = 12;
    EXPECT_NO_THROW(loadText("cube_limit.obj", cubeObj(false), nullptr, options));
}

TEST(Ingest, TexturedGltfFromDebianSamples) {
    const fs::path box = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
    if (!fs::exists(box)) GTEST_SKIP() << "assimp-testmodels not installed";
    IngestReport report;
    const TriangleMesh m = loadMesh(box, {}, &report);
    EXPECT_EQ(m.triangles.size(), 12u);
    ASSERT_EQ(m.textures.size(), 1u);
    EXPECT_EQ(m.textures[0].width, 211);
    EXPECT_EQ(m.uvs.size(), m.positions.size());
    EXPECT_TRUE(m.closed);
    expectOutward(m);
    // Written and read back, the texture travels inside the .glb.
    writeMeshGlb(m, tmp("box.glb"));
    const TriangleMesh back = loadMesh(tmp("box.glb"));
    ASSERT_EQ(back.textures.size(), 1u);
    EXPECT_EQ(back.textures[0].rgba, m.textures[0].rgba);
}

}  // namespace
