// The sectioned, checksummed container of .vtl and .vto files (docs/formats.md).
#include "container.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/input_file.h>
#include <vtex/octree/volume.h>

// Debian's libxxhash, compiled inline into this translation unit: the static vtex_octree then
// carries no link-time dependency that an installed consumer would have to find.
#define XXH_INLINE_ALL
#include <xxhash.h>

#include <fstream>
#include <memory>
#include <new>
#include <sstream>
#include <stdexcept>

namespace vtex::octree::detail {

std::uint64_t checksum(std::string_view bytes) { return XXH3_64bits(bytes.data(), bytes.size()); }

std::string sectionLocation(std::string_view tag) { return "section '" + std::string(tag) + "'"; }

std::string printableTag(std::string_view raw) {
    std::string tag;
    for (char c : raw) tag += (c >= 0x20 && c < 0x7F) ? c : '?';
    return tag;
}

std::uint64_t tableChecksum(std::string_view bytes, std::size_t tableEnd) {
    // The first 16 bytes (magic, version, count) and the table, skipping the checksum field.
    std::string guarded(bytes.substr(0, 16));
    guarded.append(bytes.substr(kHeaderSize, tableEnd - kHeaderSize));
    return checksum(guarded);
}

namespace {

// The header and section table of a container whose sections have the tags, sizes and
// checksums of `entries` (their offsets follow from the sizes), in that order.
std::string containerHeader(std::string_view magic, std::uint32_t version, const std::vector<TableEntry>& entries) {
    ByteWriter header;
    header.bytes(magic);
    header.u32(version);
    header.u32(std::uint32_t(entries.size()));
    header.u64(0);  // table checksum, filled below
    std::uint64_t offset = kHeaderSize + kTableEntrySize * entries.size();
    for (const auto& entry : entries) {
        header.bytes(entry.tag);
        header.u32(0);
        header.u64(offset);
        header.u64(entry.size);
        header.u64(entry.sum);
        offset += entry.size;
    }
    std::string& bytes = header.str();
    const std::uint64_t guard = tableChecksum(bytes, bytes.size());
    for (int i = 0; i < 8; ++i) bytes[16 + i] = char((guard >> (8 * i)) & 0xFF);
    return std::move(bytes);
}

}  // namespace

std::string writeContainer(std::string_view magic, std::uint32_t version,
                           const std::vector<OutSection>& sections) {
    std::vector<TableEntry> entries;
    for (const auto& section : sections)
        entries.push_back({section.tag, 0, section.payload.size(), checksum(section.payload)});
    std::string bytes = containerHeader(magic, version, entries);
    std::size_t size = bytes.size();
    for (const auto& section : sections) size += section.payload.size();
    bytes.reserve(size);
    for (const auto& section : sections) bytes += section.payload;
    return bytes;
}

void writeContainerFile(const std::filesystem::path& file, std::string_view magic, std::uint32_t version,
                        const std::vector<StreamedSection>& sections) {
    AtomicOutputFile out(file);
    std::ostream& stream = out.stream();
    const std::string placeholder(kHeaderSize + kTableEntrySize * sections.size(), '\0');
    stream.write(placeholder.data(), std::streamsize(placeholder.size()));
    // XXH3's streaming state gives the value XXH3_64bits gives the joined pieces.
    const std::unique_ptr<XXH3_state_t, decltype(&XXH3_freeState)> state(XXH3_createState(), &XXH3_freeState);
    if (!state) throw std::bad_alloc();
    std::vector<TableEntry> entries;
    for (const auto& section : sections) {
        XXH3_64bits_reset(state.get());
        std::uint64_t written = 0;
        section.produce([&](std::string_view piece) {
            XXH3_64bits_update(state.get(), piece.data(), piece.size());
            stream.write(piece.data(), std::streamsize(piece.size()));
            written += piece.size();
        });
        if (written != section.size)
            throw std::logic_error("container section " + section.tag + ": " + std::to_string(written) +
                                   " bytes written, " + std::to_string(section.size) + " announced");
        entries.push_back({section.tag, 0, section.size, XXH3_64bits_digest(state.get())});
    }
    const std::string header = containerHeader(magic, version, entries);
    stream.seekp(0);
    stream.write(header.data(), std::streamsize(header.size()));
    out.commit();
}

// Parses the header and table from `bytes` (at least the header and table of a file of
// `fileSize` bytes); returns a problem description or an empty string.
std::string readTable(std::string_view bytes, std::uint64_t fileSize, std::string_view magic,
                      std::uint32_t supportedVersion, std::uint32_t& version, std::vector<TableEntry>& entries,
                      std::string& location) {
    location = "header";
    const std::string_view head = bytes.substr(0, std::min<std::size_t>(8, bytes.size()));
    if (head != magic.substr(0, head.size()))
        return "bad magic number (not a " + printableTag(magic) + " file)";
    if (bytes.size() < kHeaderSize) return "truncated: " + std::to_string(bytes.size()) + " bytes, header needs 24";
    ByteReader reader(bytes.substr(8));
    version = reader.u32();
    const std::uint32_t count = reader.u32();
    const std::uint64_t storedGuard = reader.u64();
    if (version > supportedVersion)
        return "format version " + std::to_string(version) + " is newer than this program reads (" +
               std::to_string(supportedVersion) + ")";
    if (version == 0) return "invalid format version 0";
    location = "section table";
    if (count > kMaxSections) return "claims " + std::to_string(count) + " sections (at most 64)";
    const std::size_t tableEnd = kHeaderSize + kTableEntrySize * count;
    if (bytes.size() < tableEnd) return "truncated section table";
    if (tableChecksum(bytes, tableEnd) != storedGuard) return "checksum mismatch";
    ByteReader table(bytes.substr(kHeaderSize, tableEnd - kHeaderSize));
    std::uint64_t expected = tableEnd;
    for (std::uint32_t i = 0; i < count; ++i) {
        TableEntry entry;
        entry.tag = std::string(bytes.substr(kHeaderSize + kTableEntrySize * i, 4));
        (void)table.u32();
        (void)table.u32();
        entry.offset = table.u64();
        entry.size = table.u64();
        entry.sum = table.u64();
        if (entry.offset != expected) {
            location = sectionLocation(printableTag(entry.tag));
            return "at a wrong offset";
        }
        if (entry.size > fileSize || entry.offset + entry.size > fileSize) {
            location = sectionLocation(printableTag(entry.tag));
            return "truncated (" + std::to_string(entry.size) + " bytes claimed, the file ends after " +
                   std::to_string(fileSize - std::min<std::uint64_t>(fileSize, entry.offset)) + ")";
        }
        expected += entry.size;
        entries.push_back(std::move(entry));
    }
    return {};
}

std::vector<InSection> readContainer(std::string_view bytes, std::string_view magic,
                                     std::uint32_t supportedVersion, const std::filesystem::path& file) {
    std::uint32_t version = 0;
    std::vector<TableEntry> entries;
    std::string location;
    const std::string problem = readTable(bytes, bytes.size(), magic, supportedVersion, version, entries, location);
    if (!problem.empty()) throw InputError(file, problem, location);
    std::vector<InSection> sections;
    for (const auto& entry : entries) {
        const std::string where = sectionLocation(printableTag(entry.tag));
        if (entry.offset + entry.size > bytes.size())
            throw InputError(file, "truncated (" + std::to_string(bytes.size() - std::min<std::uint64_t>(bytes.size(), entry.offset)) +
                                       " of " + std::to_string(entry.size) + " bytes)",
                             where);
        const std::string_view payload = bytes.substr(entry.offset, entry.size);
        if (checksum(payload) != entry.sum) throw InputError(file, "checksum mismatch", where);
        sections.push_back({entry.tag, payload});
    }
    const std::uint64_t end = entries.empty() ? kHeaderSize : entries.back().offset + entries.back().size;
    if (end != bytes.size())
        throw InputError(file, std::to_string(bytes.size() - end) + " unexpected bytes after the last section",
                         "end of file");
    return sections;
}

void requireKnownSections(const std::vector<InSection>& sections, const std::function<bool(std::string_view)>& known,
                          const std::filesystem::path& file) {
    for (std::size_t i = 0; i < sections.size(); ++i) {
        const std::string where = sectionLocation(printableTag(sections[i].tag));
        if (!known(sections[i].tag)) throw InputError(file, "unknown section", where);
        for (std::size_t j = 0; j < i; ++j)
            if (sections[j].tag == sections[i].tag) throw InputError(file, "duplicate section", where);
    }
}

std::string_view requireSection(const std::vector<InSection>& sections, std::string_view tag,
                                const std::filesystem::path& file) {
    for (const auto& section : sections)
        if (section.tag == tag) return section.payload;
    throw InputError(file, "missing", sectionLocation(tag));
}

}  // namespace vtex::octree::detail

namespace vtex::octree {

FileCheck checkFile(std::string_view bytes, std::string_view magic, std::uint32_t supportedVersion) {
    using namespace detail;
    FileCheck check;
    std::vector<TableEntry> entries;
    std::string location;
    const std::string problem =
        readTable(bytes, bytes.size(), magic, supportedVersion, check.version, entries, location);
    if (!problem.empty()) {
        check.problem = location + ": " + problem;
        return check;
    }
    check.headerOk = true;
    for (const auto& entry : entries) {
        SectionStatus status{printableTag(entry.tag), entry.size, false};
        if (entry.offset + entry.size <= bytes.size())
            status.checksumOk = checksum(bytes.substr(entry.offset, entry.size)) == entry.sum;
        if (!status.checksumOk && check.problem.empty())
            check.problem = sectionLocation(status.tag) +
                            (entry.offset + entry.size > bytes.size() ? ": truncated" : ": checksum mismatch");
        check.sections.push_back(status);
    }
    const std::uint64_t end = entries.empty() ? kHeaderSize : entries.back().offset + entries.back().size;
    if (end != bytes.size() && check.problem.empty())
        check.problem = "end of file: " + std::to_string(std::int64_t(bytes.size()) - std::int64_t(end)) +
                        " bytes more than the sections";
    return check;
}

std::string readFileBytes(const std::filesystem::path& file, std::uint64_t maxBytes) {
    return readInputFile(file, maxBytes, "file");
}

}  // namespace vtex::octree
