// A texel per face (issue 16): a base face's texel, placement and height come from its material
// or group through a surface's `texels`; both renderers draw a surface so mapped exactly as they
// draw the same faces given as separate surfaces. And a triangulated quad grid renders as the
// quad grid it was.
#include "fixtures.h"

#include <vtex/core/error.h>
#include <vtex/ingest/base_mesh.h>
#include <vtex/render/compare.h>
#include <vtex/render/reference.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

namespace fs = std::filesystem;

// An opaque block in one corner of the reference volume (x, y < ½, z < ½ of 4³): a texel whose
// orientation shows.
std::shared_ptr<const vtex::octree::Octree> cornerBlock() {
    return makeOctree(2, [](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        if (x < 2 && y < 2 && z < 2) return sphereVoxel(40.0f, {0.9f, 0.5f, 0.2f});
        return std::nullopt;
    });
}

// A row of three unit quads along x; face f's material is `materials[f]` ("" for none).
std::shared_ptr<vtex::ingest::QuadMesh> namedRow(const std::array<std::string, 3>& materials) {
    auto mesh = gridMesh(0, 0, 3, 1, 0, 1);
    mesh->positions.clear();
    mesh->normals.clear();
    mesh->quads.clear();
    for (int j = 0; j <= 1; ++j)
        for (int i = 0; i <= 3; ++i) {
            mesh->positions.emplace_back(float(i), float(j), 0.f);
            mesh->normals.emplace_back(0.f, 0.f, 1.f);
        }
    for (std::uint32_t i = 0; i < 3; ++i) mesh->quads.push_back({i, i + 1, i + 5, i + 4});
    for (const std::string& name : materials) {
        std::uint32_t index = vtex::ingest::QuadMesh::kNoName;
        if (!name.empty()) {
            const auto it = std::find(mesh->names.begin(), mesh->names.end(), name);
            index = std::uint32_t(it - mesh->names.begin());
            if (it == mesh->names.end()) mesh->names.push_back(name);
        }
        mesh->faceNames.push_back({index, vtex::ingest::QuadMesh::kNoName});
    }
    return mesh;
}

// Face f of the row alone, as its own mesh.
std::shared_ptr<vtex::ingest::QuadMesh> rowFace(int f) { return gridMesh(f, 0, f + 1, 1, 0, 1); }

Scene rowScene() {
    Scene scene = baseScene(Eigen::Vector3d(1.5, -2.5, 2.5), Eigen::Vector3d(1.5, 0.5, 0.2), 45, 64);
    addTexel(scene, cornerBlock());  // t0
    addTexel(scene, cornerBlock());  // t1
    return scene;
}

// The row with `grass` faces under t0 0.3 high and the `bush` face under t1 0.6 high, placed
// under; the unnamed face plain.
Scene mappedRow() {
    Scene scene = rowScene();
    addSurface(scene, namedRow({"grass", "bush", ""}), std::nullopt, 0.3);
    SurfaceDef& s = scene.surfaces.back();
    TexelPlacing grass;
    grass.texel = 0;
    grass.height = 0.3;
    TexelPlacing bush = grass;
    bush.texel = 1;
    bush.height = 0.6;
    bush.placement = Placement::Under;
    s.texels = {{"bush", bush}, {"grass", grass}};
    return scene;
}

// The same faces as three surfaces.
Scene separateRow() {
    Scene scene = rowScene();
    addSurface(scene, rowFace(0), 0, 0.3);
    addSurface(scene, rowFace(1), 1, 0.6);
    scene.surfaces.back().placement = Placement::Under;
    addSurface(scene, rowFace(2), std::nullopt);
    return scene;
}

RenderResult referenceQuiet(const Scene& scene) {
    vtex::NullProgress progress;
    ReferenceOptions options;
    options.spp = 1;
    return renderReference(scene, options, progress);
}

fs::path tmp(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / "vtex_per_face_test";
    fs::create_directories(dir);
    return dir / name;
}

void writeText(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

}  // namespace

// The texel renderer: a surface whose faces take their texels by material draws as the same
// faces given one surface each, and not as the surface with one texel everywhere.
TEST(PerFaceTexels, TexelRenderDrawsEachMaterialsTexel) {
    RenderOptions options;
    options.spp = 1;
    const RenderResult mapped = renderQuiet(mappedRow(), options);
    const RenderResult separate = renderQuiet(separateRow(), options);
    EXPECT_EQ(mapped.stats.cells, 2u);  // the plain face is no cell
    EXPECT_EQ(mapped.stats.faces, 3u);
    const ImageComparison same = compareImages(mapped.image, separate.image);
    EXPECT_LT(same.rmse, 1e-6) << "worst (" << same.worstX << ", " << same.worstY << ") " << same.worstError;
    Scene uniform = mappedRow();
    uniform.surfaces[0].texels.clear();
    uniform.surfaces[0].texel = 0;
    EXPECT_GT(compareImages(mapped.image, renderQuiet(uniform, options).image).rmse, 0.01);
}

// The reference renderer honours the same map.
TEST(PerFaceTexels, ReferenceDrawsEachMaterialsTexel) {
    const auto source = std::make_shared<vtex::ingest::TriangleMesh>();
    // The corner block's source: the box [0, ½]³.
    for (int i = 0; i < 8; ++i) source->positions.emplace_back(i & 1 ? 0.5f : 0.f, i & 2 ? 0.5f : 0.f, i & 4 ? 0.5f : 0.f);
    source->triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                         {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    source->normals.assign(8, Eigen::Vector3f(0, 0, 1));
    source->materials.emplace_back();
    source->closed = true;
    Scene mapped = mappedRow(), separate = separateRow();
    for (Scene* scene : {&mapped, &separate})
        for (TexelDef& t : scene->texels) t.sourceData = source;
    const RenderResult a = referenceQuiet(mapped), b = referenceQuiet(separate);
    const ImageComparison same = compareImages(a.image, b.image);
    EXPECT_LT(same.rmse, 1e-6) << "worst (" << same.worstX << ", " << same.worstY << ") " << same.worstError;
    Scene uniform = mapped;
    uniform.surfaces[0].texels.clear();
    uniform.surfaces[0].texel = 0;
    EXPECT_GT(compareImages(a.image, referenceQuiet(uniform).image).rmse, 0.01);
}

// A `texels` entry that names no face of the mesh (a misspelt material) is refused, naming the
// key, rather than leaving its faces plain.
TEST(PerFaceTexels, AnEntryNamingNoFaceIsRefused) {
    Scene scene = mappedRow();
    scene.file = "row.toml";
    scene.surfaces[0].texels[0].name = "bushes";
    try {
        renderQuiet(scene);
        FAIL() << "rendered";
    } catch (const vtex::InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("row.toml"), std::string::npos) << what;
        EXPECT_NE(what.find("surface[0].texels.bushes"), std::string::npos) << what;
    }
}

// From files: an OBJ whose faces name their materials (no material library) and a scene that maps
// them; the group of a face serves where its material is not mapped.
TEST(PerFaceTexels, SceneFileMapsObjMaterialsAndGroups) {
    writeText(tmp("row.obj"),
              "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 1 0\n"
              "g lawn\nusemtl grass\nf 1 2 6 5\nusemtl bush\nf 2 3 7 6\ng path\nusemtl stone\nf 3 4 8 7\n");
    const auto mesh = vtex::ingest::loadBaseMesh(tmp("row.obj"));
    ASSERT_EQ(mesh.faceNames.size(), 3u);
    EXPECT_EQ(mesh.names[mesh.faceNames[1][0]], "bush");
    EXPECT_EQ(mesh.names[mesh.faceNames[2][1]], "path");
    const std::string scene = R"([camera]
position = [1.5, -2.5, 2.5]
look_at = [1.5, 0.5, 0.2]
[[light]]
type = "directional"
direction = [0, 0, -1]
[[texel]]
name = "lawn"
volume = "lawn.vto"
[[texel]]
name = "hedge"
volume = "hedge.vto"
[[surface]]
mesh = "row.obj"
height = 0.3
texels = { bush = { texel = "hedge", height = 0.6, placement = "under" }, path = "lawn" }
)";
    const Scene s = parseScene(scene, tmp("row.toml"));
    ASSERT_EQ(s.surfaces[0].texels.size(), 2u);
    const auto placings = facePlacings(s, 0, mesh);
    ASSERT_EQ(placings.size(), 3u);
    EXPECT_EQ(placings[0], 0u);  // grass/lawn: neither is mapped
    EXPECT_EQ(s.surfaces[0].placing(placings[1]).texel, 1u);
    EXPECT_DOUBLE_EQ(s.surfaces[0].placing(placings[1]).height, 0.6);
    EXPECT_EQ(s.surfaces[0].placing(placings[1]).placement, Placement::Under);
    EXPECT_EQ(s.surfaces[0].placing(placings[2]).texel, 0u);  // stone is not mapped, its group path is
    EXPECT_DOUBLE_EQ(s.surfaces[0].placing(placings[2]).height, 0.3);  // the surface's
    EXPECT_FALSE(s.surfaces[0].placing(0).texel.has_value());
}

// A quad grid exported triangulated, each quad cut along one diagonal or the other, renders as
// the quad grid: as many cells as quads, the same cells, the same image (the texel's corner block
// shows any cell that came back turned or cut).
TEST(PerFaceTexels, ATriangulatedGridRendersAsItsQuads) {
    constexpr int n = 3;
    std::string vertices, quads, triangles;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) vertices += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
            const auto f = [](int x, int y, int z) {
                return "f " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
            };
            quads += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
            triangles += (i + j) % 2 ? f(a, b, c) + f(a, c, d) : f(a, b, d) + f(b, c, d);
        }
    writeText(tmp("grid_quads.obj"), vertices + quads);
    writeText(tmp("grid_triangles.obj"), vertices + triangles);
    const auto render = [](const fs::path& mesh) {
        Scene scene = baseScene(Eigen::Vector3d(1.5, -2.0, 3.5), Eigen::Vector3d(1.5, 1.5, 0), 50, 64);
        addTexel(scene, cornerBlock());
        addSurface(scene, std::make_shared<vtex::ingest::QuadMesh>(vtex::ingest::loadBaseMesh(mesh)), 0, 0.4);
        RenderOptions options;
        options.spp = 1;
        return renderQuiet(scene, options);
    };
    const RenderResult fromQuads = render(tmp("grid_quads.obj")), fromTriangles = render(tmp("grid_triangles.obj"));
    EXPECT_EQ(fromTriangles.stats.cells, std::uint64_t(n * n));
    EXPECT_EQ(fromTriangles.stats.cells, fromQuads.stats.cells);
    const ImageComparison same = compareImages(fromTriangles.image, fromQuads.image);
    // Identical cells: the images agree to the rounding of the BVH (measured: 0).
    EXPECT_LT(same.rmse, 1e-6) << "worst (" << same.worstX << ", " << same.worstY << ") " << same.worstError;
}
