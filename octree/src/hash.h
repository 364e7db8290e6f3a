// The splitmix64 finaliser, the octree library's one hash of integers: a pure function of its
// input, for choices that must not depend on threads or build order (which nodes the filter
// error samples, the chords of the chord measure). Internal.
#pragma once

#include <cstdint>

namespace vtex::octree::detail {

inline std::uint64_t mix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

}  // namespace vtex::octree::detail
