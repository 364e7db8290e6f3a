// The container shared by .vtl and .vto files (docs/formats.md): a fixed header, a section
// table guarded by its own checksum, then the section payloads, each with an XXH3-64 checksum.
// Internal to vtex_octree.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::octree {
struct VoxelData;
struct VolumeInfo;
}  // namespace vtex::octree

namespace vtex::octree::detail {

static_assert(std::endian::native == std::endian::little || std::endian::native == std::endian::big);

/// Appends little-endian values to a byte string.
class ByteWriter {
public:
    void u8(std::uint8_t v) { mBytes.push_back(char(v)); }
    // Little-endian whatever the host, appended as one run (a node is eleven of these).
    void u32(std::uint32_t v) {
        char b[4];
        for (int i = 0; i < 4; ++i) b[i] = char((v >> (8 * i)) & 0xFF);
        mBytes.append(b, 4);
    }
    void u64(std::uint64_t v) {
        char b[8];
        for (int i = 0; i < 8; ++i) b[i] = char((v >> (8 * i)) & 0xFF);
        mBytes.append(b, 8);
    }
    void f32(float v) { u32(std::bit_cast<std::uint32_t>(v)); }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
    void bytes(std::string_view s) { mBytes.append(s); }
    void reserve(std::size_t n) { mBytes.reserve(n); }
    std::string& str() { return mBytes; }

private:
    std::string mBytes;
};

/// Reads little-endian values with bounds checks; `ok()` turns false on the first overrun and
/// every later read returns 0.
class ByteReader {
public:
    explicit ByteReader(std::string_view bytes) : mBytes(bytes) {}
    std::uint8_t u8() { return std::uint8_t(take(1) ? mBytes[mPos - 1] : 0); }
    std::uint32_t u32() {
        if (!take(4)) return 0;
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= std::uint32_t(std::uint8_t(mBytes[mPos - 4 + i])) << (8 * i);
        return v;
    }
    std::uint64_t u64() {
        if (!take(8)) return 0;
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t(std::uint8_t(mBytes[mPos - 8 + i])) << (8 * i);
        return v;
    }
    float f32() { return std::bit_cast<float>(u32()); }
    double f64() { return std::bit_cast<double>(u64()); }
    /// The next `n` bytes, or null (and ok() false) if fewer are left.
    const char* bytes(std::size_t n) { return take(n) ? mBytes.data() + mPos - n : nullptr; }
    bool ok() const { return mOk; }
    std::size_t remaining() const { return mBytes.size() - mPos; }

private:
    bool take(std::size_t n) {
        if (!mOk || mBytes.size() - mPos < n) {
            mOk = false;
            return false;
        }
        mPos += n;
        return true;
    }
    std::string_view mBytes;
    std::size_t mPos = 0;
    bool mOk = true;
};

struct OutSection {
    std::string tag;  ///< exactly 4 characters
    std::string payload;
};

struct InSection {
    std::string tag;
    std::string_view payload;
};

/// Header: 8-byte magic, u32 version, u32 section count, u64 table checksum; then per section
/// tag[4], u32 reserved (0), u64 offset, u64 size, u64 XXH3-64 of the payload.
inline constexpr std::size_t kHeaderSize = 24;
inline constexpr std::size_t kTableEntrySize = 32;
inline constexpr std::uint32_t kMaxSections = 64;

std::uint64_t checksum(std::string_view bytes);
/// The header's guard: the checksum of bytes 0–15 and of the section table, which ends at
/// `tableEnd`.
std::uint64_t tableChecksum(std::string_view bytes, std::size_t tableEnd);

/// One row of the section table: where a section's payload lies and its checksum.
struct TableEntry {
    std::string tag;
    std::uint64_t offset, size, sum;
};

/// Parses the header and section table from `bytes`, which hold at least the first
/// kHeaderSize + kTableEntrySize · count bytes of a file of `fileSize` bytes (the whole file, or
/// only its head for a reader that loads sections on demand). Returns a problem description
/// (and its `location`) or an empty string.
std::string readTable(std::string_view bytes, std::uint64_t fileSize, std::string_view magic,
                      std::uint32_t supportedVersion, std::uint32_t& version, std::vector<TableEntry>& entries,
                      std::string& location);

/// A tag as it may be printed in a message: bytes outside printable ASCII become '?'.
std::string printableTag(std::string_view raw);

/// The whole container as bytes.
std::string writeContainer(std::string_view magic, std::uint32_t version,
                           const std::vector<OutSection>& sections);

/// A section whose payload is made piece by piece while it is written: `size` bytes, which
/// `produce` hands to `emit` in order, in pieces of any size.
struct StreamedSection {
    std::string tag;  ///< exactly 4 characters
    std::uint64_t size = 0;
    std::function<void(const std::function<void(std::string_view)>& emit)> produce;
};
/// The container writeContainer makes of the same payloads, written to `file` atomically
/// (core/atomic_file.h): each piece is checksummed and written as it comes, and the header and
/// table, which hold the checksums, last, into the space left for them at the start. No payload
/// is ever whole in memory (a 1024³ texel's finest level is 0.2 GB).
void writeContainerFile(const std::filesystem::path& file, std::string_view magic, std::uint32_t version,
                        const std::vector<StreamedSection>& sections);

/// Checks magic, version, table and every section checksum; throws vtex::InputError naming
/// `kind` and the failing section.
std::vector<InSection> readContainer(std::string_view bytes, std::string_view magic,
                                     std::uint32_t supportedVersion, const std::filesystem::path& file);

/// The section with `tag`, or throws InputError("missing section").
std::string_view requireSection(const std::vector<InSection>& sections, std::string_view tag,
                                const std::filesystem::path& file);

/// "section 'TAG'" for error locations.
std::string sectionLocation(std::string_view tag);

/// The 44-byte voxel record: density, rotation (4), sigma (3), albedo (3), all f32.
inline constexpr std::size_t kVoxelRecordSize = 44;
void writeVoxelData(ByteWriter& w, const VoxelData& d);
/// The same record stored at `out` (kVoxelRecordSize bytes), for writers that fill a buffer
/// from several threads.
void storeVoxelData(char* out, const VoxelData& d);
/// The record at `in` (kVoxelRecordSize bytes, all in bounds): the one decoder of the layout
/// storeVoxelData writes, shared by readVoxelData and the .vtl reader's block records.
VoxelData loadVoxelData(const char* in);
/// The next record of `r`; past its end, the record of kVoxelRecordSize zero bytes.
VoxelData readVoxelData(ByteReader& r);
/// A problem with a parsed voxel (non-finite, negative, empty when not allowed), or empty.
std::string_view checkVoxelData(const VoxelData& d, bool allowEmpty);

/// Refuses a container with a section `known` does not accept, or one tag twice (the readers
/// take the first of each tag they ask for: a second HEAD would be silently ignored).
void requireKnownSections(const std::vector<InSection>& sections, const std::function<bool(std::string_view)>& known,
                          const std::filesystem::path& file);
void writeVolumeInfo(ByteWriter& w, const VolumeInfo& info);
VolumeInfo readVolumeInfo(ByteReader& r, const std::filesystem::path& file, std::string_view tag);

}  // namespace vtex::octree::detail
