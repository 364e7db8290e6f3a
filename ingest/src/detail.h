// Internal interface between the readers, the repair pass and the writers of vtex_ingest.
// Not installed: the fuzz targets and the tests include it through the source tree.
#pragma once

#include <vtex/ingest/ingest.h>
#include <vtex/ingest/mesh.h>

#include <Eigen/Core>

#include <array>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace vtex::ingest::detail {

inline constexpr std::uint32_t kNoGroup = 0xffffffffu;

/// What a reader hands to the repair pass: a triangle soup in world units with optional
/// per-vertex attributes. Indices are already checked against positions.size() (a reader
/// refuses or, with dropInvalidFaces, drops and counts a face that is not).
struct RawMesh {
    std::vector<Eigen::Vector3f> positions;
    /// Empty, or one per position; a non-finite or zero normal means "none, compute one".
    std::vector<Eigen::Vector3f> normals;
    std::vector<Eigen::Vector2f> uvs;  ///< empty, or one per position
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<std::uint32_t> triangleMaterials;  ///< empty, or one per triangle
    /// Empty, or one per triangle: index into `groups`, the file's face groups (OBJ `g`, glTF
    /// mesh names), which base meshes keep per face (QuadMesh::faceGroups).
    std::vector<std::uint32_t> triangleGroups;  ///< kNoGroup: in none
    std::vector<std::string> groups;
    /// Empty (every triangle is a face of its own), or per source polygon the number of
    /// consecutive triangles its fan from the first corner produced (base meshes need quads).
    std::vector<std::uint32_t> polygonTriangles;
    std::vector<Material> materials;
    std::vector<Image> textures;
    std::vector<std::string> warnings;
    RepairCounts repairs;  ///< the counts a reader already knows (invalidIndexFaces)
    std::string format;
    char up = 'z';  ///< the file's own up axis (IngestOptions::up)
};

/// A decimal number of a text format (OBJ, OFF, ASCII PLY): what std::from_chars reads, a
/// leading '+' allowed, rounded once to T. Beyond T's range it is ±inf, or 0 / a denormal below
/// it (strtod's reading), which repair refuses or drops by name. nullopt: not a number.
template <typename T>
std::optional<T> parseDecimal(std::string_view token) {
    static_assert(std::is_floating_point_v<T>);
    if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
    T value{};
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if ((ec != std::errc() && ec != std::errc::result_out_of_range) || end != token.data() + token.size())
        return std::nullopt;
    if (ec == std::errc::result_out_of_range) {
        const std::string text(token);
        if constexpr (std::is_same_v<T, float>) value = std::strtof(text.c_str(), nullptr);
        else value = T(std::strtod(text.c_str(), nullptr));
    }
    return value;
}

/// True when `candidate`, resolved through symbolic links, lies inside the directory `root`
/// (itself canonical) and is a regular file.
bool isContainedRegularFile(const std::filesystem::path& root, const std::filesystem::path& candidate);

// --- readers -----------------------------------------------------------------------------
// `file` names the input in error messages; `directory` is the folder external references may
// be read from (empty: none may be read, as for fuzzing from memory).

RawMesh readGltf(std::string_view bytes, bool binary, const std::filesystem::path& file,
                 const std::filesystem::path& directory, const IngestOptions& options);

/// Turns `raw` from its up axis (options.up, else raw.up) to +Z; returns the axis used.
char turnToZUp(RawMesh& raw, const IngestOptions& options);

/// Checks the JSON types of the glTF properties vtex relies on and the required extensions
/// (tinygltf silently skips a property of the wrong type). Throws InputError.
void checkGltfSchema(std::string_view json, const std::filesystem::path& file);

RawMesh readObj(std::string_view text, const std::filesystem::path& file,
                const std::filesystem::path& directory, const IngestOptions& options);

/// OFF (read here), PLY and STL (through OpenMesh, after checking every count the file claims
/// against the bytes present).
RawMesh readOffPlyStl(std::string_view bytes, const std::string& format,
                      const std::filesystem::path& file, const IngestOptions& options);

// --- repair ------------------------------------------------------------------------------

/// Non-finite faces, welding, degenerate and zero-area faces, normals, closedness and
/// outward orientation. Fills the counts and bounds of `report`. Throws InputError when no
/// triangle survives.
TriangleMesh repairMesh(RawMesh&& raw, const std::filesystem::path& file,
                        const IngestOptions& options, IngestReport& report);

/// Orients a closed, edge-manifold triangle mesh outward with CGAL Polygon Mesh Processing.
/// Returns, per triangle, whether it must be reversed; nullopt when CGAL finds the mesh not
/// closed or not orientable (then nothing is changed). Lives in its own translation unit
/// because CGAL adds -frounding-math.
std::optional<std::vector<char>> computeOutwardFlips(
    const std::vector<Eigen::Vector3d>& points,
    const std::vector<std::array<std::uint32_t, 3>>& triangles);

// --- images ------------------------------------------------------------------------------

/// Decodes a PNG or JPEG (by signature) to 8-bit RGBA after checking the declared size
/// against the caps. Returns nullopt and sets `why` for anything it cannot or will not decode.
std::optional<Image> decodeImage(std::string_view bytes, const IngestOptions& options,
                                 std::string& why);

}  // namespace vtex::ingest::detail
