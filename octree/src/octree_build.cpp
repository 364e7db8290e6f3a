// Building the octree: filtering every level from the sampled finest level, compressing it, and
// re-filtering only the ancestors of a re-sampled region.
//
// F. Neyret, "Un modèle général et multiéchelle de textures volumiques", AFIG 1994: §3 (the
// multiscale octree, compression of uniform regions, 91–93% at 128³) and §3.3 (filtering the
// micro-primitives). DESIGN.md, "Octree: filtering and compression".
//
// The builder keeps an uncompressed *pyramid*: per level, the non-empty nodes sorted by Morton
// key, so a node's children are one contiguous run of the next level. Memory is O(occupied
// voxels); nothing is ever N³. Compression is a separate, cheap pass over the pyramid, so a
// partial update re-filters only the ancestors of its region and yields exactly what a full
// build of the same volume yields.
#include <vtex/octree/density_profile.h>
#include <vtex/octree/octree.h>

#include "pyramid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace vtex::octree {
namespace {

using namespace detail;

// A box of node indices at some level, half-open.
struct LevelBox {
    std::array<std::uint32_t, 3> min, max;
    bool contains(std::uint64_t key) const {
        const auto c = mortonDecode(key);
        return c[0] >= min[0] && c[0] < max[0] && c[1] >= min[1] && c[1] < max[1] && c[2] >= min[2] &&
               c[2] < max[2];
    }
};

LevelBox boxAtLevel(const VoxelBox& box, std::uint32_t shift) {
    LevelBox b;
    for (int a = 0; a < 3; ++a) {
        b.min[a] = box.min[a] >> shift;
        b.max[a] = box.max[a] > box.min[a] ? ((box.max[a] - 1) >> shift) + 1 : b.min[a];
    }
    return b;
}

// The indices i in [0, n) with pick(i), in increasing order, found on all threads: a level's
// walk over its millions of nodes otherwise ran on one core while the other waited. A body
// object, not parallel_reduce's functional form, which hands each range a copy of the indices
// gathered so far (80 million instructions of copying at 512³, callgrind).
template <class Pick>
std::vector<std::size_t> pickIndices(std::size_t n, const Pick& pick) {
    struct Body {
        const Pick& pick;
        std::vector<std::size_t> picked;
        Body(const Pick& p) : pick(p) {}
        Body(Body& other, tbb::split) : pick(other.pick) {}
        void operator()(const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i != range.end(); ++i)
                if (pick(i)) picked.push_back(i);
        }
        // `right` covers the indices after this body's: appending keeps the order.
        void join(Body& right) { picked.insert(picked.end(), right.picked.begin(), right.picked.end()); }
    } body(pick);
    tbb::parallel_reduce(tbb::blocked_range<std::size_t>(0, n, 16384), body);
    return std::move(body.picked);
}

// Indices where a new parent starts in a sorted child level, restricted to `keep(parentKey)`.
template <class Keep>
std::vector<std::size_t> groupStarts(const Level& children, Keep keep) {
    return pickIndices(children.size(), [&](std::size_t i) {
        const std::uint64_t parent = children[i].key >> 3;
        return (i == 0 || (children[i - 1].key >> 3) != parent) && keep(parent);
    });
}

// The range of every entry a node's descendants hold (density, the matrix S, albedo): what the
// tolerance compares a node's own values with. Ranges compare the matrices S (the quaternion of
// a primitive is not unique).
struct Range {
    float dmin, dmax;
    std::array<float, 6> smin, smax;
    std::array<float, 3> amin, amax;
};

Range pointRange(const VoxelData& d) {
    const SggxMatrix S = unpackS(d);
    const std::array<float, 6> s{float(S.xx), float(S.yy), float(S.zz), float(S.xy), float(S.xz), float(S.yz)};
    return Range{d.density, d.density, s, s, d.albedo, d.albedo};
}

// The voxels of the finest level L that a block of `level` at Morton `key` covers.
VoxelBox blockExtent(std::uint64_t key, std::uint32_t level, std::uint32_t L) {
    const auto c = mortonDecode(key);
    const std::uint32_t shift = L - level;
    VoxelBox b;
    for (int a = 0; a < 3; ++a) {
        b.min[a] = c[a] << shift;
        b.max[a] = (c[a] + 1) << shift;
    }
    return b;
}

bool within(const VoxelBox& b, const VoxelBox& r) {
    for (int a = 0; a < 3; ++a)
        if (b.min[a] < r.min[a] || b.max[a] > r.max[a]) return false;
    return true;
}

bool apart(const VoxelBox& b, const VoxelBox& r) {
    for (int a = 0; a < 3; ++a)
        if (b.max[a] <= r.min[a] || b.min[a] >= r.max[a]) return true;
    return false;
}

// The finest level's blocks with `region` given over to `fresh` (OctreeBuilder::updateRegion):
// blocks outside it kept, blocks inside it dropped, straddling blocks split until each piece is
// inside or outside. Returns the dirty box: the region grown over the straddling blocks, whose
// representation changes.
VoxelBox spliceRegion(std::vector<VolumeBlock>& blocks, const VoxelBox& region, std::vector<VolumeBlock> fresh,
                      std::uint32_t L) {
    VoxelBox dirty = region;
    std::vector<VolumeBlock> kept;
    kept.reserve(blocks.size() + fresh.size());
    std::vector<VolumeBlock> stack;
    for (const auto& b : blocks) {
        const VoxelBox extent = blockExtent(b.key, b.level, L);
        if (apart(extent, region)) {
            kept.push_back(b);
            continue;
        }
        if (within(extent, region)) continue;
        for (int a = 0; a < 3; ++a) {
            dirty.min[a] = std::min(dirty.min[a], extent.min[a]);
            dirty.max[a] = std::max(dirty.max[a], extent.max[a]);
        }
        stack.push_back(b);
        while (!stack.empty()) {
            const VolumeBlock piece = stack.back();
            stack.pop_back();
            const VoxelBox e = blockExtent(piece.key, piece.level, L);
            if (apart(e, region)) kept.push_back(piece);
            else if (!within(e, region))
                for (std::uint64_t c = 0; c < 8; ++c)
                    stack.push_back(VolumeBlock{(piece.key << 3) | c, std::uint8_t(piece.level + 1), piece.flags, piece.data});
        }
    }
    for (auto& b : fresh) kept.push_back(b);
    blocks = std::move(kept);
    return dirty;
}

}  // namespace

struct OctreeBuilder::Impl {
    SparseVolume volume;
    BuildOptions options;
    bool keepFinest = true;     // volume.blocks kept after buildAll, for finest() and updateRegion
    std::vector<Level> levels;  // levels[ℓ], ℓ = 0 … L
    std::atomic<std::uint64_t> filtered{0};

    std::uint32_t L() const { return volume.info.levels; }

    // Filters the parents (keys passing `keep`) of level `childLevel`. `measure`: these are all
    // the filtered nodes of their level (a full build), so which of them measureFilterErrors
    // samples is known now, and their filter errors are measured from the filter just made
    // rather than from a second one later.
    template <class Keep>
    Level filterParents(std::uint32_t childLevel, Keep keep, bool measure, Progress& progress) {
        const Level& children = levels[childLevel];
        const std::vector<std::size_t> starts = groupStarts(children, keep);
        Level parents(starts.size());
        const std::uint32_t parentLevel = childLevel - 1;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, starts.size(), 256),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              Filtered f;
                              // The parents whose primitives finishDeferred packs together.
                              std::vector<VoxelData*> deferred;
                              std::vector<Mat3> means;
                              for (std::size_t g = range.begin(); g != range.end(); ++g) {
                                  const std::size_t begin = starts[g];
                                  std::size_t end = begin + 1;
                                  const std::uint64_t parent = children[begin].key >> 3;
                                  while (end < children.size() && (children[end].key >> 3) == parent) ++end;
                                  const bool sampled = measure && isSampled(parent, parentLevel, starts.size(),
                                                                            options.filterErrorSamples);
                                  filterChildren(&children[begin], end - begin, options.rule, sampled, f);
                                  const float error = sampled ? float(filterErrorOf(&children[begin], end - begin, f, options.rule))
                                                              : std::numeric_limits<float>::quiet_NaN();
                                  parents[g] = PNode{parent, f.data, error, 0};
                                  if (f.deferredMean) {
                                      deferred.push_back(&parents[g].data);
                                      means.push_back(*f.deferredMean);
                                  }
                              }
                              finishDeferred(deferred, means);
                              progress.advance(range.size());
                          });
        filtered += parents.size();
        return parents;
    }

    static Level mergeSorted(Level a, Level b) {
        if (b.empty()) return a;  // the common case: no source blocks at a level above the finest
        if (a.empty()) return b;
        Level out;
        out.reserve(a.size() + b.size());
        std::merge(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out),
                   [](const PNode& x, const PNode& y) { return x.key < y.key; });
        return out;
    }

    void buildAll(Progress& progress) {
        levels.assign(L() + 1, {});
        std::vector<Level> sources(L() + 1);
        // Sized first: grown by doubling, the finest level (millions of nodes) was copied and its
        // fresh pages cleared about twice over.
        std::vector<std::size_t> counts(L() + 1, 0);
        for (const auto& b : volume.blocks) ++counts[b.level];
        const auto& blocks = volume.blocks;
        if (counts[L()] == blocks.size()) {
            // Every block a finest voxel (any texel without a solid interior): copied from all threads.
            sources[L()].resize(blocks.size());
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 16384),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t i = range.begin(); i != range.end(); ++i)
                                      sources[L()][i] = sourceNode(blocks[i]);
                              });
        } else {
            for (std::uint32_t l = 0; l <= L(); ++l) sources[l].reserve(counts[l]);
            for (const auto& b : blocks) sources[b.level].push_back(sourceNode(b));
        }
        // The pyramid now holds every block: a builder nobody updates frees them here (56 bytes
        // per finest voxel), so the levels and the tree made next can reuse that memory instead
        // of faulting in fresh pages (vtex build keeps freed memory: keepFreedMemory).
        if (!keepFinest) std::vector<VolumeBlock>().swap(volume.blocks);
        const std::uint64_t total = counts[L()];
        progress.start("filter", total + total / 7 + 1);
        levels[L()] = std::move(sources[L()]);
        for (std::uint32_t l = L(); l-- > 0;) {
            Level parents = filterParents(l + 1, [](std::uint64_t) { return true; }, true, progress);
            levels[l] = mergeSorted(std::move(parents), std::move(sources[l]));
        }
        progress.finish();
    }

    // Where each node's children start in levels[level + 1], and one past the last node's: the
    // children of node i are [starts[i], starts[i + 1]). One linear walk, since both levels are
    // sorted by key and every node below the root has its parent in the pyramid.
    std::vector<std::uint32_t> childStarts(std::uint32_t level) const {
        const Level& parents = levels[level];
        const Level& children = levels[level + 1];
        std::vector<std::uint32_t> starts(parents.size() + 1);
        std::size_t c = 0;
        for (std::size_t i = 0; i < parents.size(); ++i) {
            starts[i] = std::uint32_t(c);
            while (c < children.size() && (children[c].key >> 3) == parents[i].key) ++c;
        }
        starts[parents.size()] = std::uint32_t(c);
        if (c != children.size()) throw std::logic_error("octree pyramid: a node without its parent");
        return starts;
    }

    // Occupancy and density per level (a source block at level k stands for 8^(ℓ−k) voxels).
    void levelStats(std::vector<LevelStats>& stats) const {
        const std::uint32_t L = this->L();
        std::vector<double> srcCount(L + 1, 0), srcMass(L + 1, 0);
        for (std::uint32_t l = 0; l <= L; ++l) {
            double count = double(levels[l].size()), mass = 0;
            for (const auto& n : levels[l]) mass += n.data.density;
            for (std::uint32_t k = 0; k < l; ++k) {
                const double copies = std::ldexp(1.0, 3 * int(l - k));
                count += srcCount[k] * copies;
                mass += srcMass[k] * copies;
            }
            for (const auto& n : levels[l])
                if (n.flags & kSource) {
                    srcCount[l] += 1;
                    srcMass[l] += n.data.density;
                }
            LevelStats& s = stats[l];
            s.occupiedNodes = std::uint64_t(count);
            s.meanDensity = mass / std::ldexp(1.0, 3 * int(l));
            s.meanOccupiedDensity = count > 0 ? mass / count : 0;
        }
    }

    // Whether `node` (level l, its children [b, e) at level l + 1) may stand for all its
    // descendants within the tolerance; if so, the range of what they hold goes to `range`.
    // `rangeOfChild(c)` is read only for children that may stand for theirs.
    template <class RangeOfChild>
    bool mayStandForDescendants(const PNode& node, std::uint32_t l, std::size_t b, std::size_t e,
                                const std::vector<std::uint8_t>& childCollapsible, RangeOfChild rangeOfChild,
                                Range& range) const {
        const VoxelData& p = node.data;
        if (node.flags & kSource) {
            range = pointRange(p);
            return true;
        }
        for (std::size_t c = b; c < e; ++c)
            if (!childCollapsible[c]) return false;
        if (!options.compress) return false;
        const double eps = options.tolerance;
        const Range self = pointRange(p);
        const double selfTrace = double(self.smax[0]) + double(self.smax[1]) + double(self.smax[2]);
        // Transmittance: standing for its descendants, the node changes the extinction anywhere
        // in its voxel by at most Δρ·Â, Â ≤ √(tr S) for every descendant's and its own
        // normalised S, so the transmittance along any chord of its voxel (length ≤ √3·h) by at
        // most Δρ·√(tr S_max)·√3·h (|e^−a − e^−b| ≤ |a − b|), for τ = 1. A missing child is
        // density 0: a node merges with empty space when its own optical depth across itself is
        // within ε.
        const auto transmittanceChange = [&](double dRho, double trace) {
            return dRho * std::sqrt(trace) * std::sqrt(3.0) * std::ldexp(1.0, -int(l));
        };
        // With a child missing, Δρ ≥ ρ and tr S_max ≥ its own: this lower bound of the change
        // (the same expression, rounded the same way on smaller operands) already refuses most
        // surface nodes, before any child's range is read (unpacking S is the cost here).
        if (e - b < 8 && transmittanceChange(double(p.density), std::max(0.0, selfTrace)) > eps) return false;
        Range r = rangeOfChild(b);
        if (e - b < 8) r.dmin = 0;  // missing children are empty
        for (std::size_t c = b; c < e; ++c) {
            const Range cr = rangeOfChild(c);
            r.dmin = std::min(r.dmin, cr.dmin);
            r.dmax = std::max(r.dmax, cr.dmax);
            for (int k = 0; k < 6; ++k) {
                r.smin[k] = std::min(r.smin[k], cr.smin[k]);
                r.smax[k] = std::max(r.smax[k], cr.smax[k]);
            }
            for (int k = 0; k < 3; ++k) {
                r.amin[k] = std::min(r.amin[k], cr.amin[k]);
                r.amax[k] = std::max(r.amax[k], cr.amax[k]);
            }
        }
        const double dRho = std::max(double(p.density) - double(r.dmin), double(r.dmax) - double(p.density));
        const double childTrace = double(r.smax[0]) + double(r.smax[1]) + double(r.smax[2]);
        if (!(transmittanceChange(dRho, std::max({0.0, childTrace, selfTrace})) <= eps)) return false;
        for (int k = 0; k < 6; ++k)
            if (!(double(self.smin[k]) - double(r.smin[k]) <= eps && double(r.smax[k]) - double(self.smin[k]) <= eps))
                return false;
        for (int k = 0; k < 3; ++k)
            if (!(double(p.albedo[k]) - double(r.amin[k]) <= eps && double(r.amax[k]) - double(p.albedo[k]) <= eps))
                return false;
        range = r;
        return true;
    }

    // Bottom-up: which pyramid nodes may stand for all their descendants within the tolerance.
    // Ranges of the finest level are not stored (they are points, read from each node's data):
    // at 1024³ that level alone would take 80 bytes per voxel. A level's ranges are written only
    // for its collapsible nodes, the only ones a parent reads, into storage left uninitialised,
    // so the pages of the others are never touched.
    std::vector<std::vector<std::uint8_t>> collapsibleNodes(const std::vector<std::vector<std::uint32_t>>& starts,
                                                            Progress& progress) const {
        const std::uint32_t L = this->L();
        std::vector<std::vector<std::uint8_t>> collapsible(L + 1);
        collapsible[L].assign(levels[L].size(), 1);
        std::unique_ptr<Range[]> below, current;
        for (std::uint32_t l = L; l-- > 0;) {
            const Level& level = levels[l];
            const auto rangeOfChild = [&](std::size_t c) {
                return l + 1 == L ? pointRange(levels[L][c].data) : below[c];
            };
            collapsible[l].assign(level.size(), 0);
            current.reset(new Range[level.size()]);
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, level.size(), 1024),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t i = range.begin(); i != range.end(); ++i)
                                      collapsible[l][i] = mayStandForDescendants(level[i], l, starts[l][i], starts[l][i + 1],
                                                                                 collapsible[l + 1], rangeOfChild, current[i]);
                              });
            std::swap(below, current);
            progress.advance(1);
        }
        return collapsible;
    }

    // Top-down: the stored tree, level by level. A stored node that cannot stand for its
    // descendants stores all its pyramid children; their places come from a prefix sum of the
    // children counts, so each level is filled from all threads.
    void storeTree(const std::vector<std::vector<std::uint8_t>>& collapsible,
                   const std::vector<std::vector<std::uint32_t>>& starts, Octree& tree) const {
        const std::uint32_t L = this->L();
        tree.levels.assign(L + 1, {});
        std::vector<std::size_t> pyramidIndex, nextIndex, offsets;
        if (levels[0].empty()) {
            tree.levels[0].push_back(OctreeNode{});
        } else {
            tree.levels[0].push_back(OctreeNode{levels[0][0].data, 0, 0});
            pyramidIndex.push_back(0);
        }
        for (std::uint32_t l = 0; l < L; ++l) {
            auto& stored = tree.levels[l];
            auto& next = tree.levels[l + 1];
            const Level& children = levels[l + 1];
            offsets.assign(pyramidIndex.size() + 1, 0);
            for (std::size_t s = 0; s < pyramidIndex.size(); ++s) {
                const std::size_t i = pyramidIndex[s];
                offsets[s + 1] = offsets[s] + (collapsible[l][i] ? 0 : starts[l][i + 1] - starts[l][i]);
            }
            next.resize(offsets.back());
            nextIndex.resize(offsets.back());
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pyramidIndex.size(), 2048),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  for (std::size_t s = range.begin(); s != range.end(); ++s) {
                                      const std::size_t i = pyramidIndex[s];
                                      if (collapsible[l][i]) continue;
                                      stored[s].firstChild = std::uint32_t(offsets[s]);
                                      std::size_t out = offsets[s];
                                      for (std::size_t c = starts[l][i]; c < starts[l][i + 1]; ++c, ++out) {
                                          stored[s].childMask |= std::uint8_t(1u << (children[c].key & 7));
                                          next[out] = OctreeNode{children[c].data, 0, 0};
                                          nextIndex[out] = c;
                                      }
                                  }
                              });
            std::swap(pyramidIndex, nextIndex);
        }
    }

    // Measures the filter error of the sampled nodes that lack it; returns per-level stats.
    // `starts[l]`: childStarts(l).
    void measureFilterErrors(const std::vector<std::vector<std::uint32_t>>& starts, std::vector<LevelStats>& stats) {
        for (std::uint32_t l = 0; l < L(); ++l) {
            Level& level = levels[l];
            std::uint64_t count = 0;
            for (const auto& n : level) count += (n.flags & kSource) ? 0 : 1;
            const std::vector<std::size_t> selected = pickIndices(level.size(), [&](std::size_t i) {
                return !(level[i].flags & kSource) && isSampled(level[i].key, l, count, options.filterErrorSamples);
            });
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, selected.size(), 64),
                              [&](const tbb::blocked_range<std::size_t>& range) {
                                  Filtered f;
                                  for (std::size_t s = range.begin(); s != range.end(); ++s) {
                                      PNode& node = level[selected[s]];
                                      if (!std::isnan(node.filterError)) continue;
                                      const std::size_t b = starts[l][selected[s]], e = starts[l][selected[s] + 1];
                                      filterChildren(&levels[l + 1][b], e - b, options.rule, true, f);
                                      node.filterError = float(filterErrorOf(&levels[l + 1][b], e - b, f, options.rule));
                                  }
                              });
            double sum = 0, max = 0;
            for (std::size_t i : selected) {
                sum += level[i].filterError;
                max = std::max(max, double(level[i].filterError));
            }
            stats[l].filterErrorSamples = selected.size();
            stats[l].filterErrorMean = selected.empty() ? 0 : sum / double(selected.size());
            stats[l].filterErrorMax = max;
        }
    }
};

OctreeBuilder::OctreeBuilder(SparseVolume finest, const BuildOptions& options, Progress& progress)
    : OctreeBuilder(std::move(finest), options, progress, true) {}

OctreeBuilder::OctreeBuilder(SparseVolume finest, const BuildOptions& options, Progress& progress, bool keepFinest)
    : mImpl(std::make_unique<Impl>()) {
    if (finest.info.levels > std::uint32_t(kMaxLevel)) throw std::invalid_argument("resolution too large");
    if (!(options.tolerance >= 0) || !std::isfinite(options.tolerance))
        throw std::invalid_argument("tolerance must be finite and non-negative");
    mImpl->volume = std::move(finest);
    mImpl->volume.sortBlocks();
    mImpl->options = options;
    mImpl->keepFinest = keepFinest;
    mImpl->buildAll(progress);
}

OctreeBuilder::OctreeBuilder() : mImpl(std::make_unique<Impl>()) {}

std::optional<OctreeBuilder> OctreeBuilder::resume(const Octree& tree, const VolumeInfo& info, const BuildOptions& options) {
    tree.loadLevels(~std::uint32_t(0));
    const std::uint32_t L = tree.info.source.levels;
    if (tree.levelCount() != L + 1 || info.levels != L || info.solidDensity != 0 || tree.info.source.solidDensity != 0)
        return std::nullopt;
    OctreeBuilder builder;
    Impl& m = *builder.mImpl;
    m.options = options;
    m.volume.info = info;
    m.levels.assign(L + 1, {});
    // The pyramid is the stored tree when nothing above the finest level was merged: every
    // stored node there has children, and a stored node's data is its pyramid node's.
    const OctreeNode& root = tree.levels[0][0];
    if (root.data.isEmpty() && root.isLeaf()) return builder;  // an empty volume
    std::vector<std::uint64_t> keys{0}, next;
    for (std::uint32_t l = 0; l <= L; ++l) {
        next.clear();
        Level& level = m.levels[l];
        level.reserve(tree.levels[l].size());
        for (std::size_t i = 0; i < tree.levels[l].size(); ++i) {
            const OctreeNode& node = tree.levels[l][i];
            if (l < L && node.isLeaf()) return std::nullopt;  // merged: its descendants are not stored
            level.push_back(PNode{keys[i], node.data, std::numeric_limits<float>::quiet_NaN(),
                                  std::uint8_t(l == L ? kSource : 0)});
            for (unsigned c = 0; c < 8; ++c)
                if (node.childMask & (1u << c)) next.push_back((keys[i] << 3) | c);
        }
        std::swap(keys, next);
    }
    m.volume.blocks.reserve(m.levels[L].size());
    for (const PNode& node : m.levels[L]) m.volume.blocks.push_back(VolumeBlock{node.key, std::uint8_t(L), 0, node.data});
    return builder;
}

OctreeBuilder::~OctreeBuilder() = default;
OctreeBuilder::OctreeBuilder(OctreeBuilder&&) noexcept = default;
OctreeBuilder& OctreeBuilder::operator=(OctreeBuilder&&) noexcept = default;

const SparseVolume& OctreeBuilder::finest() const { return mImpl->volume; }
std::uint64_t OctreeBuilder::filteredNodeCount() const { return mImpl->filtered.load(); }

void OctreeBuilder::updateRegion(const VoxelBox& region, std::vector<VolumeBlock> blocks, Progress& progress) {
    Impl& m = *mImpl;
    const std::uint32_t L = m.L();
    const std::uint32_t n = std::uint32_t(1) << L;
    for (int a = 0; a < 3; ++a)
        if (region.max[a] > n || region.min[a] > region.max[a])
            throw std::invalid_argument("updateRegion: region outside the volume");
    for (const auto& b : blocks)
        if (b.level > L || !within(blockExtent(b.key, b.level, L), region))
            throw std::invalid_argument("updateRegion: a new block lies outside the region");

    // The new finest level; the dirty box D.
    const VoxelBox dirty = spliceRegion(m.volume.blocks, region, std::move(blocks), L);
    m.volume.sortBlocks();

    // New source nodes inside D, per level.
    std::vector<Level> sources(L + 1);
    for (const auto& b : m.volume.blocks)
        if (!apart(blockExtent(b.key, b.level, L), dirty))
            sources[b.level].push_back(sourceNode(b));

    progress.start("refilter", L + 1);
    for (std::uint32_t l = L + 1; l-- > 0;) {
        const LevelBox box = boxAtLevel(dirty, L - l);
        Level keptNodes;
        keptNodes.reserve(m.levels[l].size());
        for (const auto& node : m.levels[l])
            if (!box.contains(node.key)) keptNodes.push_back(node);
        Level fresh = std::move(sources[l]);
        if (l < L) {
            Level parents = m.filterParents(l + 1, [&](std::uint64_t parent) { return box.contains(parent); },
                                            false, progress);
            // A source block at this level has no children below it, so no parent collides with it.
            fresh = Impl::mergeSorted(std::move(parents), std::move(fresh));
        }
        m.levels[l] = Impl::mergeSorted(std::move(keptNodes), std::move(fresh));
        progress.advance(1);
    }
    progress.finish();
}

Octree OctreeBuilder::compress(Progress& progress) const {
    const Impl& m = *mImpl;
    const std::uint32_t L = m.L();
    Octree tree;
    tree.info.source = m.volume.info;
    tree.info.rule = m.options.rule;
    tree.info.tolerance = float(m.options.tolerance);
    tree.stats.assign(L + 1, {});
    progress.start("compress", L + 1);
    m.levelStats(tree.stats);
    std::vector<std::vector<std::uint32_t>> starts(L);
    tbb::parallel_for(std::uint32_t(0), L, [&](std::uint32_t l) { starts[l] = m.childStarts(l); });
    mImpl->measureFilterErrors(starts, tree.stats);
    m.storeTree(m.collapsibleNodes(starts, progress), starts, tree);
    for (std::uint32_t l = 0; l <= L; ++l) tree.stats[l].storedNodes = tree.levels[l].size();
    // What a render's coarse levels are profiled with (octree/density_profile.h), measured here
    // where every level is in memory; a render that marches only those levels then reads none
    // finer (reading level 6 for it took 10 ms of the bush field's far view).
    if (DensityProfile::profiledLevels(int(L)) > 0) tree.layerMeans = measureLayerMeans(tree);
    progress.finish();
    return tree;
}

Octree buildOctree(SparseVolume volume, const BuildOptions& options, Progress& progress) {
    OctreeBuilder builder(std::move(volume), options, progress, false);
    return builder.compress(progress);
}

std::uint64_t estimateBuildMemory(const std::filesystem::path& file) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec) return 0;
    return std::uint64_t(std::min(12.0 * double(size) + double(32 << 20), 1.8e19));
}

}  // namespace vtex::octree
