// Every model of Debian's assimp-testmodels under glTF2/, OBJ/, OFF/, PLY/, STL/ and invalid/
// through `vtex ingest`: each is ingested (exit 0) or refused cleanly (exit 3, one line naming
// the file and the problem) — never a signal, never a hang (each run has a 60 s timeout).
// The table says which and why; a model that appears in the package but not in the table
// fails the test, so the table stays complete.
#include "run_vtex.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

namespace fs = std::filesystem;

namespace {

const fs::path kModels = "/usr/share/assimp/models";

struct Expectation {
    const char* path;      ///< relative to kModels
    int exitStatus;        ///< 0 ingested, 3 refused
    const char* message;   ///< for refusals: part of the one-line error
    const char* why;
};

// clang-format off
const Expectation kTable[] = {
    {"OBJ/WusonOBJ.obj", 0, "", "ingested"},
    {"OBJ/box.obj", 0, "", "ingested"},
    {"OBJ/box_UTF16BE.obj", 3, "UTF-16 text is not supported (convert th", "UTF-16 encoded OBJ: refused rather than guessed"},
    {"OBJ/box_longline.obj", 0, "", "ingested; very long line"},
    {"OBJ/box_mat_with_spaces.obj", 0, "", "ingested"},
    {"OBJ/box_without_lineending.obj", 0, "", "ingested; no final newline"},
    {"OBJ/concave_polygon.obj", 0, "", "ingested; polygon triangulated as a fan"},
    {"OBJ/cube_mtllib_after_g.obj", 0, "", "ingested"},
    {"OBJ/cube_usemtl.obj", 0, "", "ingested"},
    {"OBJ/cube_with_vertexcolors.obj", 0, "", "ingested; vertex colours ignored"},
    {"OBJ/cube_with_vertexcolors_uni.obj", 0, "", "ingested"},
    {"OBJ/empty_mat.obj", 0, "", "ingested"},
    {"OBJ/multiple_spaces.obj", 0, "", "ingested"},
    {"OBJ/number_formats.obj", 3, "bad number '3.1+e2'", "'3.1+e2' is not a number"},
    {"OBJ/point_cloud.obj", 3, "no faces", "points only"},
    {"OBJ/regr01.obj", 0, "", "ingested"},
    {"OBJ/regr_3429812.obj", 0, "", "ingested"},
    {"OBJ/space_in_material_name.obj", 0, "", "ingested; material name with a space"},
    {"OBJ/spider.obj", 0, "", "ingested"},
    {"OBJ/testline.obj", 3, "no faces (points and lines only)", "lines only"},
    {"OBJ/testmixed.obj", 0, "", "ingested"},
    {"OBJ/testpoints.obj", 3, "no faces (points and lines only)", "points only"},
    {"OFF/Cube.off", 0, "", "ingested"},
    {"OFF/Wuson.off", 0, "", "ingested"},
    {"OFF/formatDetection", 3, "unknown mesh format '' (expected .gltf, ", "no extension: vtex dispatches on the extension"},
    {"OFF/invalid.off", 3, "OFF header: bad vertex/face/edge counts", "header has 2 counts instead of 3"},
    {"PLY/Wuson.ply", 0, "", "ingested"},
    {"PLY/cube.ply", 0, "", "ingested"},
    {"PLY/cube_binary.ply", 0, "", "ingested; binary PLY"},
    {"PLY/cube_uv.ply", 0, "", "ingested"},
    {"PLY/float-color.ply", 0, "", "ingested"},
    {"PLY/issue623.ply", 3, "PLY 'vertex' record 0: '7.941797' does not read as uint8", "vertex element declares a list its records do not hold"},
    {"PLY/points.ply", 3, "no faces", "point cloud"},
    {"PLY/pond.0.ply", 3, "PLY header claims 70051 'vertex' element", "truncated binary point cloud (69 bytes short)"},
    {"STL/3DSMaxExport.STL", 0, "", "ingested"},
    {"STL/Spider_ascii.stl", 0, "", "ingested"},
    {"STL/Spider_binary.stl", 0, "", "ingested; binary STL"},
    {"STL/Wuson.stl", 0, "", "ingested"},
    {"STL/formatDetection", 3, "unknown mesh format '' (expected .gltf, ", "no extension: vtex dispatches on the extension"},
    {"STL/sphereWithHole.stl", 0, "", "ingested"},
    {"STL/triangle.stl", 0, "", "ingested"},
    {"STL/triangle_with_empty_solid.stl", 0, "", "ingested; empty solid ignored"},
    {"STL/triangle_with_two_solids.stl", 0, "", "ingested"},
    {"glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb", 0, "", "ingested"},
    {"glTF2/BoxBadNormals-glTF-Binary/BoxBadNormals.glb", 0, "", "ingested; invalid normals recomputed"},
    {"glTF2/BoxTexcoords-glTF/boxTexcoords.gltf", 0, "", "ingested"},
    {"glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", 0, "", "ingested"},
    {"glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf", 0, "", "ingested"},
    {"glTF2/BoxTextured-glTF-pbrSpecularGlossiness/BoxTextured.gltf", 0, "", "ingested"},
    {"glTF2/BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf", 3, "extensionsRequired: requires extension K", "requires KHR_technique_webgl"},
    {"glTF2/BoxTextured-glTF/BoxTextured.gltf", 0, "", "ingested"},
    {"glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", 3, "NaN or infinite coordinate at vertex 2 (", "Inf positions (strict default)"},
    {"glTF2/ClearCoat-glTF/ClearCoatTest.gltf", 0, "", "ingested"},
    {"glTF2/IncorrectVertexArrays/Cube.gltf", 3, "extends past the end of its buffer (offs", "bufferView past the end of its buffer"},
    {"glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf", 3, "index 65535 out of range (24 vertices)", "indices out of range"},
    {"glTF2/IndexOutOfRange/IndexOutOfRange.gltf", 3, "index 255 out of range (24 vertices)", "an index out of range (strict default)"},
    {"glTF2/MissingBin/BoxTextured.gltf", 3, "invalid glTF: File not found : BoxTextur", "buffer file missing"},
    {"glTF2/RecursiveNodes/RecursiveNodes.gltf", 3, "node cycle through node 0", "node cycle"},
    {"glTF2/SchemaFailures/sceneWrongType.gltf", 3, "must be a non-negative integer", "scene is a string"},
    {"glTF2/TestNoRootNode/NoScene.gltf", 3, "no triangles (points, lines or empty geo", "no mesh instanced"},
    {"glTF2/TestNoRootNode/SceneWithoutNodes.gltf", 3, "no triangles (points, lines or empty geo", "scene without nodes"},
    {"glTF2/cameras/Cameras.gltf", 0, "", "ingested; cameras ignored"},
    {"glTF2/draco/2CylinderEngine.gltf", 3, "extensionsRequired: requires extension K", "requires Draco compression"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_01.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_02.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_03.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_04.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_05.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_06.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_07.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_08.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_09.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_10.gltf", 3, "no triangles (points, lines or empty geo", "points or lines only"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_11.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_12.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_13.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_14.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_15.gltf", 0, "", "ingested"},
    {"glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf", 0, "", "ingested; morph targets ignored (rest pose)"},
    {"glTF2/issue_3269/texcoord_crash.gltf", 0, "", "ingested"},
    {"glTF2/simple_skin/simple_skin.gltf", 0, "", "ingested; skinning ignored (bind pose)"},
    {"glTF2/textureTransform/TextureTransformTest.gltf", 0, "", "ingested"},
    {"glTF2/wrongTypes/badArray.gltf", 3, "must be an array of objects", "primitives not an array of objects"},
    {"glTF2/wrongTypes/badExtension.gltf", 0, "", "ingested; an unknown extension body is ignored (not required)"},
    {"glTF2/wrongTypes/badNumber.gltf", 3, "required property 'index' is missing", "textureInfo without index"},
    {"glTF2/wrongTypes/badObject.gltf", 3, "must be an object", "pbrMetallicRoughness not an object"},
    {"glTF2/wrongTypes/badString.gltf", 3, "must be a string", "name is a number"},
    {"glTF2/wrongTypes/badUint.gltf", 3, "must be a non-negative integer", "texture index is a string"},
    {"invalid/OutOfMemory.off", 3, "OFF header claims 353535235358 vertices ", "claims 3.5e11 vertices in 309 bytes"},
    {"invalid/empty.3ds", 3, "unknown mesh format '.3ds' (expected .gl", "not a format vtex reads"},
    {"invalid/empty.ase", 3, "unknown mesh format '.ase' (expected .gl", "not a format vtex reads"},
    {"invalid/empty.lwo", 3, "unknown mesh format '.lwo' (expected .gl", "not a format vtex reads"},
    {"invalid/empty.md5mesh", 3, "unknown mesh format '.md5mesh' (expected", "not a format vtex reads"},
    {"invalid/empty.obj", 3, "empty file", "empty file"},
    {"invalid/empty.off", 3, "empty file", "empty file"},
    {"invalid/empty.ply", 3, "empty file", "empty file"},
    {"invalid/empty.raw", 3, "unknown mesh format '.raw' (expected .gl", "not a format vtex reads"},
    {"invalid/empty.smd", 3, "unknown mesh format '.smd' (expected .gl", "not a format vtex reads"},
    {"invalid/empty.x", 3, "unknown mesh format '.x' (expected .gltf", "not a format vtex reads"},
    {"invalid/emptyIrrMesh.xml", 3, "unknown mesh format '.xml' (expected .gl", "not a format vtex reads"},
    {"invalid/malformed.obj", 3, "vertex index 12 out of range", "vertex index out of range"},
    {"invalid/malformed2.obj", 3, "face with fewer than 3 vertices", "face with 2 corners"},
};
// clang-format on

struct Outcome {
    int exitStatus = -1;
    int signal = 0;
    std::string err;
};

Outcome ingestWithTimeout(const fs::path& input, const fs::path& output) {
    const fs::path errPath = fs::path(VTEX_TEST_TMP) / "testmodels.err";
    const std::string command = "timeout -s KILL 60 " + vtex::test::shellQuote(VTEX_BINARY) + " ingest " +
                                vtex::test::shellQuote(input.string()) + " -o " +
                                vtex::test::shellQuote(output.string()) + " </dev/null >/dev/null 2>" +
                                vtex::test::shellQuote(errPath.string());
    const int raw = std::system(command.c_str());
    Outcome outcome;
    if (WIFEXITED(raw)) {
        outcome.exitStatus = WEXITSTATUS(raw);
        if (outcome.exitStatus > 128) outcome.signal = outcome.exitStatus - 128;  // 137: timeout's KILL
    } else if (WIFSIGNALED(raw)) {
        outcome.signal = WTERMSIG(raw);
    }
    outcome.err = vtex::test::readText(errPath);
    return outcome;
}

bool isModel(const fs::path& path) {
    static const std::set<std::string> kSkip = {".png", ".jpg", ".bin", ".mtl", ".txt", ".md", ".vert", ".frag"};
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return !kSkip.count(extension) && path.filename() != "LICENSE";
}

TEST(AssimpTestModels, TableCoversEveryModel) {
    if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels is not installed";
    std::set<std::string> listed;
    for (const auto& e : kTable) listed.insert(e.path);
    for (const char* folder : {"glTF2", "OBJ", "OFF", "PLY", "STL", "invalid"})
        for (const auto& entry : fs::recursive_directory_iterator(kModels / folder)) {
            if (!entry.is_regular_file() || !isModel(entry.path())) continue;
            EXPECT_TRUE(listed.count(fs::relative(entry.path(), kModels).string()))
                << fs::relative(entry.path(), kModels) << " is not in the table";
        }
}

TEST(AssimpTestModels, EachIsIngestedOrRefusedCleanly) {
    if (!fs::exists(kModels)) GTEST_SKIP() << "assimp-testmodels is not installed";
    const fs::path outDir = fs::path(VTEX_TEST_TMP) / "testmodels";
    fs::create_directories(outDir);
    for (const auto& e : kTable) {
        SCOPED_TRACE(std::string(e.path) + " (" + e.why + ")");
        const fs::path input = kModels / e.path;
        if (!fs::exists(input)) continue;  // another package version
        const fs::path output = outDir / "out.glb";
        fs::remove(output);
        const Outcome outcome = ingestWithTimeout(input, output);
        ASSERT_EQ(outcome.signal, 0) << "killed by a signal (or the timeout): " << outcome.err;
        EXPECT_EQ(outcome.exitStatus, e.exitStatus) << outcome.err;
        if (e.exitStatus == 0) {
            EXPECT_TRUE(fs::exists(output));
        } else {
            EXPECT_FALSE(fs::exists(output));
            EXPECT_EQ(vtex::test::lineCount(outcome.err), 1u) << outcome.err;
            EXPECT_NE(outcome.err.find(input.string()), std::string::npos) << outcome.err;
            EXPECT_NE(outcome.err.find(e.message), std::string::npos) << outcome.err;
        }
    }
}

}  // namespace
