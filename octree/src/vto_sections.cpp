// The .vto sections one by one, and openVto's reading of the levels on first use (see
// vto_sections.h, docs/formats.md).
#include "vto_sections.h"

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

namespace vtex::octree::detail {
namespace {

constexpr std::size_t kNodeRecordSize = 1 + 44;
constexpr std::size_t kStatRecordSize = 8 * 7;

}  // namespace

std::string levelTag(std::uint32_t l) {
    char tag[8];
    std::snprintf(tag, sizeof tag, "LV%02u", l % 100);
    return tag;
}

bool isVtoSection(std::string_view tag) {
    return tag == "HEAD" || tag == "STAT" || tag == "MEAS" || tag == "PROF" ||
           (tag.size() == 4 && tag.substr(0, 2) == "LV" && std::isdigit(static_cast<unsigned char>(tag[2])) &&
            std::isdigit(static_cast<unsigned char>(tag[3])));
}

void parseVtoHead(std::string_view payload, Octree& tree, const std::filesystem::path& file) {
    ByteReader head(payload);
    tree.info.source = readVolumeInfo(head, file, "HEAD");
    const std::uint8_t rule = head.u8();
    tree.info.tolerance = head.f32();
    const std::uint32_t count = head.u32();
    const std::string where = sectionLocation("HEAD");
    if (!head.ok() || head.remaining() != 0) throw InputError(file, "wrong size", where);
    if (rule > 1) throw InputError(file, "unknown filter rule " + std::to_string(rule), where);
    tree.info.rule = rule == 0 ? FilterRule::Neyret : FilterRule::Sggx;
    if (!std::isfinite(tree.info.tolerance) || tree.info.tolerance < 0) throw InputError(file, "invalid tolerance", where);
    if (count != tree.info.source.levels + 1)
        throw InputError(file, "level count " + std::to_string(count) + " does not match the resolution", where);
}

void parseVtoStats(std::string_view payload, Octree& tree, const std::filesystem::path& file) {
    const std::uint32_t levelCount = tree.info.source.levels + 1;
    if (payload.size() != kStatRecordSize * levelCount)
        throw InputError(file, "wrong size for " + std::to_string(levelCount) + " levels", sectionLocation("STAT"));
    ByteReader r(payload);
    tree.stats.resize(levelCount);
    for (auto& s : tree.stats) {
        s.storedNodes = r.u64();
        s.occupiedNodes = r.u64();
        s.meanDensity = r.f64();
        s.meanOccupiedDensity = r.f64();
        s.filterErrorMean = r.f64();
        s.filterErrorMax = r.f64();
        s.filterErrorSamples = r.u64();
        if (!std::isfinite(s.meanDensity) || !std::isfinite(s.meanOccupiedDensity) || !std::isfinite(s.filterErrorMean) ||
            !std::isfinite(s.filterErrorMax))
            throw InputError(file, "non-finite statistic", sectionLocation("STAT"));
    }
}

std::string measuresBytes(const SourceMeasures& m) {
    ByteWriter w;
    w.u32(m.version);
    w.u64(m.geometryHash);
    w.u64(m.fileHash);
    w.f64(m.tau);
    w.f64(m.tolerance);
    w.u32(std::uint32_t(m.faithfulCoarsest));
    w.u32(std::uint32_t(m.faithfulFinest));
    w.u32(std::uint32_t(m.meshLevel));
    w.u32(std::uint32_t(m.levelScales.size()));
    for (const double s : m.levelScales) w.f64(s);
    w.u32(std::uint32_t(m.shadowLevels.size()));
    for (const std::int32_t l : m.shadowLevels) w.u32(std::uint32_t(l));
    w.u32(std::uint32_t(m.ownShares.size()));
    for (const double s : m.ownShares) w.f64(s);
    return std::move(w.str());
}

SourceMeasures parseVtoMeasures(std::string_view payload, const Octree& tree, const std::filesystem::path& file) {
    const std::string where = sectionLocation("MEAS");
    const std::uint32_t levelCount = tree.info.source.levels + 1;
    ByteReader r(payload);
    SourceMeasures m;
    m.version = r.u32();
    m.geometryHash = r.u64();
    m.fileHash = r.u64();
    m.tau = r.f64();
    m.tolerance = r.f64();
    m.faithfulCoarsest = std::int32_t(r.u32());
    m.faithfulFinest = std::int32_t(r.u32());
    m.meshLevel = std::int32_t(r.u32());
    // Counts are checked before anything is allocated for them: at most one entry per level.
    const std::uint32_t scales = r.u32();
    if (!r.ok() || scales > levelCount) throw InputError(file, "wrong size", where);
    for (std::uint32_t i = 0; i < scales; ++i) m.levelScales.push_back(r.f64());
    const std::uint32_t shadows = r.u32();
    if (!r.ok() || shadows > levelCount) throw InputError(file, "wrong size", where);
    for (std::uint32_t i = 0; i < shadows; ++i) m.shadowLevels.push_back(std::int32_t(r.u32()));
    // A record written before the own shares ends here (its version makes renders measure again).
    if (r.ok() && r.remaining() > 0) {
        const std::uint32_t shares = r.u32();
        if (!r.ok() || shares > levelCount) throw InputError(file, "wrong size", where);
        for (std::uint32_t i = 0; i < shares; ++i) m.ownShares.push_back(r.f64());
    }
    if (!r.ok() || r.remaining() != 0) throw InputError(file, "wrong size", where);
    const auto level = [&](std::int32_t l) { return l >= 0 && std::uint32_t(l) < levelCount; };
    if (!(m.tau > 0) || !std::isfinite(m.tau) || !(m.tolerance >= 0) || !std::isfinite(m.tolerance))
        throw InputError(file, "invalid tau or tolerance", where);
    if (!level(m.faithfulCoarsest) || !level(m.faithfulFinest) || !level(m.meshLevel) ||
        !std::all_of(m.shadowLevels.begin(), m.shadowLevels.end(), level))
        throw InputError(file, "a level beyond the tree's " + std::to_string(levelCount), where);
    if (!std::all_of(m.levelScales.begin(), m.levelScales.end(), [](double s) { return s > 0 && std::isfinite(s); }))
        throw InputError(file, "a level scale that is not positive and finite", where);
    if (!std::all_of(m.ownShares.begin(), m.ownShares.end(), [](double s) { return s >= 0 && s <= 1; }))
        throw InputError(file, "an own share outside [0, 1]", where);
    return m;
}

std::string layerMeansBytes(const LayerMeans& m) {
    ByteWriter w;
    w.u32(m.level);
    for (const auto& axis : m.axis)
        for (const double v : axis) w.f64(v);
    return std::move(w.str());
}

LayerMeans parseVtoLayerMeans(std::string_view payload, const Octree& tree, const std::filesystem::path& file) {
    const std::string where = sectionLocation("PROF");
    ByteReader r(payload);
    LayerMeans m;
    m.level = r.u32();
    // The level is checked before anything is allocated for it: 3 × 2^level values.
    if (!r.ok() || m.level > tree.info.source.levels)
        throw InputError(file, "a level beyond the tree's " + std::to_string(tree.info.source.levels + 1), where);
    const std::uint64_t layers = std::uint64_t(1) << m.level;
    if (r.remaining() != 3 * 8 * layers) throw InputError(file, "wrong size", where);
    for (auto& axis : m.axis) {
        axis.resize(std::size_t(layers));
        for (double& v : axis) v = r.f64();
        if (!std::all_of(axis.begin(), axis.end(), [](double v) { return v >= 0 && std::isfinite(v); }))
            throw InputError(file, "a layer mean that is negative or not finite", where);
    }
    return m;
}

std::uint64_t parseVtoLevel(std::string_view payload, std::uint32_t l, std::uint64_t expected, const Octree& tree,
                            std::vector<OctreeNode>& nodes, const std::filesystem::path& file) {
    const std::uint32_t levelCount = tree.info.source.levels + 1;
    const std::string where = sectionLocation(levelTag(l));
    ByteReader r(payload);
    const std::uint64_t count = r.u64();
    if (!r.ok() || count > r.remaining() / kNodeRecordSize || count * kNodeRecordSize != r.remaining())
        throw InputError(file, "size does not match its node count " + std::to_string(count), where);
    if (count != expected)
        throw InputError(file, std::to_string(count) + " nodes where the level above has " + std::to_string(expected) +
                                   " children", where);
    if (tree.stats[l].storedNodes != count) throw InputError(file, "node count disagrees with STAT", where);
    nodes.resize(count);
    std::uint64_t children = 0;
    for (std::uint64_t i = 0; i < count; ++i) {
        OctreeNode& node = nodes[i];
        node.childMask = r.u8();
        node.data = readVoxelData(r);
        // Built only for a message: a level holds millions of nodes.
        const auto nodeWhere = [&] { return where + ", node " + std::to_string(i); };
        // Only an empty root (an empty volume) may be stored empty.
        const bool mayBeEmpty = l == 0 && node.childMask == 0;
        if (const auto problem = checkVoxelData(node.data, mayBeEmpty); !problem.empty())
            throw InputError(file, std::string(problem), nodeWhere());
        if (l + 1 == levelCount && node.childMask != 0) throw InputError(file, "finest-level node with children", nodeWhere());
        if (children > std::numeric_limits<std::uint32_t>::max()) throw InputError(file, "too many nodes", nodeWhere());
        node.firstChild = std::uint32_t(children);
        children += std::uint64_t(std::popcount(unsigned(node.childMask)));
    }
    return children;
}

LevelLoader::LevelLoader(std::filesystem::path file, int fd, std::vector<TableEntry> levels, std::uint64_t bytesRead)
    : mFile(std::move(file)),
      mFd(fd),
      mLevels(std::move(levels)),
      mOnce(std::make_unique<std::once_flag[]>(mLevels.size())),
      mChildren(mLevels.size(), 0),
      mBytesRead(bytesRead) {}

LevelLoader::~LevelLoader() { ::close(mFd); }

std::string readSection(int fd, const TableEntry& entry, const std::filesystem::path& file) {
    const std::string where = sectionLocation(printableTag(entry.tag));
    std::string payload(entry.size, '\0');
    std::uint64_t done = 0;
    while (done < entry.size) {
        const ssize_t n = ::pread(fd, payload.data() + done, entry.size - done, off_t(entry.offset + done));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw IoError(file, std::string("cannot read ") + where + ": " + std::strerror(errno));
        // The table said the file was long enough when it was opened: it was truncated since.
        if (n == 0) throw InputError(file, "truncated since the file was opened", where);
        done += std::uint64_t(n);
    }
    if (checksum(payload) != entry.sum) throw InputError(file, "checksum mismatch", where);
    return payload;
}

void LevelLoader::load(std::uint32_t level, Octree& tree) {
    if (mLevels.empty()) return;
    const int deepest = int(std::min<std::uint64_t>(level, mLevels.size() - 1));
    if (deepest <= mDeepestLoaded.load(std::memory_order_acquire)) return;
    for (int l = 0; l <= deepest; ++l) {
        std::call_once(mOnce[std::size_t(l)], [&] {
            const TableEntry& entry = mLevels[std::size_t(l)];
            mBytesRead.fetch_add(entry.size, std::memory_order_relaxed);
            const std::string payload = readSection(mFd, entry, mFile);
            const std::uint64_t expected = l == 0 ? 1 : mChildren[std::size_t(l) - 1];
            std::vector<OctreeNode> nodes;
            mChildren[std::size_t(l)] = parseVtoLevel(payload, std::uint32_t(l), expected, tree, nodes, mFile);
            tree.levels[std::size_t(l)] = std::move(nodes);
            // Levels load in order, each after the one above: the stores only grow.
            mDeepestLoaded.store(l, std::memory_order_release);
        });
    }
}

}  // namespace vtex::octree::detail

namespace vtex::octree {
namespace {

using detail::LevelLoader;
using detail::TableEntry;

// The first `size` bytes of the open file (fewer if it is shorter).
std::string readHead(int fd, std::size_t size, const std::filesystem::path& file) {
    std::string bytes(size, '\0');
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::pread(fd, bytes.data() + done, size - done, off_t(done));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw IoError(file, std::string("cannot read: ") + std::strerror(errno));
        if (n == 0) break;
        done += std::size_t(n);
    }
    bytes.resize(done);
    return bytes;
}

// The table entries of HEAD, STAT and LV00 … LVnn, checked as readContainer checks them, read
// from the file's head alone.
std::vector<TableEntry> readVtoTable(int fd, std::uint64_t fileSize, const std::filesystem::path& file,
                                     std::uint64_t& headBytes) {
    using namespace detail;
    std::string head = readHead(fd, kHeaderSize, file);
    std::uint32_t count = 0;
    if (head.size() >= kHeaderSize) {
        ByteReader r(std::string_view(head).substr(12));
        count = std::min(r.u32(), kMaxSections);  // readTable refuses more
        head = readHead(fd, kHeaderSize + kTableEntrySize * count, file);
    }
    headBytes = head.size();
    std::uint32_t version = 0;
    std::vector<TableEntry> entries;
    std::string location;
    if (const std::string problem = readTable(head, fileSize, kVtoMagic, kVtoVersion, version, entries, location);
        !problem.empty())
        throw InputError(file, problem, location);
    const std::uint64_t end = entries.empty() ? kHeaderSize : entries.back().offset + entries.back().size;
    if (end != fileSize)
        throw InputError(file, std::to_string(fileSize - end) + " unexpected bytes after the last section", "end of file");
    std::vector<InSection> tags;
    for (const auto& entry : entries) tags.push_back({entry.tag, {}});
    requireKnownSections(tags, isVtoSection, file);
    return entries;
}

const TableEntry& requireEntry(const std::vector<TableEntry>& entries, std::string_view tag,
                               const std::filesystem::path& file) {
    for (const auto& entry : entries)
        if (entry.tag == tag) return entry;
    throw InputError(file, "missing", detail::sectionLocation(tag));
}

}  // namespace

std::shared_ptr<const Octree> openVto(const std::filesystem::path& file) {
    using namespace detail;
    checkInputFile(file, kMaxFileBytes, "file");  // the same refusals as readVto's
    // Closes the descriptor unless the loader has taken it.
    struct Descriptor {
        int fd;
        ~Descriptor() {
            if (fd >= 0) ::close(fd);
        }
    } descriptor{::open(file.c_str(), O_RDONLY | O_CLOEXEC)};
    const int fd = descriptor.fd;
    if (fd < 0) throw IoError(file, std::string("cannot open for reading: ") + std::strerror(errno));
    struct stat status {};
    if (::fstat(fd, &status) != 0 || !S_ISREG(status.st_mode)) throw InputError(file, "file is not a regular file");
    std::uint64_t bytesRead = 0;
    const std::vector<TableEntry> entries = readVtoTable(fd, std::uint64_t(status.st_size), file, bytesRead);
    auto tree = std::make_shared<Octree>();
    for (const char* tag : {"HEAD", "STAT"}) {
        const TableEntry& entry = requireEntry(entries, tag, file);
        const std::string payload = readSection(fd, entry, file);
        bytesRead += entry.size;
        if (tag == std::string_view("HEAD")) parseVtoHead(payload, *tree, file);
        else parseVtoStats(payload, *tree, file);
    }
    for (const TableEntry& entry : entries)
        if (entry.tag == "MEAS" || entry.tag == "PROF") {
            const std::string payload = readSection(fd, entry, file);
            if (entry.tag == "MEAS") tree->measures = parseVtoMeasures(payload, *tree, file);
            else tree->layerMeans = parseVtoLayerMeans(payload, *tree, file);
            bytesRead += entry.size;
        }
    const std::uint32_t levelCount = tree->info.source.levels + 1;
    std::vector<TableEntry> levels;
    for (std::uint32_t l = 0; l < levelCount; ++l) levels.push_back(requireEntry(entries, levelTag(l), file));
    tree->mLoader = std::make_unique<LevelLoader>(file, fd, std::move(levels), bytesRead);
    descriptor.fd = -1;
    tree->levels.resize(levelCount);
    return tree;
}

}  // namespace vtex::octree
