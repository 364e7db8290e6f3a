/// @file
/// @brief A texel's levels as an OpenVDB file, for Blender, Houdini and Nuke (docs/export.md).
///
/// Each exported level L is eight grids: `density` (FloatGrid, fog volume: the extinction a
/// volume renderer integrates, τ·ρ per world unit — the direction-averaged extinction, since the
/// normalised projected area Â has mean 1, DESIGN.md "The micro-primitive"), `albedo`
/// (Vec3SGrid, linear RGB) and `sggx_xx`, `sggx_yy`, `sggx_zz`, `sggx_xy`, `sggx_xz`, `sggx_yz`
/// (FloatGrids, the entries of the normalised SGGX matrix S: the extinction along a unit ω is
/// density · √(ωᵀSω)). All share one topology: a stored node of level L is an active voxel, a
/// stored leaf above it a constant region, filled as OpenVDB tiles where its nodes allow
/// (level_export.h). Voxel size 2^−L reference units times `scale`.
///
/// No OpenVDB type appears here: its headers cost ~22 s a translation unit and stay in
/// src/vdb_grids.cpp, compiled into the module vtex_vdb.so that writeVdb loads (src/vdb_module.h).
#pragma once

#include <vtex/octree/octree.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace vtex::interop {

/// True when this build can write .vdb files (OpenVDB was found at configure time).
inline constexpr bool kHasOpenVdb = VTEX_HAVE_OPENVDB != 0;

/// Where a voxel's value sits in index space. OpenVDB (and Houdini) centre voxel i on the index
/// coordinate i, so it covers [i − ½, i + ½]; Blender's Cycles (3.4) draws it over [i, i + 1]
/// (measured by bench/blender_transmittance.sh, docs/export.md). The transform is shifted by half
/// a voxel for the second, so that either reader puts the texel on its world box.
enum class VoxelCentres { OpenVdb, Blender };

struct VdbExportOptions {
    /// The levels to write, each in [0, levelCount); empty: the finest. With more than one, every
    /// grid name carries its level (`density_L3`); with one, the names are bare (`density`), as
    /// Blender's Principled Volume expects.
    std::vector<std::uint32_t> levels;
    /// The density → extinction constant τ (a scene's texel `tau`, 1 by default as there).
    double tau = 1;
    /// World length of one reference unit: the copy is placed at p_world = scale · p_ref +
    /// translate. density is per world unit (τ·ρ / scale), so the copy's optical depths along
    /// corresponding paths are the texel's whatever its size, as a vtex render's are.
    double scale = 1;
    std::array<double, 3> translate{0, 0, 0};
    VoxelCentres centres = VoxelCentres::OpenVdb;
    /// Empty: `density` is the direction-averaged extinction τ·ρ/scale. A unit direction ω: the
    /// extinction along ω, τ·ρ·√(ωᵀSω)/scale, what vtex renders for a view or light from ω (for a
    /// renderer without anisotropy and a fixed view).
    std::optional<std::array<double, 3>> along;
    /// What wrote the file, for the metadata (`vtex_version`): "0.1.0 (commit …)".
    std::string writer;
    /// The .vto's file name, for the metadata (`vtex_source`); may be empty.
    std::string source;
};

/// The grid name of `quantity` ("density", "albedo", "sggx_xx", …) at `level` when `suffixed`.
inline std::string vdbGridName(const std::string& quantity, std::uint32_t level, bool suffixed) {
    return suffixed ? quantity + "_L" + std::to_string(level) : quantity;
}

/// What one exported level became (OpenVDB's own counts of the written grids).
struct VdbLevelSummary {
    std::uint32_t level = 0;
    std::uint64_t activeVoxels = 0;      ///< voxels the level stands for (in tiles and leaf nodes)
    std::uint64_t leafVoxels = 0;        ///< of those, voxels stored one by one in leaf nodes
    std::uint64_t tiles = 0;             ///< active tiles (constant regions of 8³ voxels and up)
    std::uint64_t memoryBytes = 0;       ///< the density grid's in-memory size
};

/// Writes the grids of `options.levels` of `octree` to `file` atomically (core/atomic_file.h).
/// Throws std::out_of_range for a level the octree does not have (before anything is written),
/// vtex::IoError when the file cannot be written, std::runtime_error in a build without OpenVDB.
std::vector<VdbLevelSummary> writeVdb(const octree::Octree& octree, const VdbExportOptions& options,
                                      const std::filesystem::path& file);

}  // namespace vtex::interop
