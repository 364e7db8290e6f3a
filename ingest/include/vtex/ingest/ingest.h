/// @file
/// @brief Loading untrusted source geometry into a canonical TriangleMesh, and writing it.
///
/// Formats: glTF 2.0 (.gltf with external, embedded or data-URI buffers; .glb) read with
/// tinygltf; OFF, PLY and STL read with OpenMesh after a pre-check of the sizes their headers
/// claim; OBJ (+ MTL `Kd`) read by vtex's own bounded parser (see obj_reader.cpp for why).
/// Every input is untrusted: anything malformed, truncated, hostile or absurd is refused with a
/// vtex::InputError whose message is one line naming the file and the problem; nothing is
/// allocated beyond what the bytes of the file really hold, and no file outside the input's
/// folder is ever read.
#pragma once

#include <vtex/ingest/mesh.h>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace vtex {
class AtomicOutputFile;
class Progress;
}

namespace vtex::ingest {

/// Limits and policies of loadMesh(). The defaults suit interactive use on a workstation.
struct IngestOptions {
    /// Refuse a mesh with more triangles than this (after triangulation and instancing).
    std::uint64_t maxTriangles = 50'000'000;
    /// Refuse any single file (the input, an external buffer, an image, an MTL) larger than this.
    std::uint64_t maxFileBytes = std::uint64_t(4) << 30;
    /// Refuse a texture wider or taller than this, or with more pixels than maxTexturePixels,
    /// before decoding it.
    int maxTextureDimension = 16384;
    std::uint64_t maxTexturePixels = std::uint64_t(64) << 20;
    /// Vertices closer than this fraction of the bounding-box diagonal are merged.
    double weldTolerance = 1e-7;
    /// false (default): an index out of range or a NaN/Inf coordinate used by a face refuses
    /// the file, as the robustness contract asks. true: such faces are dropped and counted in
    /// IngestReport::repairs (the file is still refused if no triangle survives).
    bool dropInvalidFaces = false;
    /// Orient closed meshes outward with CGAL (the normals follow).
    bool orientClosed = true;
    /// The file's up axis, turned to vtex's +Z up by a rotation (exact in float: coordinates are
    /// permuted and negated): 'x', 'y' or 'z'; 0 (the default) takes the file's own convention,
    /// +Y for glTF (its specification's; Blender's exporter writes it) except the canonical .glb
    /// vtex itself writes (asset.generator "vtex …", already +Z), +Z for OBJ, OFF, PLY and STL.
    char up = 0;
    /// Scale the mesh uniformly and move it so that its bounding box fits the unit cube, centred
    /// in x and y with its base at z = 0 (`--fit cell`: a model ready to be sampled as a texel);
    /// false keeps its coordinates.
    bool fitCell = false;
    /// Coarse progress (one phase per step); never printed by the library.
    Progress* progress = nullptr;
};

/// What the repairs changed, counted in triangles unless named otherwise.
struct RepairCounts {
    std::uint64_t invalidIndexFaces = 0;    ///< referenced a vertex out of range (dropInvalidFaces)
    std::uint64_t nonFiniteFaces = 0;       ///< used a NaN/Inf coordinate (dropInvalidFaces)
    std::uint64_t degenerateFaces = 0;      ///< two corners the same vertex after merging
    std::uint64_t zeroAreaFaces = 0;        ///< area below (tolerance · diagonal)²
    std::uint64_t mergedVertices = 0;       ///< vertices merged into another (positions)
    std::uint64_t unreferencedVertices = 0; ///< vertices no face used, dropped
    std::uint64_t recomputedNormals = 0;    ///< vertices whose file normal was missing or invalid
    std::uint64_t flippedNormals = 0;       ///< file normals turned to agree with the winding
    std::uint64_t flippedFaces = 0;         ///< faces reversed to orient a closed mesh outward
};

/// What loadMesh() read and did; toJson() gives the report `vtex ingest --report` writes.
struct IngestReport {
    std::string file;
    std::string format;  ///< "gltf", "glb", "obj", "off", "ply", "stl"
    std::uint64_t verticesIn = 0;
    std::uint64_t trianglesIn = 0;  ///< after triangulation, before repair
    std::uint64_t verticesOut = 0;
    std::uint64_t trianglesOut = 0;
    std::uint64_t materials = 0;
    std::uint64_t textures = 0;
    Eigen::Vector3f boundsMin{0, 0, 0};
    Eigen::Vector3f boundsMax{0, 0, 0};
    bool closed = false;
    char up = 'z';            ///< the up axis the file was read with (turned to +Z)
    bool fitCell = false;     ///< fitted to the unit cell: positions = scale · p + offset
    double fitScale = 1;
    Eigen::Vector3d fitOffset{0, 0, 0};
    RepairCounts repairs;
    std::vector<std::string> warnings;
    double seconds = 0.0;  ///< wall time of loadMesh()
};

/// The report as a JSON document (pretty-printed, newline-terminated).
std::string toJson(const IngestReport& report);

/// Loads, validates and repairs a .gltf/.glb/.obj/.off/.ply/.stl file (by extension) into a
/// canonical mesh: node transforms baked in, polygons triangulated, valid unit normals,
/// orientation fixed outward when closed. Throws vtex::InputError naming the file and the
/// problem for anything malformed.
TriangleMesh loadMesh(const std::filesystem::path& file);

/// As above with explicit limits; fills `report` (may be null).
TriangleMesh loadMesh(const std::filesystem::path& file, const IngestOptions& options,
                      IngestReport* report = nullptr);

/// Writes the canonical mesh as a binary glTF (.glb) atomically: one buffer, float positions,
/// normals and (if any) UVs shared by one indexed TRIANGLES primitive per material, base-colour
/// textures embedded as PNG. Any glTF viewer opens it. Throws vtex::IoError.
void writeMeshGlb(const TriangleMesh& mesh, const std::filesystem::path& file);
/// The same into an output the caller commits (commitAll: several outputs all or none).
void writeMeshGlb(const TriangleMesh& mesh, AtomicOutputFile& out);

/// The .glb bytes writeMeshGlb() would write (for tests and in-memory pipelines).
std::string encodeMeshGlb(const TriangleMesh& mesh);

}  // namespace vtex::ingest
