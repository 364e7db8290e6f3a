// The compressed octree: queries and the .vto file format (docs/formats.md).
#include "container.h"
#include "vto_sections.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/octree/octree.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

namespace vtex::octree {

namespace {
constexpr std::uint32_t kAllLevels = ~std::uint32_t(0);
}  // namespace

Octree::Octree() = default;
Octree::~Octree() = default;
Octree::Octree(const Octree& other) { *this = other; }
Octree::Octree(Octree&& other) { *this = std::move(other); }

Octree& Octree::operator=(const Octree& other) {
    if (this == &other) return *this;
    other.loadLevels(kAllLevels);
    info = other.info;
    levels = other.levels;
    stats = other.stats;
    measures = other.measures;
    layerMeans = other.layerMeans;
    mBytesRead = other.bytesRead();
    mLoader.reset();
    return *this;
}

Octree& Octree::operator=(Octree&& other) {
    if (this == &other) return *this;
    // The loader stays behind: the moved-to object may be const, and loadLevels may write only
    // into the non-const object openVto made.
    other.loadLevels(kAllLevels);
    info = std::move(other.info);
    levels = std::move(other.levels);
    stats = std::move(other.stats);
    measures = std::move(other.measures);
    layerMeans = std::move(other.layerMeans);
    mBytesRead = other.bytesRead();
    mLoader.reset();
    other.mLoader.reset();
    other.levels.clear();
    return *this;
}

bool operator==(const Octree& a, const Octree& b) {
    a.loadLevels(kAllLevels);
    b.loadLevels(kAllLevels);
    return a.info == b.info && a.levels == b.levels && a.stats == b.stats && a.measures == b.measures &&
           a.layerMeans == b.layerMeans;
}

void Octree::loadLevels(std::uint32_t level) const {
    // A tree with a loader is the non-const object openVto made (copies and moves load
    // everything and drop the loader), so filling its levels writes no const object; the level
    // vectors other threads may be reading are never touched, only the ones not yet loaded.
    if (mLoader) mLoader->load(level, const_cast<Octree&>(*this));
}

std::uint64_t Octree::bytesRead() const { return mLoader ? mLoader->bytesRead() : mBytesRead; }

std::uint64_t Octree::storedNodes() const {
    loadLevels(kAllLevels);
    std::uint64_t n = 0;
    for (const auto& level : levels) n += level.size();
    return n;
}

double Octree::compression() const {
    const double voxels = std::ldexp(1.0, 3 * int(info.source.levels));
    return 1.0 - double(storedNodes()) / voxels;
}

std::vector<VolumeBlock> Octree::expandLevel(std::uint32_t level) const {
    loadLevels(level);
    std::vector<VolumeBlock> out;
    if (levels.empty() || level >= levels.size()) return out;
    struct Item {
        std::uint32_t l;
        std::size_t index;
        std::uint64_t key;
    };
    // Depth-first in Morton order, children pushed in reverse so output stays sorted.
    std::vector<Item> stack{{0, 0, 0}};
    while (!stack.empty()) {
        const Item it = stack.back();
        stack.pop_back();
        const OctreeNode& node = levels[it.l][it.index];
        if (it.l == level || node.isLeaf()) {
            if (node.data.isEmpty()) continue;
            const std::uint64_t copies = std::uint64_t(1) << (3 * (level - it.l));
            for (std::uint64_t c = 0; c < copies; ++c)
                out.push_back(VolumeBlock{(it.key << (3 * (level - it.l))) | c, std::uint8_t(level), 0, node.data});
            continue;
        }
        std::size_t child = node.firstChild + std::size_t(std::popcount(unsigned(node.childMask)));
        for (int c = 7; c >= 0; --c)
            if (node.childMask & (1u << c)) stack.push_back({it.l + 1, --child, (it.key << 3) | unsigned(c)});
    }
    return out;
}

std::string_view filterRuleName(FilterRule rule) { return kFilterRuleNames.name(rule); }

std::optional<FilterRule> parseFilterRule(std::string_view name) { return kFilterRuleNames.parse(name); }

namespace {

constexpr std::size_t kNodeRecordSize = 1 + detail::kVoxelRecordSize;

// The records of nodes [begin, end) at `out`, kNodeRecordSize bytes each. Records have a fixed
// size, so they are filled from all threads (a 1024³ texel stores some 10⁷ nodes).
void storeNodeRecords(const std::vector<OctreeNode>& nodes, std::size_t begin, std::size_t end, char* out) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 8192), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            char* record = out + kNodeRecordSize * (i - begin);
            record[0] = char(nodes[i].childMask);
            detail::storeVoxelData(record + 1, nodes[i].data);
        }
    });
}

// A level's section opens with its node count.
std::string levelCountBytes(const std::vector<OctreeNode>& nodes) {
    detail::ByteWriter count;
    count.u64(nodes.size());
    return std::move(count.str());
}

// The HEAD and STAT sections of `octree`.
std::vector<detail::OutSection> vtoHeadAndStats(const Octree& octree) {
    using namespace detail;
    ByteWriter head;
    writeVolumeInfo(head, octree.info.source);
    head.u8(octree.info.rule == FilterRule::Neyret ? 0 : 1);
    head.f32(octree.info.tolerance);
    head.u32(octree.levelCount());
    ByteWriter stats;
    for (const auto& s : octree.stats) {
        stats.u64(s.storedNodes);
        stats.u64(s.occupiedNodes);
        stats.f64(s.meanDensity);
        stats.f64(s.meanOccupiedDensity);
        stats.f64(s.filterErrorMean);
        stats.f64(s.filterErrorMax);
        stats.u64(s.filterErrorSamples);
    }
    std::vector<detail::OutSection> out{{"HEAD", std::move(head.str())}, {"STAT", std::move(stats.str())}};
    if (octree.measures) out.push_back({"MEAS", detail::measuresBytes(*octree.measures)});
    if (octree.layerMeans) out.push_back({"PROF", detail::layerMeansBytes(*octree.layerMeans)});
    return out;
}

// The container's sections of `octree`, whole in memory.
std::vector<detail::OutSection> vtoSections(const Octree& octree) {
    std::vector<detail::OutSection> sections = vtoHeadAndStats(octree);
    for (std::uint32_t l = 0; l < octree.levelCount(); ++l) {
        const auto& nodes = octree.levels[l];
        std::string bytes = levelCountBytes(nodes);
        bytes.resize(8 + kNodeRecordSize * nodes.size());
        storeNodeRecords(nodes, 0, nodes.size(), bytes.data() + 8);
        sections.push_back({detail::levelTag(l), std::move(bytes)});
    }
    return sections;
}

}  // namespace

std::string serializeVto(const Octree& octree) {
    return detail::writeContainer(detail::kVtoMagic, kVtoVersion, vtoSections(octree));
}

void writeVto(const Octree& octree, const std::filesystem::path& file) {
    // The same bytes as serializeVto, each level made and written a piece at a time through one
    // buffer: a whole copy of the tree in file form was the largest allocation after the tree's.
    constexpr std::size_t kPieceNodes = std::size_t(1) << 15;
    std::string piece;
    std::vector<detail::StreamedSection> sections;
    for (auto& section : vtoHeadAndStats(octree))
        sections.push_back({section.tag, section.payload.size(),
                            [payload = std::move(section.payload)](const auto& emit) { emit(payload); }});
    for (std::uint32_t l = 0; l < octree.levelCount(); ++l) {
        const auto& nodes = octree.levels[l];
        sections.push_back({detail::levelTag(l), 8 + kNodeRecordSize * nodes.size(), [&nodes, &piece](const auto& emit) {
                                emit(levelCountBytes(nodes));
                                for (std::size_t begin = 0; begin < nodes.size(); begin += kPieceNodes) {
                                    const std::size_t end = std::min(nodes.size(), begin + kPieceNodes);
                                    piece.resize(kNodeRecordSize * (end - begin));
                                    storeNodeRecords(nodes, begin, end, piece.data());
                                    emit(piece);
                                }
                            }});
    }
    detail::writeContainerFile(file, detail::kVtoMagic, kVtoVersion, sections);
}

Octree parseVto(std::string_view bytes, const std::filesystem::path& file) {
    using namespace detail;
    const auto sections = readContainer(bytes, kVtoMagic, kVtoVersion, file);
    requireKnownSections(sections, isVtoSection, file);
    Octree tree;
    parseVtoHead(requireSection(sections, "HEAD", file), tree, file);
    parseVtoStats(requireSection(sections, "STAT", file), tree, file);
    for (const InSection& section : sections)
        if (section.tag == "MEAS") tree.measures = parseVtoMeasures(section.payload, tree, file);
        else if (section.tag == "PROF") tree.layerMeans = parseVtoLayerMeans(section.payload, tree, file);
    const std::uint32_t levelCount = tree.info.source.levels + 1;
    tree.levels.resize(levelCount);
    std::uint64_t expected = 1;  // nodes the level above announces
    for (std::uint32_t l = 0; l < levelCount; ++l)
        expected = parseVtoLevel(requireSection(sections, levelTag(l), file), l, expected, tree, tree.levels[l], file);
    return tree;
}

Octree readVto(const std::filesystem::path& file) {
    const std::string bytes = readFileBytes(file);
    Octree tree = parseVto(bytes, file);
    tree.mBytesRead = bytes.size();
    return tree;
}

}  // namespace vtex::octree
