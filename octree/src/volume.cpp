// The sampled finest level and the .vtl file format (docs/formats.md).
#include "container.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/input_file.h>
#include <vtex/octree/volume.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>

namespace vtex::octree {
namespace {

constexpr std::string_view kVtlMagic{"VTEX.VTL", 8};
// A block record: its key, level and flags, then the voxel record (detail::kVoxelRecordSize).
constexpr std::size_t kBlockHeaderSize = 8 + 1 + 1;
constexpr std::size_t kBlockRecordSize = kBlockHeaderSize + detail::kVoxelRecordSize;

bool allFinite(const VoxelData& d) {
    if (!std::isfinite(d.density)) return false;
    for (float v : d.rotation)
        if (!std::isfinite(v)) return false;
    for (float v : d.sigma)
        if (!std::isfinite(v)) return false;
    for (float v : d.albedo)
        if (!std::isfinite(v)) return false;
    return true;
}

// A little-endian value of the file at `p`, whatever the host.
template <class T>
T loadLittleEndian(const char* p) {
    static_assert(sizeof(T) == 4 || sizeof(T) == 8);
    using Bits = std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>;
    Bits bits;
    std::memcpy(&bits, p, sizeof bits);
    if constexpr (std::endian::native == std::endian::big)
        bits = sizeof bits == 4 ? Bits(__builtin_bswap32(std::uint32_t(bits))) : Bits(__builtin_bswap64(bits));
    return std::bit_cast<T>(bits);
}

// One kBlockRecordSize-byte record of the VOXL section (the layout serializeVtl writes): the
// whole record is in bounds, so no field needs ByteReader's checks. decodeBlockHeader: its key,
// level and flags alone (the voxel left empty).
VolumeBlock decodeBlockHeader(const char* record) {
    VolumeBlock b;
    b.key = loadLittleEndian<std::uint64_t>(record);
    b.level = std::uint8_t(record[8]);
    b.flags = std::uint8_t(record[9]);
    return b;
}
VolumeBlock decodeBlock(const char* record) {
    VolumeBlock b = decodeBlockHeader(record);
    b.data = detail::loadVoxelData(record + kBlockHeaderSize);
    return b;
}

}  // namespace

namespace detail {

void writeVoxelData(ByteWriter& w, const VoxelData& d) {
    char record[kVoxelRecordSize];
    storeVoxelData(record, d);
    w.bytes(std::string_view(record, kVoxelRecordSize));
}

void storeVoxelData(char* out, const VoxelData& d) {
    const auto f32 = [&out](float v) {
        const std::uint32_t bits = std::bit_cast<std::uint32_t>(v);
        for (int i = 0; i < 4; ++i) *out++ = char((bits >> (8 * i)) & 0xFF);  // little-endian on any host
    };
    f32(d.density);
    for (float v : d.rotation) f32(v);
    for (float v : d.sigma) f32(v);
    for (float v : d.albedo) f32(v);
}

VoxelData loadVoxelData(const char* in) {
    VoxelData d;
    d.density = loadLittleEndian<float>(in);
    for (float& v : d.rotation) v = loadLittleEndian<float>(in += 4);
    for (float& v : d.sigma) v = loadLittleEndian<float>(in += 4);
    for (float& v : d.albedo) v = loadLittleEndian<float>(in += 4);
    return d;
}

VoxelData readVoxelData(ByteReader& r) {
    static constexpr char kZeros[kVoxelRecordSize] = {};
    const char* record = r.bytes(kVoxelRecordSize);
    return loadVoxelData(record ? record : kZeros);
}

// Validates one stored voxel's values, not only its checksum (issue 14, item 8): finite,
// non-negative density; for a non-empty voxel a unit quaternion (to 1e-3: the format stores it
// normalised in float), σ non-negative and not all zero (S would vanish), and an albedo in
// [0, 1] (a glTF base colour is, and filtering averages it). Returns a problem or empty (a
// literal: no string is built for each of a file's millions of valid voxels).
std::string_view checkVoxelData(const VoxelData& d, bool allowEmpty) {
    if (!allFinite(d)) return "non-finite value";
    if (d.density < 0) return "negative density";
    if (!allowEmpty && d.density == 0) return "empty voxel stored";
    for (float v : d.sigma)
        if (v < 0) return "negative sigma";
    if (d.density == 0) return {};
    double norm = 0;
    for (float v : d.rotation) norm += double(v) * double(v);
    if (std::abs(std::sqrt(norm) - 1) > 1e-3) return "rotation is not a unit quaternion";
    if (!(d.sigma[0] > 0 || d.sigma[1] > 0 || d.sigma[2] > 0)) return "all sigma are zero";
    for (float v : d.albedo)
        if (v < 0 || v > 1.001f) return "albedo outside [0, 1]";
    return {};
}

void writeVolumeInfo(ByteWriter& w, const VolumeInfo& info) {
    w.u32(info.levels);
    w.u8(info.cyclic ? 1 : 0);
    w.f32(info.solidDensity);
    w.f64(info.scale);
    for (double v : info.offset) w.f64(v);
    w.u64(info.sourceTriangles);
    w.f64(info.sourceArea);
    w.u64(info.fitError.samples);
    w.f64(info.fitError.mean);
    w.f64(info.fitError.max);
}

VolumeInfo readVolumeInfo(ByteReader& r, const std::filesystem::path& file, std::string_view tag) {
    VolumeInfo info;
    info.levels = r.u32();
    const std::uint8_t cyclic = r.u8();
    info.cyclic = cyclic != 0;
    info.solidDensity = r.f32();
    info.scale = r.f64();
    for (double& v : info.offset) v = r.f64();
    info.sourceTriangles = r.u64();
    info.sourceArea = r.f64();
    info.fitError.samples = r.u64();
    info.fitError.mean = r.f64();
    info.fitError.max = r.f64();
    const std::string where = sectionLocation(tag);
    if (!r.ok()) throw InputError(file, "too short", where);
    if (info.levels > std::uint32_t(kMaxLevel))
        throw InputError(file, "resolution 2^" + std::to_string(info.levels) + " is beyond 2^20", where);
    if (cyclic > 1) throw InputError(file, "invalid cyclic flag", where);
    const bool finite = std::isfinite(info.solidDensity) && info.solidDensity >= 0 &&
                        std::isfinite(info.scale) && info.scale > 0 && std::isfinite(info.offset[0]) &&
                        std::isfinite(info.offset[1]) && std::isfinite(info.offset[2]) &&
                        std::isfinite(info.sourceArea) && info.sourceArea >= 0 &&
                        std::isfinite(info.fitError.mean) && std::isfinite(info.fitError.max);
    if (!finite) throw InputError(file, "invalid number in the header", where);
    return info;
}

}  // namespace detail

void SparseVolume::sortBlocks() {
    // Keys of disjoint blocks are distinct, so the order is unique; a read .vtl is already in it.
    const auto less = [this](const VolumeBlock& a, const VolumeBlock& b) { return finestKey(a) < finestKey(b); };
    if (!std::is_sorted(blocks.begin(), blocks.end(), less)) std::sort(blocks.begin(), blocks.end(), less);
}

double SparseVolume::totalMass() const {
    double mass = 0;
    for (const auto& b : blocks) mass += double(b.data.density) * std::ldexp(1.0, -3 * int(b.level));
    return mass;
}

std::string serializeVtl(const SparseVolume& volume) {
    using namespace detail;
    ByteWriter head;
    writeVolumeInfo(head, volume.info);
    ByteWriter voxels;
    voxels.reserve(8 + kBlockRecordSize * volume.blocks.size());
    voxels.u64(volume.blocks.size());
    for (const auto& b : volume.blocks) {
        voxels.u64(b.key);
        voxels.u8(b.level);
        voxels.u8(b.flags);
        writeVoxelData(voxels, b.data);
    }
    return writeContainer(kVtlMagic, kVtlVersion, {{"HEAD", head.str()}, {"VOXL", std::move(voxels.str())}});
}

SparseVolume parseVtl(std::string_view bytes, const std::filesystem::path& file) {
    using namespace detail;
    const auto sections = readContainer(bytes, kVtlMagic, kVtlVersion, file);
    requireKnownSections(sections, [](std::string_view tag) { return tag == "HEAD" || tag == "VOXL"; }, file);
    SparseVolume volume;
    ByteReader head(requireSection(sections, "HEAD", file));
    volume.info = readVolumeInfo(head, file, "HEAD");
    if (head.remaining() != 0) throw InputError(file, "unexpected trailing bytes", sectionLocation("HEAD"));

    const std::string where = sectionLocation("VOXL");
    const std::string_view payload = requireSection(sections, "VOXL", file);
    ByteReader reader(payload);
    const std::uint64_t count = reader.u64();
    if (!reader.ok() || count > reader.remaining() / kBlockRecordSize ||
        count * kBlockRecordSize != reader.remaining())
        throw InputError(file, "size does not match its block count " + std::to_string(count), where);
    const std::uint32_t L = volume.info.levels;
    const char* records = payload.data() + 8;
    // A block's problem, or empty; blocks i − 1 and i must not overlap (keys strictly in order).
    // The previous block is read from its record, which every thread can see, decoded or not.
    const auto problemAt = [&](std::uint64_t i) -> std::string_view {
        const VolumeBlock& b = volume.blocks[i];
        if (b.level > L) return "level deeper than the resolution";
        if (b.flags > kBlockSolid) return "unknown block flags";
        if (b.level < L && !b.isSolid()) return "coarse block that is not solid";
        if (b.key >= (std::uint64_t(1) << (3 * b.level))) return "key out of range";
        if (auto problem = checkVoxelData(b.data, false); !problem.empty()) return problem;
        if (i > 0) {
            // A level beyond L is the previous block's own problem, reported first.
            const VolumeBlock p = decodeBlockHeader(records + kBlockRecordSize * (i - 1));
            if (p.level <= L && volume.finestKey(b) < volume.finestKey(p) + (std::uint64_t(1) << (3 * (L - p.level))))
                return "blocks out of order or overlapping";
        }
        return {};
    };
    // Decoded and checked in one pass on all threads: the decode into reserved storage ran on
    // one core before the check (a 512³ bush holds 10⁶ blocks), and the check read every block
    // back. Sized first, which clears the blocks once; the error names the first bad block, as a
    // sequential reader would.
    volume.blocks.resize(count);
    std::atomic<std::uint64_t> firstBad{count};
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, count, 16384), [&](const auto& range) {
        for (std::uint64_t i = range.begin(); i != range.end() && i < firstBad.load(); ++i) {
            volume.blocks[i] = decodeBlock(records + kBlockRecordSize * i);
            if (!problemAt(i).empty()) {
                std::uint64_t seen = firstBad.load();
                while (i < seen && !firstBad.compare_exchange_weak(seen, i)) {}
                return;
            }
        }
    });
    if (firstBad < count)
        throw InputError(file, std::string(problemAt(firstBad)), where + ", block " + std::to_string(firstBad.load()));
    return volume;
}

void writeVtl(const SparseVolume& volume, const std::filesystem::path& file) {
    writeFileAtomically(file, serializeVtl(volume));
}

SparseVolume readVtl(const std::filesystem::path& file) {
    return parseVtl(readInputBytes(file, kMaxFileBytes, "file").view(), file);
}

}  // namespace vtex::octree
