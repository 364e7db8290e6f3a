#include "own_share.h"

#include "source_bvh.h"

#include <vtex/sampler/clip.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <numeric>
#include <unordered_map>

namespace vtex::render::detail {
namespace {

// Union–find over triangles, with path halving.
class Components {
public:
    explicit Components(std::size_t n) : mParent(n) { std::iota(mParent.begin(), mParent.end(), std::uint32_t(0)); }
    std::uint32_t find(std::uint32_t x) {
        while (mParent[x] != x) x = mParent[x] = mParent[mParent[x]];
        return x;
    }
    void join(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a != b) mParent[std::max(a, b)] = std::min(a, b);
    }

private:
    std::vector<std::uint32_t> mParent;
};

struct PositionHash {
    std::size_t operator()(const Vec3& p) const {
        std::uint64_t h = 0x9e3779b97f4a7c15ull;
        for (int i = 0; i < 3; ++i) h = (h ^ std::bit_cast<std::uint64_t>(p[i] + 0.0)) * 0xff51afd7ed558ccdull;
        return std::size_t(h ^ (h >> 32));
    }
};
struct PositionEqual {
    bool operator()(const Vec3& a, const Vec3& b) const { return a == b; }
};

// Each triangle's component: triangles sharing a corner position are one.
std::vector<std::uint32_t> componentOf(const SourceBvh& source) {
    const auto count = std::uint32_t(source.triangleCount());
    Components components(count);
    std::unordered_map<Vec3, std::uint32_t, PositionHash, PositionEqual> first;
    first.reserve(std::size_t(count) * 2);
    for (std::uint32_t t = 0; t < count; ++t)
        for (const Vec3& corner : source.triangle(t)) {
            const auto [it, inserted] = first.emplace(corner, t);
            if (!inserted) components.join(it->second, t);
        }
    std::vector<std::uint32_t> of(count);
    for (std::uint32_t t = 0; t < count; ++t) of[t] = components.find(t);
    return of;
}

// A piece of surface: the voxel (x, y, z at 10 bits each, above bit 32) and the component (the
// low 32 bits), and its area.
struct Piece {
    std::uint64_t key;
    double area;
};
std::uint64_t keyOf(std::uint64_t x, std::uint64_t y, std::uint64_t z, std::uint32_t component) {
    return (x | y << 10 | z << 20) << 32 | component;
}

// Sorts the pieces by key and merges those of one key.
void merge(std::vector<Piece>& pieces) {
    std::sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) { return a.key < b.key; });
    std::size_t out = 0;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        if (out > 0 && pieces[out - 1].key == pieces[i].key)
            pieces[out - 1].area += pieces[i].area;
        else
            pieces[out++] = pieces[i];
    }
    pieces.resize(out);
}

// s_L of the merged pieces: Σ_v Σ_c a² / A_v over Σ_v A_v.
double shareOf(const std::vector<Piece>& pieces) {
    double weighted = 0, total = 0;
    for (std::size_t i = 0; i < pieces.size();) {
        const std::uint64_t voxel = pieces[i].key >> 32;
        double sum = 0, squares = 0;
        for (; i < pieces.size() && pieces[i].key >> 32 == voxel; ++i) {
            sum += pieces[i].area;
            squares += pieces[i].area * pieces[i].area;
        }
        if (sum > 0) weighted += squares / sum;
        total += sum;
    }
    // Σ a² ≤ (Σ a)² per voxel, so the share is at most 1 but for rounding (a² / a need not be a).
    return total > 0 ? std::min(weighted / total, 1.0) : 0.0;
}

}  // namespace

std::vector<double> measureOwnShares(const SourceBvh& source, int finestLevel) {
    const int finest = std::clamp(finestLevel, 0, kMaxOwnShareLevel);
    const std::vector<std::uint32_t> component = componentOf(source);
    const std::uint32_t n = 1u << finest;
    const double scale = double(n);
    std::vector<Piece> pieces;
    for (std::uint32_t t = 0; t < component.size(); ++t) {
        const std::array<Vec3, 3> c = source.triangle(t);
        sampler::clipTriangleToGrid(c[0] * scale, c[1] * scale, c[2] * scale, n, source.cyclic(),
                                    [&](std::uint32_t x, std::uint32_t y, std::uint32_t z, const sampler::ClipPolygon& p) {
                                        const double area = p.area();
                                        if (area > 0) pieces.push_back({keyOf(x, y, z, component[t]), area});
                                    });
    }
    std::vector<double> shares(std::size_t(finest) + 1, 0.0);
    merge(pieces);
    for (int level = finest;; --level) {
        shares[std::size_t(level)] = shareOf(pieces);
        if (level == 0) break;
        // The parent voxel: each coordinate halved.
        constexpr std::uint64_t kMask = (1u << 10) - 1;
        for (Piece& p : pieces) {
            const std::uint64_t v = p.key >> 32;
            p.key = keyOf((v & kMask) >> 1, (v >> 10 & kMask) >> 1, (v >> 20 & kMask) >> 1, std::uint32_t(p.key));
        }
        merge(pieces);
    }
    return shares;
}

}  // namespace vtex::render::detail
