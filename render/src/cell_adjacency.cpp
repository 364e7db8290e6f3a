// See cell_adjacency.h.
#include "cell_adjacency.h"

#include <algorithm>
#include <utility>

namespace vtex::render::detail {
namespace {

using FaceKey = std::array<double, 12>;

// The four corners as one key that does not depend on their order.
FaceKey keyOf(const std::array<Vec3, 4>& corners) {
    std::array<std::array<double, 3>, 4> points;
    for (int i = 0; i < 4; ++i) points[std::size_t(i)] = {corners[std::size_t(i)].x(), corners[std::size_t(i)].y(), corners[std::size_t(i)].z()};
    std::sort(points.begin(), points.end());
    FaceKey key;
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) key[std::size_t(3 * i + k)] = points[std::size_t(i)][std::size_t(k)];
    return key;
}

bool hasEqualCorners(const std::array<Vec3, 4>& c) {
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
            if (c[std::size_t(i)] == c[std::size_t(j)]) return true;
    return false;
}

// This face's parameters (a, b) of the neighbour's corner j, under the symmetry s.
std::pair<int, int> cornerParameters(const CellNeighbour& s, int j) {
    const int x = s.swap ? (j >> 1) : (j & 1), y = s.swap ? (j & 1) : (j >> 1);
    return {s.flipA ? 1 - x : x, s.flipB ? 1 - y : y};
}

// The symmetry of the unit square that takes this face's corners `mine` to the neighbour's
// `theirs`, if one does.
bool findSymmetry(const std::array<Vec3, 4>& mine, const std::array<Vec3, 4>& theirs, CellNeighbour& out) {
    for (int code = 0; code < 8; ++code) {
        CellNeighbour s = out;
        s.flipA = code & 1;
        s.flipB = (code >> 1) & 1;
        s.swap = (code >> 2) & 1;
        bool all = true;
        for (int j = 0; j < 4 && all; ++j) {
            const auto [a, b] = cornerParameters(s, j);
            all = theirs[std::size_t(j)] == mine[std::size_t(a + 2 * b)];
        }
        if (all) {
            out = s;
            return true;
        }
    }
    return false;
}

// A side face's own parameters (a, b) at cell coordinates r (TrilinearCell::faceCorners).
std::pair<double, double> faceParameters(int face, const Vec3& r) {
    return face < 4 ? std::pair{r.y(), r.z()} : std::pair{r.x(), r.z()};
}

}  // namespace

CellAdjacency::CellAdjacency(const PrimTable& prims) : mSides(prims.size()) {
    // Every side face keyed by its corners, sorted so that the faces sharing corners are
    // consecutive (a sort rather than a map: a million cells are four million faces).
    struct Side {
        FaceKey key;
        int prim, face;
    };
    std::vector<Side> sides;
    for (std::size_t p = 0; p < prims.size(); ++p) {
        if (!prims.textured(p)) continue;
        const TrilinearCell cell = prims.cell(p);
        for (int face = 2; face < 6; ++face) {
            const auto corners = cell.faceCorners(face);
            if (!hasEqualCorners(corners)) sides.push_back({keyOf(corners), int(p), face});
        }
    }
    std::sort(sides.begin(), sides.end(), [](const Side& a, const Side& b) {
        return a.key != b.key ? a.key < b.key : std::pair(a.prim, a.face) < std::pair(b.prim, b.face);
    });
    for (std::size_t i = 0; i < sides.size();) {
        std::size_t j = i + 1;
        while (j < sides.size() && sides[j].key == sides[i].key) ++j;
        if (j - i == 2 && sides[i].prim != sides[i + 1].prim) {
            for (int side = 0; side < 2; ++side) {
                const Side& mine = sides[i + std::size_t(side)];
                const Side& theirs = sides[i + std::size_t(1 - side)];
                CellNeighbour n;
                n.prim = theirs.prim;
                n.face = theirs.face;
                if (findSymmetry(prims.cell(std::size_t(mine.prim)).faceCorners(mine.face),
                                 prims.cell(std::size_t(theirs.prim)).faceCorners(theirs.face), n))
                    mSides[std::size_t(mine.prim)][std::size_t(mine.face - 2)] = n;
            }
        }
        i = j;
    }
}

const CellNeighbour& CellAdjacency::across(int prim, int face) const {
    static const CellNeighbour kNone;
    if (prim < 0 || std::size_t(prim) >= mSides.size() || face < 2 || face > 5) return kNone;
    return mSides[std::size_t(prim)][std::size_t(face - 2)];
}

Vec3 CellAdjacency::toNeighbour(const CellNeighbour& n, int face, const Vec3& r) {
    const auto [a, b] = faceParameters(face, r);
    const double x = n.flipA ? 1 - a : a, y = n.flipB ? 1 - b : b;
    return TrilinearCell::faceToCell(n.face, n.swap ? y : x, n.swap ? x : y);
}

}  // namespace vtex::render::detail
