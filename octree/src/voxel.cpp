// Voxel records and Morton keys (octree/include/vtex/octree/voxel.h).
#include <vtex/octree/voxel.h>

namespace vtex::octree {
namespace {

// Spreads the low 20 bits of v so that bit i lands on bit 3i.
std::uint64_t spread3(std::uint32_t v) {
    std::uint64_t x = v & 0xFFFFFu;
    x = (x | (x << 32)) & 0x1F00000000FFFFull;
    x = (x | (x << 16)) & 0x1F0000FF0000FFull;
    x = (x | (x << 8)) & 0x100F00F00F00F00Full;
    x = (x | (x << 4)) & 0x10C30C30C30C30C3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
}

std::uint32_t compact3(std::uint64_t x) {
    x &= 0x1249249249249249ull;
    x = (x ^ (x >> 2)) & 0x10C30C30C30C30C3ull;
    x = (x ^ (x >> 4)) & 0x100F00F00F00F00Full;
    x = (x ^ (x >> 8)) & 0x1F0000FF0000FFull;
    x = (x ^ (x >> 16)) & 0x1F00000000FFFFull;
    x = (x ^ (x >> 32)) & 0xFFFFFull;
    return std::uint32_t(x);
}

}  // namespace

std::uint64_t mortonEncode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return spread3(x) | (spread3(y) << 1) | (spread3(z) << 2);
}

std::array<std::uint32_t, 3> mortonDecode(std::uint64_t key) {
    return {compact3(key), compact3(key >> 1), compact3(key >> 2)};
}

}  // namespace vtex::octree
