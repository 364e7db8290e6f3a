// A .vtl of finest voxels read straight into the octree builder's finest level (pyramid.h,
// readFinestLevel).
//
// readVtl reads the whole file into memory, checksums it, then decodes its blocks into a
// SparseVolume, which the builder copies into its pyramid: three arrays of the volume's size,
// the file's and the blocks' on one thread, before any filtering. On this project's VMs the
// pages a process touches first cost more than the work done on them, and a 512³ bush's file
// is 54 MB. Here the file is read a piece at a time into two small buffers, each piece
// checksummed as it arrives and decoded from all threads into the pyramid's level while the
// next piece is read.
#include "pyramid.h"
#include "vtl_records.h"

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

namespace vtex::octree::detail {
namespace {

// Records per piece: some 1.8 MB, small enough to stay in cache between its read and its decode,
// large enough that a 256³ file takes several pieces to overlap.
constexpr std::size_t kPieceRecords = std::size_t(1) << 15;

// Closes the descriptor it holds.
struct Descriptor {
    int fd;
    ~Descriptor() {
        if (fd >= 0) ::close(fd);
    }
};

// `size` bytes of the open file at `offset`; false if the file ends first or the read fails
// (readVtl, which the caller falls back to, then names the problem).
bool readAt(int fd, char* out, std::size_t size, std::uint64_t offset) {
    while (size > 0) {
        const ssize_t n = ::pread(fd, out, size, off_t(offset));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        out += n;
        size -= std::size_t(n);
        offset += std::uint64_t(n);
    }
    return true;
}

// The HEAD section's volume header, checked as parseVtl checks it, or std::nullopt.
std::optional<VolumeInfo> readHead(int fd, const TableEntry& entry, const std::filesystem::path& file) {
    std::string payload(entry.size, '\0');
    if (!readAt(fd, payload.data(), payload.size(), entry.offset) || checksum(payload) != entry.sum) return std::nullopt;
    ByteReader reader(payload);
    try {
        const VolumeInfo info = readVolumeInfo(reader, file, "HEAD");
        if (reader.remaining() != 0) return std::nullopt;
        return info;
    } catch (const InputError&) {
        return std::nullopt;
    }
}

// The header and the two sections' table entries, HEAD then VOXL (serializeVtl's order), the
// last ending where the file does; empty for anything else.
std::vector<TableEntry> readTableOf(int fd, std::uint64_t fileSize) {
    std::string head(kHeaderSize + 2 * kTableEntrySize, '\0');
    if (fileSize < head.size() || !readAt(fd, head.data(), head.size(), 0)) return {};
    std::uint32_t version = 0;
    std::vector<TableEntry> entries;
    std::string location;
    if (!readTable(head, fileSize, kVtlMagic, kVtlVersion, version, entries, location).empty()) return {};
    if (entries.size() != 2 || entries[0].tag != "HEAD" || entries[1].tag != "VOXL" ||
        entries[1].offset + entries[1].size != fileSize)
        return {};
    return entries;
}

// Decodes records [first, first + count) of the VOXL section, held in `records`, into
// nodes[first …]; `previous` is the record before them (null for the first block). False if a
// block is not a finest voxel or has a problem parseVtl would refuse it for.
bool decodePiece(const char* records, std::size_t count, std::uint64_t first, const char* previous,
                 std::uint32_t L, Level& nodes) {
    std::atomic<bool> ok{true};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end() && ok.load(std::memory_order_relaxed); ++i) {
            const char* record = records + kBlockRecordSize * i;
            const VolumeBlock b = decodeBlock(record);
            if (b.level != L || !blockProblem(b, i > 0 ? record - kBlockRecordSize : previous, L).empty()) {
                ok = false;
                return;
            }
            nodes[first + i] = sourceNode(b);
        }
    });
    return ok;
}

// The VOXL section's blocks into a level, or std::nullopt. Piece k + 1 is read and checksummed
// on one thread while piece k is decoded on the others.
std::optional<Level> readVoxels(int fd, const TableEntry& entry, std::uint32_t L) {
    char countBytes[8];
    if (entry.size < 8 || !readAt(fd, countBytes, 8, entry.offset)) return std::nullopt;
    ByteReader countReader(std::string_view(countBytes, 8));
    const std::uint64_t count = countReader.u64();
    const std::uint64_t recordBytes = entry.size - 8;
    if (count > recordBytes / kBlockRecordSize || count * kBlockRecordSize != recordBytes) return std::nullopt;
    StreamingChecksum sum;
    sum.update(std::string_view(countBytes, 8));
    Level nodes(count);
    std::vector<char> buffers[2];
    for (auto& buffer : buffers) buffer.resize(kBlockRecordSize * std::min<std::uint64_t>(count, kPieceRecords));
    char previous[kBlockRecordSize];  // the last record of the piece before the one decoded
    const auto readPiece = [&](std::uint64_t first, std::vector<char>& buffer) {
        const std::size_t bytes = kBlockRecordSize * std::size_t(std::min<std::uint64_t>(count - first, kPieceRecords));
        if (!readAt(fd, buffer.data(), bytes, entry.offset + 8 + kBlockRecordSize * first)) return false;
        sum.update(std::string_view(buffer.data(), bytes));
        return true;
    };
    if (count > 0 && !readPiece(0, buffers[0])) return std::nullopt;
    for (std::uint64_t first = 0, piece = 0; first < count; first += kPieceRecords, ++piece) {
        const std::vector<char>& current = buffers[piece % 2];
        const std::size_t size = std::size_t(std::min<std::uint64_t>(count - first, kPieceRecords));
        bool readOk = true, decodeOk = true;
        tbb::parallel_invoke(
            [&] {
                if (first + kPieceRecords < count) readOk = readPiece(first + kPieceRecords, buffers[(piece + 1) % 2]);
            },
            [&] { decodeOk = decodePiece(current.data(), size, first, first > 0 ? previous : nullptr, L, nodes); });
        if (!readOk || !decodeOk) return std::nullopt;
        std::memcpy(previous, current.data() + kBlockRecordSize * (size - 1), kBlockRecordSize);
    }
    if (sum.digest() != entry.sum) return std::nullopt;
    return nodes;
}

}  // namespace

std::optional<FinestLevel> readFinestLevel(const std::filesystem::path& file) {
    const std::uint64_t fileSize = checkInputFile(file, kMaxFileBytes, "file");  // readVtl's refusals
    const Descriptor descriptor{::open(file.c_str(), O_RDONLY | O_CLOEXEC)};
    if (descriptor.fd < 0) return std::nullopt;
    const std::vector<TableEntry> entries = readTableOf(descriptor.fd, fileSize);
    if (entries.empty()) return std::nullopt;
    // A solid interior holds blocks above the finest level: read as a SparseVolume.
    const std::optional<VolumeInfo> info = readHead(descriptor.fd, entries[0], file);
    if (!info || info->solidDensity != 0) return std::nullopt;
    std::optional<Level> nodes = readVoxels(descriptor.fd, entries[1], info->levels);
    if (!nodes) return std::nullopt;
    return FinestLevel{*info, std::move(*nodes)};
}

}  // namespace vtex::octree::detail
