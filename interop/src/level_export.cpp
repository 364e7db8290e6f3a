// One level of an octree as constant cubes of voxels (level_export.h).
#include <vtex/interop/level_export.h>

#include <bit>
#include <stdexcept>
#include <string>

namespace vtex::interop {

std::vector<LevelBlock> levelBlocks(const octree::Octree& octree, std::uint32_t level) {
    if (level >= octree.levelCount())
        throw std::out_of_range("level " + std::to_string(level) + " (the octree has levels 0 to " +
                                std::to_string(int(octree.levelCount()) - 1) + ")");
    std::vector<LevelBlock> blocks;
    // Level by level, the Morton keys of one level's stored nodes: the children of node i are
    // stored consecutively from firstChild, in the order of their bits in childMask, so each
    // level's keys follow from its parents' without a lookup.
    std::vector<std::uint64_t> keys{0};
    for (std::uint32_t l = 0; l <= level; ++l) {
        const std::vector<octree::OctreeNode>& nodes = octree.levels[l];
        const bool last = l == level;
        const std::uint32_t shift = level - l;
        std::vector<std::uint64_t> childKeys;
        if (!last && l + 1 < octree.levelCount()) childKeys.resize(octree.levels[l + 1].size());
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const octree::OctreeNode& node = nodes[i];
            if ((last || node.isLeaf()) && !node.data.isEmpty()) {
                const auto xyz = octree::mortonDecode(keys[i]);
                blocks.push_back(LevelBlock{{xyz[0] << shift, xyz[1] << shift, xyz[2] << shift},
                                            std::uint32_t(1) << shift, l, &node.data});
            }
            if (last) continue;
            std::size_t child = node.firstChild;
            for (unsigned c = 0; c < 8; ++c)
                if (node.childMask & (1u << c)) childKeys.at(child++) = (keys[i] << 3) | c;
        }
        keys = std::move(childKeys);
    }
    return blocks;
}

std::array<double, 6> sggxEntries(const octree::VoxelData& voxel) {
    const octree::SggxMatrix s = octree::unpackS(voxel);
    return {s.xx, s.yy, s.zz, s.xy, s.xz, s.yz};
}

}  // namespace vtex::interop
