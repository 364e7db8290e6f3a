/// @file
/// @brief The one descent of the compressed octree: a cursor that remembers its last path.
///
/// Like OpenVDB's ValueAccessor beside its tree (Museth 2013, "VDB: high-resolution sparse
/// volumes with dynamic topology", §3.2): it keeps the nodes from the root to the voxel it found
/// last, and the next lookup starts from the deepest ancestor the two voxels share instead of the
/// root. Consecutive steps of a march are neighbours, and most of them share all but the last
/// level or two. Header-only: the renderer's block march calls it at every step.
#pragma once

#include <vtex/octree/octree.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>

namespace vtex::octree {

namespace detail {

// The number of set bits below bit c of a child mask, from a table: without -mpopcnt,
// std::popcount is a library call, and this lookup runs at every level of every step.
inline constexpr auto kBitsBelow = [] {
    std::array<std::array<std::uint8_t, 8>, 256> table{};
    for (unsigned mask = 0; mask < 256; ++mask)
        for (unsigned c = 0; c < 8; ++c) {
            unsigned n = 0;
            for (unsigned b = 0; b < c; ++b) n += (mask >> b) & 1u;
            table[mask][c] = std::uint8_t(n);
        }
    return table;
}();

}  // namespace detail

/// What stands for one voxel of a level.
struct Located {
    const OctreeNode* node;  ///< the stored node at that level or the leaf above it; nullptr: empty space
    /// The level at which the answer is uniform: the node's own level, or for empty space the
    /// level of the missing child that makes the block empty (the level asked for at most).
    int blockLevel;
};

/// Lookups in one tree (which must outlive the cursor and not change while it is used). Not
/// thread-safe: one cursor per thread or per march.
class OctreeCursor {
public:
    explicit OctreeCursor(const Octree& tree) : mTree(&tree) {}

    /// The node that stands for voxel (x, y, z) of `level` (indices at that level, < 2^level).
    /// Precondition: the tree has a root and 0 ≤ level < levelCount() (≤ 31).
    Located locate(int level, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
        int l = 0;
        if (mDepth < 0) {
            mPath[0] = &mTree->levels[0][0];
            mDepth = 0;
        } else {
            const std::uint32_t diff = (x ^ mX) | (y ^ mY) | (z ^ mZ);
            // Ancestors at levels l ≤ level − bit_width(diff) hold both voxels. (Voxels of
            // another level share nothing that the formula could vouch for: start at the root.)
            l = level == mLevel ? std::min(mDepth, level - int(std::bit_width(diff))) : 0;
        }
        mX = x;
        mY = y;
        mZ = z;
        mLevel = level;
        const OctreeNode* node = mPath[std::size_t(l)];
        while (l < level && !node->isLeaf()) {
            const int shift = level - l - 1;
            const unsigned c = ((x >> shift) & 1u) | (((y >> shift) & 1u) << 1) | (((z >> shift) & 1u) << 2);
            if (!(node->childMask & (1u << c))) {
                mDepth = l;
                return {nullptr, l + 1};
            }
            const unsigned before = detail::kBitsBelow[node->childMask][c];
            node = &mTree->levels[std::size_t(l + 1)][node->firstChild + before];
            ++l;
            mPath[std::size_t(l)] = node;
        }
        mDepth = l;
        if (node->data.isEmpty()) return {nullptr, l};
        return {node, l};
    }

private:
    const Octree* mTree;
    std::array<const OctreeNode*, 32> mPath{};
    int mDepth = -1;  ///< mPath[0..mDepth] valid; −1: nothing located yet
    int mLevel = -1;
    std::uint32_t mX = 0, mY = 0, mZ = 0;
};

}  // namespace vtex::octree
