/// @file
/// @brief The sampled finest level of a texel (what a .vtl file holds): sparse, never N³.
///
/// The reference volume is the unit cube with N = 2^L voxels per side. Surface voxels are stored
/// one by one at level L; the solid interior of a closed mesh is stored as whole octree-aligned
/// blocks at coarser levels (a block at level k stands for its 8^(L−k) voxels, all equal), so
/// storage follows the surface, not the volume. Empty space is not stored.
#pragma once

#include <vtex/octree/voxel.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::octree {

/// VolumeBlock::flags: the block is solid interior (not surface).
inline constexpr std::uint8_t kBlockSolid = 1;

/// A stored voxel or uniform block: `key` is the Morton key at `level` (≤ the finest level).
struct VolumeBlock {
    std::uint64_t key = 0;
    std::uint8_t level = 0;
    std::uint8_t flags = 0;  ///< kBlockSolid or 0 (surface)
    VoxelData data;
    bool isSolid() const { return (flags & kBlockSolid) != 0; }
    friend bool operator==(const VolumeBlock&, const VolumeBlock&) = default;
};

/// A half-open box of finest-level voxel indices [min, max).
struct VoxelBox {
    std::array<std::uint32_t, 3> min{0, 0, 0};
    std::array<std::uint32_t, 3> max{0, 0, 0};
    bool contains(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
        return x >= min[0] && x < max[0] && y >= min[1] && y < max[1] && z >= min[2] && z < max[2];
    }
    bool isEmpty() const { return min[0] >= max[0] || min[1] >= max[1] || min[2] >= max[2]; }
    friend bool operator==(const VoxelBox&, const VoxelBox&) = default;
};

/// Summary of the ellipsoid fits (Ellipsoid::fitNormals against its facets, fitError()),
/// measured on a deterministic sample of the surface voxels.
struct FitErrorStats {
    std::uint64_t samples = 0;
    double mean = 0;
    double max = 0;
    friend bool operator==(const FitErrorStats&, const FitErrorStats&) = default;
};

struct VolumeInfo {
    std::uint32_t levels = 0;  ///< L: N = 2^L voxels per side
    bool cyclic = false;       ///< sampled with periodic x and y
    float solidDensity = 0;    ///< ρ of solid interior voxels (0 when none was filled)
    /// Source world coordinates → reference (unit cube): p_ref = p_world · scale + offset.
    double scale = 1;
    std::array<double, 3> offset{0, 0, 0};
    std::uint64_t sourceTriangles = 0;
    double sourceArea = 0;  ///< total area of the source mesh, reference units²
    FitErrorStats fitError;
    friend bool operator==(const VolumeInfo&, const VolumeInfo&) = default;

    std::uint32_t resolution() const { return std::uint32_t(1) << levels; }
};

struct SparseVolume {
    VolumeInfo info;
    /// Sorted by the key of each block's first finest voxel (key << 3·(L − level)); blocks do
    /// not overlap.
    std::vector<VolumeBlock> blocks;
    friend bool operator==(const SparseVolume&, const SparseVolume&) = default;

    /// The Morton key, at the finest level, of a block's first voxel.
    std::uint64_t finestKey(const VolumeBlock& block) const {
        return block.key << (3 * (info.levels - block.level));
    }
    /// Sorts `blocks` into the canonical order.
    void sortBlocks();
    /// Σ ρ · (volume of the block): twice the surface area held, plus ρ_solid × solid volume.
    double totalMass() const;
};

/// .vtl file format version written by this program (docs/formats.md).
inline constexpr std::uint32_t kVtlVersion = 1;

/// Serialises to the .vtl byte layout (docs/formats.md).
std::string serializeVtl(const SparseVolume& volume);
/// Parses and validates .vtl bytes; `file` names the source in errors. Throws vtex::InputError
/// (bad magic, future version, truncated or corrupted section, inconsistent content), naming
/// the failing section.
SparseVolume parseVtl(std::string_view bytes, const std::filesystem::path& file);

/// Writes atomically. Throws vtex::IoError.
void writeVtl(const SparseVolume& volume, const std::filesystem::path& file);
/// Reads and validates. Throws vtex::InputError / vtex::IoError.
SparseVolume readVtl(const std::filesystem::path& file);

/// Per-section checksum status of a .vtl or .vto file, for `vtex inspect`: never throws on
/// corrupted content (only when the file cannot be read at all).
struct SectionStatus {
    std::string tag;
    std::uint64_t size = 0;
    bool checksumOk = false;
};
struct FileCheck {
    bool headerOk = false;  ///< magic, version and section table are readable and intact
    std::uint32_t version = 0;
    std::string problem;    ///< the first problem found, empty when everything is intact
    std::vector<SectionStatus> sections;
};
/// Checks the container of any vtex binary file (magic given as 8 bytes) without parsing it.
FileCheck checkFile(std::string_view bytes, std::string_view magic, std::uint32_t supportedVersion);

/// The largest .vtl or .vto file the readers accept (1 TiB).
inline constexpr std::uint64_t kMaxFileBytes = std::uint64_t(1) << 40;

/// Reads a whole file into memory, refusing anything above `maxBytes`. Throws vtex::IoError /
/// vtex::InputError.
std::string readFileBytes(const std::filesystem::path& file, std::uint64_t maxBytes = kMaxFileBytes);

}  // namespace vtex::octree
