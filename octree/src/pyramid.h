// The builder's uncompressed pyramid (octree_build.cpp): its nodes, and the filter of one parent
// from its children, with the filter error measured on the sampled nodes. Internal to
// vtex_octree.
//
// F. Neyret, "Un modèle général et multiéchelle de textures volumiques", AFIG 1994, §3.3
// (filtering the micro-primitives); DESIGN.md, "Octree: filtering and compression".
#pragma once

#include <vtex/octree/filtering.h>
#include <vtex/octree/volume.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

namespace vtex::octree::detail {

constexpr std::uint8_t kSource = 1;  // a block given by the volume: it has no children here

struct PNode {
    std::uint64_t key;
    VoxelData data;
    float filterError;  // NaN: not measured yet
    std::uint8_t flags;
};

// Leaves the nodes of a resized level unwritten: each is written right after, from all
// threads, and initialising them first was one more single-threaded pass over the level's fresh
// pages (a pyramid level holds up to millions of nodes). Default-initialising was not enough:
// a PNode's VoxelData has default member values, whose stores were a third of buildAll's own
// samples at 512³ (perf record). Nothing is constructed: a node is an aggregate with a trivial
// destructor, an implicit-lifetime type, which the allocated storage holds as soon as it is
// written ([intro.object]).
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
    UninitialisedAllocator() = default;
    template <class U>
    UninitialisedAllocator(const UninitialisedAllocator<U>&) noexcept {}
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
    template <class U>
    void construct(U*) noexcept {
        static_assert((std::is_aggregate_v<U> || std::is_trivially_default_constructible_v<U>) &&
                      std::is_trivially_destructible_v<U> && std::is_trivially_copyable_v<U>);
    }
};

using Level = std::vector<PNode, UninitialisedAllocator<PNode>>;

// The pyramid node of a block the volume gives: it has no children here.
inline PNode sourceNode(const VolumeBlock& b) {
    return PNode{b.key, b.data, std::numeric_limits<float>::quiet_NaN(), kSource};
}

// Whether the filter error of node `key` of `level` is measured, given that the level has
// `count` filtered nodes: a hash-selected sample of about `samples` of them, independent of the
// order in which nodes were built, so an update and a full build measure the same nodes.
bool isSampled(std::uint64_t key, std::uint32_t level, std::uint64_t count, std::uint64_t samples);

// One parent's filter: its voxel, and what it was made of (kept for the filter error).
struct Filtered {
    VoxelData data;
    std::vector<Mat3> forms;  // what the rule averages, per child with an ellipsoid
    std::vector<double> weights;
    std::vector<std::size_t> formChildren;  // which child each form is of
    std::optional<Ellipsoid> result;
    // Sggx without keepResult: the forms' mean, whose primitive the caller packs with those of
    // other parents (packSggxMeans) into data.rotation and data.sigma.
    std::optional<Mat3> deferredMean;
};

// The design's filter for one parent from its (1 to 8) non-empty children. The children are
// read through storedFilterForm, not rebuilt as Ellipsoids: this runs once per node of the
// pyramid and was the build's cost (an eigensolver and elliptic integrals per child).
// `keepResult`: the filtered Ellipsoid is kept in out.result, for filterErrorOf; otherwise only
// its packed form is made (filterFormsPacked), the same bytes for less, and with the Sggx rule
// left to the caller (out.deferredMean: finishDeferred packs several parents' at once).
void filterChildren(const PNode* children, std::size_t count, FilterRule rule, bool keepResult, Filtered& out);

// Packs the primitives of the parents whose filterChildren left a deferred mean: `parents[k]`'s
// data gets the primitive of `means[k]`, as filterChildren would have packed it.
void finishDeferred(std::span<VoxelData* const> parents, std::span<const Mat3> means);

// The filter error of one parent whose filter `f` of its children filterChildren has just made
// (filterError: its NDF against the mixture of its children's), with the children rebuilt as
// Ellipsoids; for the sampled nodes only. `rule`: the one filterChildren was given.
double filterErrorOf(const PNode* children, std::size_t count, const Filtered& f, FilterRule rule);

}  // namespace vtex::octree::detail
