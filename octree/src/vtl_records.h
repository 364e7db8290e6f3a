// The .vtl's block records (docs/formats.md), decoded and checked one at a time: shared by
// parseVtl (volume.cpp), which reads a whole file into a SparseVolume, and readFinestLevel
// (vtl_stream.cpp), which streams a file of finest voxels into the octree builder. Internal to
// vtex_octree.
#pragma once

#include "container.h"

#include <vtex/octree/volume.h>

#include <cstdint>
#include <string_view>

namespace vtex::octree::detail {

inline constexpr std::string_view kVtlMagic{"VTEX.VTL", 8};
// A block record: its key, level and flags, then the voxel record (kVoxelRecordSize).
inline constexpr std::size_t kBlockHeaderSize = 8 + 1 + 1;
inline constexpr std::size_t kBlockRecordSize = kBlockHeaderSize + kVoxelRecordSize;

// One kBlockRecordSize-byte record of the VOXL section (the layout serializeVtl writes): the
// whole record is in bounds, so no field needs ByteReader's checks. decodeBlockHeader: its key,
// level and flags alone (the voxel left empty).
VolumeBlock decodeBlockHeader(const char* record);
VolumeBlock decodeBlock(const char* record);

// The problem of block `b` of a volume of 2^L voxels a side, or empty. `previousRecord`: the
// record before it in the file, or null for the first; the two must not overlap (finest keys
// strictly in order).
std::string_view blockProblem(const VolumeBlock& b, const char* previousRecord, std::uint32_t L);

}  // namespace vtex::octree::detail
