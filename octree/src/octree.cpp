// The compressed octree: queries and the .vto file format (docs/formats.md).
#include "container.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/octree/octree.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <bit>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

namespace vtex::octree {

std::uint64_t Octree::storedNodes() const {
    std::uint64_t n = 0;
    for (const auto& level : levels) n += level.size();
    return n;
}

double Octree::compression() const {
    const double voxels = std::ldexp(1.0, 3 * int(info.source.levels));
    return 1.0 - double(storedNodes()) / voxels;
}

std::vector<VolumeBlock> Octree::expandLevel(std::uint32_t level) const {
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

std::string_view filterRuleName(FilterRule rule) { return rule == FilterRule::Neyret ? "neyret" : "sggx"; }

std::optional<FilterRule> parseFilterRule(std::string_view name) {
    if (name == "neyret") return FilterRule::Neyret;
    if (name == "sggx") return FilterRule::Sggx;
    return std::nullopt;
}

namespace {

constexpr std::string_view kVtoMagic{"VTEX.VTO", 8};
constexpr std::size_t kNodeRecordSize = 1 + detail::kVoxelRecordSize;
constexpr std::size_t kStatRecordSize = 8 * 7;

std::string levelTag(std::uint32_t l) {
    char tag[8];
    std::snprintf(tag, sizeof tag, "LV%02u", l % 100);
    return tag;
}

// The container's sections of `octree`. A level's records have a fixed size, so its section
// is filled from all threads (a 1024³ texel stores some 10⁷ nodes).
std::vector<detail::OutSection> vtoSections(const Octree& octree) {
    using namespace detail;
    std::vector<OutSection> sections;
    ByteWriter head;
    writeVolumeInfo(head, octree.info.source);
    head.u8(octree.info.rule == FilterRule::Neyret ? 0 : 1);
    head.f32(octree.info.tolerance);
    head.u32(octree.levelCount());
    sections.push_back({"HEAD", std::move(head.str())});
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
    sections.push_back({"STAT", std::move(stats.str())});
    for (std::uint32_t l = 0; l < octree.levelCount(); ++l) {
        const auto& nodes = octree.levels[l];
        ByteWriter count;
        count.u64(nodes.size());
        std::string bytes = std::move(count.str());
        bytes.resize(8 + kNodeRecordSize * nodes.size());
        char* records = bytes.data() + 8;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes.size(), 8192),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t i = range.begin(); i != range.end(); ++i) {
                                  char* record = records + kNodeRecordSize * i;
                                  record[0] = char(nodes[i].childMask);
                                  storeVoxelData(record + 1, nodes[i].data);
                              }
                          });
        sections.push_back({levelTag(l), std::move(bytes)});
    }
    return sections;
}

}  // namespace

std::string serializeVto(const Octree& octree) {
    return detail::writeContainer(kVtoMagic, kVtoVersion, vtoSections(octree));
}

Octree parseVto(std::string_view bytes, const std::filesystem::path& file) {
    using namespace detail;
    const auto sections = readContainer(bytes, kVtoMagic, kVtoVersion, file);
    requireKnownSections(
        sections,
        [](std::string_view tag) {
            return tag == "HEAD" || tag == "STAT" ||
                   (tag.size() == 4 && tag.substr(0, 2) == "LV" && std::isdigit(static_cast<unsigned char>(tag[2])) &&
                    std::isdigit(static_cast<unsigned char>(tag[3])));
        },
        file);
    Octree tree;
    {
        ByteReader head(requireSection(sections, "HEAD", file));
        tree.info.source = readVolumeInfo(head, file, "HEAD");
        const std::uint8_t rule = head.u8();
        tree.info.tolerance = head.f32();
        const std::uint32_t count = head.u32();
        const std::string where = sectionLocation("HEAD");
        if (!head.ok() || head.remaining() != 0) throw InputError(file, "wrong size", where);
        if (rule > 1) throw InputError(file, "unknown filter rule " + std::to_string(rule), where);
        tree.info.rule = rule == 0 ? FilterRule::Neyret : FilterRule::Sggx;
        if (!std::isfinite(tree.info.tolerance) || tree.info.tolerance < 0)
            throw InputError(file, "invalid tolerance", where);
        if (count != tree.info.source.levels + 1)
            throw InputError(file, "level count " + std::to_string(count) + " does not match the resolution", where);
    }
    const std::uint32_t levelCount = tree.info.source.levels + 1;
    {
        const std::string_view payload = requireSection(sections, "STAT", file);
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
            if (!std::isfinite(s.meanDensity) || !std::isfinite(s.meanOccupiedDensity) ||
                !std::isfinite(s.filterErrorMean) || !std::isfinite(s.filterErrorMax))
                throw InputError(file, "non-finite statistic", sectionLocation("STAT"));
        }
    }
    tree.levels.resize(levelCount);
    std::uint64_t expected = 1;  // nodes the level above announces
    for (std::uint32_t l = 0; l < levelCount; ++l) {
        const std::string tag = levelTag(l);
        const std::string where = sectionLocation(tag);
        ByteReader r(requireSection(sections, tag, file));
        const std::uint64_t count = r.u64();
        if (!r.ok() || count > r.remaining() / kNodeRecordSize || count * kNodeRecordSize != r.remaining())
            throw InputError(file, "size does not match its node count " + std::to_string(count), where);
        if (count != expected)
            throw InputError(file, std::to_string(count) + " nodes where the level above has " +
                                       std::to_string(expected) + " children", where);
        if (tree.stats[l].storedNodes != count) throw InputError(file, "node count disagrees with STAT", where);
        auto& nodes = tree.levels[l];
        nodes.resize(count);
        std::uint64_t children = 0;
        for (std::uint64_t i = 0; i < count; ++i) {
            OctreeNode& node = nodes[i];
            node.childMask = r.u8();
            node.data = readVoxelData(r);
            const std::string nodeWhere = where + ", node " + std::to_string(i);
            // Only an empty root (an empty volume) may be stored empty.
            const bool mayBeEmpty = l == 0 && node.childMask == 0;
            if (const auto problem = checkVoxelData(node.data, mayBeEmpty); !problem.empty())
                throw InputError(file, problem, nodeWhere);
            if (l + 1 == levelCount && node.childMask != 0)
                throw InputError(file, "finest-level node with children", nodeWhere);
            if (children > std::numeric_limits<std::uint32_t>::max())
                throw InputError(file, "too many nodes", nodeWhere);
            node.firstChild = std::uint32_t(children);
            children += std::uint64_t(std::popcount(unsigned(node.childMask)));
        }
        expected = children;
    }
    return tree;
}

void writeVto(const Octree& octree, const std::filesystem::path& file) {
    detail::writeContainerFile(file, kVtoMagic, kVtoVersion, vtoSections(octree));
}

Octree readVto(const std::filesystem::path& file) { return parseVto(readFileBytes(file), file); }

}  // namespace vtex::octree
