// The sections of a .vto file (docs/formats.md), parsed one by one: by parseVto from a whole
// file in memory, and by openVto's LevelLoader from an open file, a level at a time. Internal to
// vtex_octree.
#pragma once

#include "container.h"

#include <vtex/octree/octree.h>

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace vtex::octree::detail {

inline constexpr std::string_view kVtoMagic{"VTEX.VTO", 8};

/// "LV00" … "LV99".
std::string levelTag(std::uint32_t level);
/// HEAD, STAT, MEAS, PROF or LVnn.
bool isVtoSection(std::string_view tag);

/// HEAD into tree.info, STAT into tree.stats (sized to the level count HEAD gives). Throw
/// vtex::InputError naming `file` and the section.
void parseVtoHead(std::string_view payload, Octree& tree, const std::filesystem::path& file);
void parseVtoStats(std::string_view payload, Octree& tree, const std::filesystem::path& file);

/// The MEAS section (docs/formats.md): its payload for `m`, and `m` from a payload, checked
/// against the tree's level count (HEAD parsed first). Throws vtex::InputError naming `file`
/// and the section.
std::string measuresBytes(const SourceMeasures& m);
SourceMeasures parseVtoMeasures(std::string_view payload, const Octree& tree, const std::filesystem::path& file);

/// The PROF section (docs/formats.md): its payload for `m`, and `m` from a payload, checked
/// against the tree's level count (HEAD parsed first). Throws vtex::InputError naming `file`
/// and the section.
std::string layerMeansBytes(const LayerMeans& m);
LayerMeans parseVtoLayerMeans(std::string_view payload, const Octree& tree, const std::filesystem::path& file);

/// Level `level`'s section into `nodes`, checked against tree.stats and against `expected`, the
/// number of children the level above announces (1 for the root). Returns the number of
/// children this level announces. Throws vtex::InputError naming `file` and the section or node.
std::uint64_t parseVtoLevel(std::string_view payload, std::uint32_t level, std::uint64_t expected, const Octree& tree,
                            std::vector<OctreeNode>& nodes, const std::filesystem::path& file);

/// The payload of `entry`, read from the open file `fd` at its offset and checked against its
/// checksum. Throws vtex::InputError naming `file` and the section (vtex::IoError if the system
/// refuses the read).
std::string readSection(int fd, const TableEntry& entry, const std::filesystem::path& file);

/// The open file behind a tree from openVto, and which of its levels are in memory.
class LevelLoader {
public:
    /// Takes ownership of the open descriptor `fd`; `levels[ℓ]` is level ℓ's table entry.
    LevelLoader(std::filesystem::path file, int fd, std::vector<TableEntry> levels, std::uint64_t bytesRead);
    ~LevelLoader();
    LevelLoader(const LevelLoader&) = delete;
    LevelLoader& operator=(const LevelLoader&) = delete;

    /// Loads levels 0 … min(level, deepest) into tree.levels (see Octree::loadLevels).
    void load(std::uint32_t level, Octree& tree);
    std::uint64_t bytesRead() const { return mBytesRead.load(std::memory_order_relaxed); }

private:
    std::filesystem::path mFile;
    int mFd;
    std::vector<TableEntry> mLevels;
    // Each level is read once, in order (a level's nodes are checked against the children the
    // level above announces, mChildren[ℓ − 1], written under the level above's flag).
    std::unique_ptr<std::once_flag[]> mOnce;
    std::vector<std::uint64_t> mChildren;
    std::atomic<int> mDeepestLoaded{-1};
    std::atomic<std::uint64_t> mBytesRead;
};

}  // namespace vtex::octree::detail
