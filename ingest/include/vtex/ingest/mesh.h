/// @file
/// @brief The canonical triangle mesh that ingest produces and every later stage reads.
///
/// World (source) units, right-handed, triangles counter-clockwise seen from the side their
/// normal points to. A mesh that passed ingest holds no NaN/Inf, no index out of range, no
/// zero-area triangle; `closed` says whether it is watertight and oriented outward.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::ingest {

/// A decoded base-colour texture: 8-bit RGBA, rows top to bottom, sRGB-encoded as glTF stores
/// base colour (convert to linear before averaging).
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgba;  ///< width · height · 4 bytes
};

/// PNG bytes of `image` (8-bit RGBA as stored, so sRGB stays sRGB). Throws std::runtime_error
/// when its size does not match its pixels or libpng fails.
std::string encodePng(const Image& image);

/// The 8-bit RGBA pixels of PNG `bytes` (any bit depth or colour type libpng reads), within the
/// texture limits of the default IngestOptions (16384 a side, 64 Mi pixels, checked before any
/// pixel is allocated); std::nullopt with the reason in `why` when they are not a PNG or too large.
std::optional<Image> decodePngRgba(std::string_view bytes, std::string& why);

/// The linear RGB base colour of `image` at texture coordinates (u, v): bilinear, glTF's
/// default REPEAT wrapping, sRGB decoded before filtering (averaging encoded values would
/// darken edges). White for an empty image or a non-finite coordinate.
Eigen::Vector3f sampleBaseColour(const Image& image, float u, float v);

struct Material {
    /// glTF baseColorFactor, linear RGBA.
    Eigen::Vector4f baseColorFactor{1.0f, 1.0f, 1.0f, 1.0f};
    /// Index into TriangleMesh::textures, or -1 for none; sampled at the vertex UVs.
    int baseColorTexture = -1;
    /// The file's name for it (OBJ `usemtl`/`newmtl`, glTF `materials[i].name`); may be empty.
    std::string name;
};

struct TriangleMesh {
    std::vector<Eigen::Vector3f> positions;
    std::vector<Eigen::Vector3f> normals;     ///< unit, one per position
    std::vector<Eigen::Vector2f> uvs;         ///< empty, or one per position (glTF convention)
    std::vector<std::array<std::uint32_t, 3>> triangles;
    std::vector<std::uint32_t> triangleMaterials;  ///< empty (all use material 0) or one per triangle
    std::vector<Material> materials;               ///< at least one once ingested
    std::vector<Image> textures;
    bool closed = false;  ///< watertight and consistently oriented outward
};

}  // namespace vtex::ingest
