// loadBaseMesh (ingest/base_mesh.h): quads kept, triangulated quads put back together, names per
// face, one vertex per distinct OBJ corner and normals shared by the vertices at one point.
#include "gltf_builder.h"

#include <vtex/ingest/base_mesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace fs = std::filesystem;
using namespace vtex;
using namespace vtex::ingest;
using vtex::test::GltfBuilder;

namespace {

fs::path tmp(const std::string& name) { return test::tmpFile("base_mesh", name); }

TEST(BaseMesh, QuadsStayQuadsTrianglesCollapse) {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nv 3 0 0\n"
                            "f 1 2 3 4\nf 2 5 6 3\nf 5 7 6\n";
    test::writeBytes(tmp("base.obj"), obj);
    const QuadMesh q = loadBaseMesh(tmp("base.obj"));
    ASSERT_EQ(q.quads.size(), 3u);
    EXPECT_FALSE(q.isTriangle(0));
    EXPECT_FALSE(q.isTriangle(1));
    EXPECT_TRUE(q.isTriangle(2));
    EXPECT_EQ(q.quads[0], (std::array<std::uint32_t, 4>{0, 1, 2, 3}));
    ASSERT_EQ(q.normals.size(), q.positions.size());
    for (const auto& n : q.normals) EXPECT_TRUE(n.isApprox(Eigen::Vector3f(0, 0, 1)));
    test::writeBytes(tmp("base.off"),
                    "OFF\n7 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n3 0.5 0\n4 0 1 2 3\n5 1 4 6 5 2\n");
    const QuadMesh off = loadBaseMesh(tmp("base.off"));
    ASSERT_EQ(off.quads.size(), 3u);  // a quad, then a pentagon as a quad and a triangle
    EXPECT_FALSE(off.isTriangle(1));
    EXPECT_TRUE(off.isTriangle(2));
    for (const auto& n : off.normals) EXPECT_TRUE(n.isApprox(Eigen::Vector3f(0, 0, 1))) << n.transpose();
}

// A quad grid exported triangulated (as Blender writes it with "Triangulate Faces") comes back
// as its quads (issue 16): each pair of triangles on a quad's diagonal is one cell again, starting
// at the quad's own first corner, wound counter-clockwise; triangles that were not a quad stay
// triangles.
TEST(BaseMesh, ATriangulatedGridComesBackAsItsQuads) {
    constexpr int n = 4;
    std::string obj;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(j) + " " + std::to_string(0.1 * i * j) + "\n";
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 2, d = a + n + 1;  // OBJ counts from 1
            // Alternate the diagonal, as exporters do not all cut the same way.
            if ((i + j) % 2) obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\nf " +
                                    std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
            else obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(d) + "\nf " +
                        std::to_string(b) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
        }
    obj += "v 10 0 0\nv 11 0 0\nv 10 1 0\nf 26 27 28\n";  // a lone triangle
    test::writeBytes(tmp("triangulated.obj"), obj);
    const QuadMesh q = loadBaseMesh(tmp("triangulated.obj"));
    ASSERT_EQ(q.quads.size(), std::size_t(n * n + 1));
    // Corners by their (x, y), each quad turned to start at its smallest: the reader numbers
    // vertices in its own order, and a quad may start at any corner.
    using Corners = std::array<std::pair<float, float>, 4>;
    const auto canonical = [](Corners c) {
        std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
        return c;
    };
    std::set<Corners> expected, quads;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            expected.insert(canonical({std::pair(float(i), float(j)), std::pair(float(i + 1), float(j)),
                                       std::pair(float(i + 1), float(j + 1)), std::pair(float(i), float(j + 1))}));
    int triangles = 0, lowerLeftCells = 0;
    for (std::size_t f = 0; f < q.quads.size(); ++f) {
        if (q.isTriangle(f)) {
            ++triangles;
            continue;
        }
        Corners c;
        for (int k = 0; k < 4; ++k) c[std::size_t(k)] = {q.positions[q.quads[f][std::size_t(k)]].x(), q.positions[q.quads[f][std::size_t(k)]].y()};
        quads.insert(canonical(c));
        // Every pair, a fan or cut along the other diagonal, starts at the quad's own first
        // corner: its lower left here.
        const auto& first = q.positions[q.quads[f][0]];
        const bool lowerLeft = first.x() == std::min({c[0].first, c[1].first, c[2].first, c[3].first}) &&
                               first.y() == std::min({c[0].second, c[1].second, c[2].second, c[3].second});
        EXPECT_TRUE(lowerLeft) << f;
        lowerLeftCells += lowerLeft;
    }
    EXPECT_EQ(quads, expected);
    EXPECT_EQ(lowerLeftCells, n * n);
    EXPECT_EQ(triangles, 1);
}

// Base faces keep their material and group names (a scene's `texels` maps them to texels,
// issue 16): OBJ `usemtl` (with or without a material library) and `g`, glTF material and mesh
// names. Two triangles of different materials are never merged into one quad, even where they
// would make a perfect one.
TEST(BaseMesh, FacesKeepTheirMaterialAndGroupNames) {
    test::writeBytes(tmp("named.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                                       "g left\nusemtl grass\nf 1 2 3\nf 1 3 4\ng right\nf 2 5 6\nusemtl bush\nf 2 6 3\n");
    const QuadMesh q = loadBaseMesh(tmp("named.obj"));
    ASSERT_EQ(q.quads.size(), 3u);  // the left pair merged; the right pair is of two materials
    ASSERT_EQ(q.faceNames.size(), 3u);
    std::multiset<std::pair<std::string, std::string>> faces;
    for (std::size_t f = 0; f < q.quads.size(); ++f)
        faces.insert({q.names.at(q.faceNames[f][0]), q.names.at(q.faceNames[f][1])});
    EXPECT_EQ(faces, (std::multiset<std::pair<std::string, std::string>>{{"grass", "left"}, {"grass", "right"}, {"bush", "right"}}));
    EXPECT_FALSE(q.isTriangle(0));

    GltfBuilder b;
    const int pos = b.positions({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    const int idx = b.indices({0, 1, 2, 0, 2, 3});
    b.doc["materials"] = {{{"name", "moss"}}};
    b.meshNode({{"attributes", {{"POSITION", pos}}}, {"indices", idx}, {"material", 0}});
    b.doc["meshes"][0]["name"] = "roof";
    test::writeBytes(tmp("named.gltf"), b.gltfEmbedded());
    const QuadMesh g = loadBaseMesh(tmp("named.gltf"));
    ASSERT_EQ(g.quads.size(), 1u);
    ASSERT_EQ(g.faceNames.size(), 1u);
    EXPECT_EQ(g.names.at(g.faceNames[0][0]), "moss");
    EXPECT_EQ(g.names.at(g.faceNames[0][1]), "roof");
    // A file that names nothing leaves the table empty.
    test::writeBytes(tmp("unnamed.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    const QuadMesh u = loadBaseMesh(tmp("unnamed.obj"));
    EXPECT_TRUE(u.faceNames.empty());
    EXPECT_TRUE(u.names.empty());
}

// An OBJ corner is a (position, texture coordinate, normal) triple: each distinct one is one
// vertex, numbered by first use, whether it repeats its position's first corner (the reader's
// table by position) or another one (its map); vertices at one position (a UV seam) get one
// area-weighted normal.
TEST(BaseMesh, EveryDistinctCornerIsOneVertexInOrderOfFirstUse) {
    const std::string obj = "v 0 0 0\nv 1 0 0.5\nv 1 1 0.5\nv 0 1 0\nv 2 0 0\nv 2 1 0\nv 9 9 9\n"
                            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0\nvt 0.5 1\n"
                            "f 1/1 2/2 3/3 4/4\n"
                            "f 2/5 5/2 6/3 3/6\n"   // positions 2 and 3 again, with other UVs: a seam
                            "f 2/5 5/2 6/3 3/6\n"   // the same corners: no new vertex
                            "f 1/1 2/2 3/3 4/4\n";
    test::writeBytes(tmp("seam.obj"), obj);
    const QuadMesh q = loadBaseMesh(tmp("seam.obj"));
    ASSERT_EQ(q.quads.size(), 4u);
    EXPECT_EQ(q.quads[0], (std::array<std::uint32_t, 4>{0, 1, 2, 3}));
    EXPECT_EQ(q.quads[1], (std::array<std::uint32_t, 4>{4, 5, 6, 7}));
    EXPECT_EQ(q.quads[2], q.quads[1]);
    EXPECT_EQ(q.quads[3], q.quads[0]);
    ASSERT_EQ(q.positions.size(), 8u);  // position 7 is used by no face
    ASSERT_EQ(q.uvs.size(), 8u);
    const std::array<Eigen::Vector3f, 8> positions = {
        Eigen::Vector3f(0, 0, 0), {1, 0, 0.5f}, {1, 1, 0.5f}, {0, 1, 0}, {1, 0, 0.5f}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0.5f}};
    // (The reader turns OBJ's v up to glTF's v down: 1 − v.)
    const std::array<Eigen::Vector2f, 8> uvs = {
        Eigen::Vector2f(0, 1), {1, 1}, {1, 0}, {0, 0}, {0.5f, 1}, {1, 1}, {1, 0}, {0.5f, 0}};
    for (std::size_t v = 0; v < 8; ++v) {
        EXPECT_EQ(q.positions[v], positions[v]) << v;
        EXPECT_EQ(q.uvs[v], uvs[v]) << v;
    }
    // The ridge x = 1 is shared by a face rising along +x and one falling: the seam's two
    // vertices at each of its points have one normal, the mean of both faces' (each counted
    // twice, as the file has each face twice), which points along +z.
    EXPECT_EQ(q.normals[1], q.normals[4]);
    EXPECT_EQ(q.normals[2], q.normals[7]);
    EXPECT_NEAR(q.normals[1].x(), 0, 1e-6);
    EXPECT_NEAR(q.normals[1].z(), 1, 1e-6);
    EXPECT_NEAR(q.normals[0].x(), -0.5f / std::sqrt(1.25f), 1e-6);  // the rising face's alone
}

// −0 and +0 are one point: the two vertices a file writes there share their normal.
TEST(BaseMesh, NegativeZeroIsTheSamePointAsZero) {
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                            "v -0 -0 -0\nv 0 1 0\nv -1 1 1\nv -1 0 1\n"
                            "f 1 2 3 4\nf 5 6 7 8\n";
    test::writeBytes(tmp("zero.obj"), obj);
    const QuadMesh q = loadBaseMesh(tmp("zero.obj"));
    ASSERT_EQ(q.positions.size(), 8u);
    ASSERT_TRUE(std::signbit(q.positions[4].x()));
    EXPECT_EQ(q.normals[0], q.normals[4]);
    EXPECT_EQ(q.normals[3], q.normals[5]);
    // The mean of the flat face's +z and the tilted face's (1, 0, 1)/√2, each weighted by area
    // (1 and √2): (1, 0, 2)/√5.
    EXPECT_NEAR(q.normals[0].x(), 1 / std::sqrt(5.f), 1e-6);
    EXPECT_NEAR(q.normals[0].z(), 2 / std::sqrt(5.f), 1e-6);
    EXPECT_EQ(q.normals[1], Eigen::Vector3f(0, 0, 1));
}

}  // namespace
