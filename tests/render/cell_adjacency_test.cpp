// CellAdjacency (render/src/cell_adjacency.h): the cell across each side face, and the map of the
// shared face's parameters, which the chained transmittance lattice follows from cell to cell.
#include "fixtures.h"
#include "../../render/src/cell_adjacency.h"
#include "../../render/src/frame.h"

#include <gtest/gtest.h>

#include <random>

namespace vtex::render::test {
namespace {

// A 4×4 grid whose quads start at a different corner and wind either way, so that the shared
// faces' parameters run in every combination of directions between neighbours.
std::shared_ptr<ingest::QuadMesh> scrambledGrid(unsigned seed) {
    auto mesh = gridMesh(0, 0, 4, 4, 0, 4);
    std::mt19937 rng(seed);
    for (auto& q : mesh->quads) {
        std::rotate(q.begin(), q.begin() + int(rng() % 4), q.end());
        if (rng() % 2) std::swap(q[1], q[3]);  // the other winding, same corners
    }
    for (auto& n : mesh->normals) n = Eigen::Vector3f(0.1f, -0.2f, 1.f).normalized();  // sheared cells
    return mesh;
}

TEST(CellAdjacency, NeighboursShareTheirSideFacesPointForPoint) {
    Scene scene = baseScene(Eigen::Vector3d(2, -6, 4), Eigen::Vector3d(2, 2, 0));
    addSurface(scene, scrambledGrid(7), addTexel(scene, makeOctree(3, [](int x, int y, int z) { return (x + y + z) % 3 == 0 ? std::optional(sphereVoxel(2)) : std::nullopt; })), 0.7);
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    const auto& prims = geometry.tracer->prims();
    ASSERT_EQ(prims.size(), 16u);
    const detail::CellAdjacency adjacency(prims);
    int shared = 0, border = 0;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> uniform(0, 1);
    for (std::size_t p = 0; p < prims.size(); ++p)
        for (int face = 2; face < 6; ++face) {
            const detail::CellNeighbour& n = adjacency.across(int(p), face);
            if (n.prim < 0) {
                ++border;
                continue;
            }
            ++shared;
            // Symmetric: the neighbour's neighbour across the same face is this cell.
            EXPECT_EQ(adjacency.across(n.prim, n.face).prim, int(p));
            for (int k = 0; k < 8; ++k) {
                const Vec3 r = TrilinearCell::faceToCell(face, uniform(rng), uniform(rng));
                const Vec3 rn = detail::CellAdjacency::toNeighbour(n, face, r);
                const Vec3 x = prims[p].cell.map(r), xn = prims[std::size_t(n.prim)].cell.map(rn);
                EXPECT_LT((x - xn).norm(), 1e-12) << "cell " << p << " face " << face;
                // And back.
                EXPECT_LT((detail::CellAdjacency::toNeighbour(adjacency.across(n.prim, n.face), n.face, rn) - r).norm(), 1e-12);
            }
        }
    EXPECT_EQ(shared, 2 * 24);  // a 4×4 grid has 24 inner edges, each seen from both sides
    EXPECT_EQ(border, 16);
}

TEST(CellAdjacency, CellsWithoutACommonFaceAreNotNeighbours) {
    Scene scene = baseScene(Eigen::Vector3d(2, -6, 4), Eigen::Vector3d(2, 2, 0));
    const auto texel = addTexel(scene, makeOctree(3, [](int x, int y, int z) { return (x + y + z) % 3 == 0 ? std::optional(sphereVoxel(2)) : std::nullopt; }));
    // Two quads side by side whose shells differ in height: their side faces share the base
    // edge only. And a plain face, which has no cell.
    addSurface(scene, gridMesh(0, 0, 1, 1, 0), texel, 0.5);
    addSurface(scene, gridMesh(1, 0, 2, 1, 0), texel, 0.6);
    addSurface(scene, gridMesh(2, 0, 3, 1, 0), std::nullopt);
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    const detail::CellAdjacency adjacency(geometry.tracer->prims());
    for (std::size_t p = 0; p < geometry.tracer->prims().size(); ++p)
        for (int face = 2; face < 6; ++face) EXPECT_EQ(adjacency.across(int(p), face).prim, -1);
}

}  // namespace
}  // namespace vtex::render::test
