// `vtex export scene.toml -o layout.glb`: the base meshes and the texel cells read back with
// tinygltf, the cells' corners where the scene's shells are (on and under the faces).
#include "run_vtex.h"
#include "scratch_dir.h"
#include "texel_fixture.h"

#include <tiny_gltf.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace vtex::interop {
namespace {

namespace fs = std::filesystem;

fs::path folder() { return test::scratchDir("layout"); }

// Two 1×1 quads side by side at z = 0 and one triangle at z = 5, as an OBJ.
void writeMeshes(const fs::path& dir) {
    std::ofstream(dir / "ground.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n"
                                         "f 1 2 5 4\nf 2 3 6 5\n";
    std::ofstream(dir / "roof.obj") << "v 0 0 5\nv 1 0 5\nv 0 1 5\nf 1 2 3\n";
}

void writeScene(const fs::path& file, const std::string& placement) {
    std::ofstream(file) << "[camera]\nposition = [0, -6, 3]\nlook_at = [0, 0, 0]\n"
                           "[[texel]]\nname = \"bush\"\nvolume = \"texel.vto\"\ntau = 2\n"
                           "[[surface]]\nmesh = \"ground.obj\"\ntexel = \"bush\"\nheight = 0.25\nplacement = \""
                        << placement
                        << "\"\nrepeat = [2, 3]\n"
                           "[[surface]]\nmesh = \"roof.obj\"\n";
}

tinygltf::Model load(const fs::path& file) {
    tinygltf::TinyGLTF loader;
    // No image decoding (/work/shared/deps.md: stb's decoder is not safe): the layout has none.
    loader.SetImageLoader([](tinygltf::Image*, int, std::string*, std::string*, int, int, const unsigned char*, int,
                             void*) { return true; },
                          nullptr);
    tinygltf::Model model;
    std::string err, warn;
    EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, file.string())) << err;
    EXPECT_TRUE(err.empty()) << err;
    return model;
}

std::vector<float> positions(const tinygltf::Model& model, const tinygltf::Primitive& primitive) {
    const tinygltf::Accessor& a = model.accessors[std::size_t(primitive.attributes.at("POSITION"))];
    const tinygltf::BufferView& v = model.bufferViews[std::size_t(a.bufferView)];
    std::vector<float> out(a.count * 3);
    std::memcpy(out.data(), model.buffers[std::size_t(v.buffer)].data.data() + v.byteOffset + a.byteOffset,
                out.size() * sizeof(float));
    return out;
}

const tinygltf::Node* node(const tinygltf::Model& model, const std::string& name) {
    for (const tinygltf::Node& n : model.nodes)
        if (n.name == name) return &n;
    return nullptr;
}

struct Layout {
    tinygltf::Model model;
    fs::path file;
};

Layout exportLayout(const std::string& placement) {
    const fs::path dir = folder();
    writeMeshes(dir);
    octree::writeVto(test::exportTestOctree(), dir / "texel.vto");
    writeScene(dir / ("scene_" + placement + ".toml"), placement);
    const fs::path out = dir / ("layout_" + placement + ".glb");
    const auto r = test::runVtex({"export", (dir / ("scene_" + placement + ".toml")).string(), "-o", out.string()});
    EXPECT_EQ(r.exitStatus, 0) << r.err;
    return {load(out), out};
}

TEST(LayoutGlb, HoldsTheBaseMeshesAndOneHexahedronPerCell) {
    const Layout layout = exportLayout("on");
    const tinygltf::Model& model = layout.model;
    const tinygltf::Node* ground = node(model, "surface0 ground.obj");
    const tinygltf::Node* cells = node(model, "surface0 cells bush");
    const tinygltf::Node* roof = node(model, "surface1 roof.obj");
    ASSERT_TRUE(ground && cells && roof);
    EXPECT_FALSE(node(model, "surface1 cells bush")) << "a plain surface has no cells";
    EXPECT_EQ(model.scenes.at(0).nodes.size(), 3u);

    const tinygltf::Mesh& groundMesh = model.meshes[std::size_t(ground->mesh)];
    EXPECT_EQ(model.accessors[std::size_t(groundMesh.primitives.at(0).indices)].count, 2u * 2 * 3);  // 2 quads
    const tinygltf::Mesh& roofMesh = model.meshes[std::size_t(roof->mesh)];
    EXPECT_EQ(model.accessors[std::size_t(roofMesh.primitives.at(0).indices)].count, 3u);  // a collapsed quad

    const tinygltf::Mesh& cellMesh = model.meshes[std::size_t(cells->mesh)];
    ASSERT_EQ(cellMesh.primitives.size(), 2u);
    EXPECT_EQ(cellMesh.primitives[0].mode, TINYGLTF_MODE_TRIANGLES);
    EXPECT_EQ(cellMesh.primitives[1].mode, TINYGLTF_MODE_LINE);
    EXPECT_EQ(model.accessors[std::size_t(cellMesh.primitives[0].indices)].count, 2u * 12 * 3);
    EXPECT_EQ(model.accessors[std::size_t(cellMesh.primitives[1].indices)].count, 2u * 12 * 2);
    // The shell of height 0.25 on the faces (normals +z): each cell is the box over its quad,
    // corner i + 2j + 4k at (x0 + i, j, 0.25 k).
    const std::vector<float> p = positions(model, cellMesh.primitives[0]);
    ASSERT_EQ(p.size(), 2u * 8 * 3);
    for (int cell = 0; cell < 2; ++cell)
        for (int c = 0; c < 8; ++c) {
            const float* q = &p[std::size_t(3 * (8 * cell + c))];
            EXPECT_FLOAT_EQ(q[0], float(cell + (c & 1))) << cell << " " << c;
            EXPECT_FLOAT_EQ(q[1], float((c >> 1) & 1)) << cell << " " << c;
            EXPECT_FLOAT_EQ(q[2], 0.25f * float(c >> 2)) << cell << " " << c;
        }

    const tinygltf::Value& vtex = cells->extras.Get("vtex");
    ASSERT_TRUE(vtex.IsObject());
    EXPECT_EQ(vtex.Get("texel").Get<std::string>(), "bush");
    EXPECT_EQ(vtex.Get("tau").GetNumberAsDouble(), 2.0);
    EXPECT_EQ(vtex.Get("height").GetNumberAsDouble(), 0.25);
    EXPECT_EQ(vtex.Get("placement").Get<std::string>(), "on");
    EXPECT_EQ(vtex.Get("repeat").Get(1).GetNumberAsDouble(), 3.0);
    EXPECT_NE(vtex.Get("volume").Get<std::string>().find("texel.vto"), std::string::npos);
    EXPECT_EQ(model.materials[std::size_t(cellMesh.primitives[0].material)].alphaMode, "BLEND");
}

TEST(LayoutGlb, AShellUnderTheFaceEndsAtTheFace) {
    const Layout layout = exportLayout("under");
    const tinygltf::Node* cells = node(layout.model, "surface0 cells bush");
    ASSERT_TRUE(cells);
    const std::vector<float> p = positions(layout.model, layout.model.meshes[std::size_t(cells->mesh)].primitives[0]);
    for (std::size_t c = 0; c < p.size() / 3; ++c)
        EXPECT_FLOAT_EQ(p[3 * c + 2], (c % 8) >= 4 ? 0.f : -0.25f) << "corner " << c;
}

TEST(LayoutGlb, BadUsageAndBadScenesAreRefused) {
    const fs::path dir = folder();
    writeMeshes(dir);
    writeScene(dir / "scene.toml", "on");
    const std::string scene = (dir / "scene.toml").string();
    EXPECT_EQ(test::runVtex({"export", scene, "-o", (dir / "x.vdb").string()}).exitStatus, 2);
    EXPECT_EQ(test::runVtex({"export", scene, "-o", (dir / "x.glb").string(), "--level", "2"}).exitStatus, 2);
    EXPECT_EQ(test::runVtex({"export", scene, "-o", (dir / "x.glb").string(), "--scale", "2"}).exitStatus, 2);
    EXPECT_EQ(test::runVtex({"export", scene, "-o", scene}).exitStatus, 3);  // its own input
    std::ofstream(dir / "nomesh.toml") << "[camera]\nposition = [0, -6, 3]\nlook_at = [0, 0, 0]\n"
                                          "[[surface]]\nmesh = \"missing.obj\"\n";
    const auto r = test::runVtex({"export", (dir / "nomesh.toml").string(), "-o", (dir / "x.glb").string()});
    EXPECT_EQ(r.exitStatus, 3) << r.err;
    EXPECT_NE(r.err.find("missing.obj"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "x.glb"));
    EXPECT_FALSE(fs::exists(dir / "x.vdb"));

    // A face at the float limit under a shell of 1e30: the cell's top is beyond what glTF holds.
    std::ofstream(dir / "edge.obj") << "v 0 0 3.4028234663852886e38\nv 1 0 3.4028234663852886e38\n"
                                       "v 1 1 3.4028234663852886e38\nv 0 1 3.4028234663852886e38\nf 1 2 3 4\n";
    std::ofstream(dir / "edge.toml") << "[camera]\nposition = [0, -6, 3]\nlook_at = [0, 0, 0]\n"
                                        "[[texel]]\nname = \"t\"\nvolume = \"t.vto\"\n"
                                        "[[surface]]\nmesh = \"edge.obj\"\ntexel = \"t\"\nheight = 1e30\n";
    const auto edge = test::runVtex({"export", (dir / "edge.toml").string(), "-o", (dir / "x.glb").string()});
    EXPECT_EQ(edge.exitStatus, 3) << edge.err;
    EXPECT_NE(edge.err.find("beyond the float range"), std::string::npos) << edge.err;
    EXPECT_FALSE(fs::exists(dir / "x.glb"));
}

}  // namespace
}  // namespace vtex::interop
