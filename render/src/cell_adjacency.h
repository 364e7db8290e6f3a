// Which texel cell lies across each side face of a cell, and how the shared face's parameters
// map from one cell to the other. Two cells are neighbours when one side face of each has the
// same four world corners (bit for bit: the mesh's shared vertices, lifted along the same vertex
// normal by the same height), so that the face is one bilinear patch seen from both; a face
// shared by more than two cells, or with two equal corners (a collapsed quad's side), has none.
// Built once per render from the tracer's primitives.
#pragma once

#include "tracer.h"

#include <array>
#include <vector>

namespace vtex::render::detail {

struct CellNeighbour {
    int prim = -1;   ///< −1: no neighbour across this face
    int face = -1;   ///< the shared face's index in the neighbour (TrilinearCell numbering, 2…5)
    /// The neighbour's face parameters (a′, b′) from this cell's (a, b): (x, y) = (a or 1 − a,
    /// b or 1 − b) by the flips, then (a′, b′) = (x, y), or (y, x) when swapped.
    bool flipA = false, flipB = false, swap = false;
};

class CellAdjacency {
public:
    CellAdjacency() = default;
    explicit CellAdjacency(const PrimTable& prims);

    /// The neighbour across side face `face` (2: u = 0, 3: u = 1, 4: v = 0, 5: v = 1) of
    /// primitive `prim`; prim = −1 when there is none (or `prim` is not a cell).
    const CellNeighbour& across(int prim, int face) const;

    /// The neighbour's cell coordinates of the point at cell coordinates r, which lies on side
    /// face `face` of this cell.
    static Vec3 toNeighbour(const CellNeighbour& n, int face, const Vec3& r);

private:
    std::vector<std::array<CellNeighbour, 4>> mSides;  ///< per primitive, faces 2…5
};

}  // namespace vtex::render::detail
