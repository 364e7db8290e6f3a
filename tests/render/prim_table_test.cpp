// PrimTable (render/src/prim_table.h): the primitives the renderers trace are put together from
// the base meshes, once and kept when the table is small, on demand otherwise; what it gives must
// be what the scene describes, built directly, in all three of its forms (whole, the ray test's
// cell or patch alone, the map alone), and the same whether kept or not.
#include "fixtures.h"
#include "../../render/src/footprint.h"
#include "../../render/src/frame.h"

#include <gtest/gtest.h>

#include <random>

namespace vtex::render::test {
namespace {

// A twisted, sheared 3×3 grid: no two cells alike.
std::shared_ptr<ingest::QuadMesh> bumpyGrid() {
    auto mesh = gridMesh(0, 0, 3, 3, 0, 3);
    for (std::size_t v = 0; v < mesh->positions.size(); ++v) {
        mesh->positions[v].z() = 0.1f * float(v % 5);
        mesh->normals[v] = Eigen::Vector3f(0.05f * float(v % 3), -0.1f, 1.f).normalized();
    }
    return mesh;
}

// The surface scene: a textured grid under its faces, perturbed, and a plain face beside it.
Scene primScene() {
    Scene scene = baseScene(Eigen::Vector3d(2, -6, 4), Eigen::Vector3d(2, 2, 0));
    const std::size_t texel = addTexel(scene, makeOctree(2, [](int x, int y, int z) {
        return (x + y + z) % 2 == 0 ? std::optional(sphereVoxel(2)) : std::nullopt;
    }));
    addSurface(scene, bumpyGrid(), texel, 0.7, {2, 1});
    scene.surfaces.back().placement = Placement::Under;
    scene.surfaces.back().perturb = {7, true, true, false};
    addSurface(scene, gridMesh(3, 0, 4, 1, 0.2), std::nullopt);
    return scene;
}

void expectSame(const std::array<Vec3, 4>& a, const std::array<Vec3, 4>& b, const char* what, std::size_t i) {
    for (std::size_t c = 0; c < 4; ++c) EXPECT_EQ(a[c], b[c]) << what << " of primitive " << i << ", corner " << c;
}

TEST(PrimTable, PrimitivesAreTheFacesTheSceneDescribes) {
    const Scene scene = primScene();
    for (const bool floors : {false, true}) {
        const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene, floors);
        const detail::PrimTable& prims = geometry.tracer->prims();
        ASSERT_EQ(prims.size(), 10u);
        EXPECT_EQ(geometry.cells, 9u);
        for (std::size_t i = 0; i < prims.size(); ++i) {
            const detail::Prim prim = prims[i];
            EXPECT_EQ(prim.index, int(i));
            const bool cell = i < 9;
            const auto& mesh = *scene.surfaces[cell ? 0 : 1].meshData;
            EXPECT_EQ(prim.face, int(cell ? i : 0));
            EXPECT_EQ(prim.textured, cell && !floors);
            EXPECT_EQ(prims.textured(i), prim.textured);
            std::array<Vec3, 4> p, n;
            ASSERT_TRUE(ingest::patchCorners(mesh, std::size_t(prim.face), p, n));
            expectSame(prim.n, n, "normals", i);
            if (!cell) {
                expectSame(prim.p, p, "corners", i);
                expectSame(prims.patch(i), p, "patch", i);
                continue;
            }
            // The cell, built here from the face as buildSceneGeometry describes it.
            const TrilinearCell expected(p, n, 0.7, true);
            for (std::size_t c = 0; c < 8; ++c) {
                EXPECT_EQ(prim.cell.corners()[c], expected.corners()[c]) << i;
                EXPECT_EQ(prims.cell(i).corners()[c], expected.corners()[c]) << i;
            }
            const CellMap map = makeCellMap(scene.surfaces[0].placing(0), drawFaceTransform(scene.surfaces[0].perturb, i));
            EXPECT_EQ(prim.map.a, map.a);
            EXPECT_EQ(prim.map.b, map.b);
            EXPECT_EQ(prims.map(i).a, map.a);
            EXPECT_EQ(prims.map(i).b, map.b);
            // A floor is the patch of the cell's w = 0 face, which `under` puts one shell below.
            if (floors) {
                expectSame(prim.p, expected.faceCorners(0), "floor", i);
                expectSame(prims.patch(i), expected.faceCorners(0), "floor patch", i);
                EXPECT_NEAR((prim.p[0] - p[0]).norm(), 0.7, 1e-6);
            } else {
                expectSame(prim.p, p, "corners", i);
            }
        }
    }
}

// A table small enough to be kept (keepBuilt, as buildSceneGeometry's is) gives what the same
// table put together on demand gives, bit for bit, in every form.
TEST(PrimTable, KeptPrimitivesAreThoseBuiltOnDemand) {
    const Scene scene = primScene();
    for (const bool floors : {false, true}) {
        const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene, floors);
        const detail::PrimTable& kept = geometry.tracer->prims();
        detail::PrimTable onDemand = kept;
        onDemand.keepBuilt(0);
        for (std::size_t i = 0; i < kept.size(); ++i) {
            const detail::Prim a = kept[i], b = onDemand[i];
            EXPECT_EQ(a.index, b.index);
            EXPECT_EQ(a.surface, b.surface);
            EXPECT_EQ(a.face, b.face);
            EXPECT_EQ(a.textured, b.textured);
            expectSame(a.p, b.p, "corners", i);
            expectSame(a.n, b.n, "normals", i);
            if (!a.textured) expectSame(kept.patch(i), onDemand.patch(i), "patch", i);
            if (!a.textured && !floors) continue;
            for (std::size_t c = 0; c < 8; ++c) {
                EXPECT_EQ(a.cell.corners()[c], b.cell.corners()[c]) << i;
                EXPECT_EQ(kept.cell(i).corners()[c], onDemand.cell(i).corners()[c]) << i;
            }
            EXPECT_EQ(a.cell.size(), b.cell.size());
            EXPECT_EQ(kept.map(i).a, onDemand.map(i).a);
            EXPECT_EQ(kept.map(i).b, onDemand.map(i).b);
            EXPECT_EQ(a.map.a, b.map.a);
            EXPECT_EQ(a.map.b, b.map.b);
        }
        // A face added after keepBuilt is not missing from what is kept: the table drops it.
        detail::PrimTable grown = kept;
        grown.add(0, 0);
        ASSERT_EQ(grown.size(), kept.size() + 1);
        const detail::Prim added = grown[kept.size()];
        EXPECT_EQ(added.index, int(kept.size()));
        EXPECT_EQ(added.face, 0);
        for (std::size_t c = 0; c < 8; ++c) EXPECT_EQ(grown.cell(kept.size()).corners()[c], kept.cell(0).corners()[c]);
    }
}

// An affine cell's Prim keeps its localScale and the inverse of its tiled Jacobian, which every
// camera span and shadow query asks for: at points all over the cell they are what the cell and
// its map compute there, bit for bit (the Jacobian of an affine cell is the same everywhere); a
// trilinear cell keeps nothing and computes them where asked. The flat grid's cells are affine
// (flat, with the normals of the plane), the bumpy grid's are not.
TEST(PrimTable, AnAffineCellKeepsItsScaleAndJacobianInverse) {
    Scene scene = primScene();
    const std::size_t texel = 0;
    addSurface(scene, gridMesh(0, 4, 2, 6, 0.5, 2), texel, 0.9, {1, 1});
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    const detail::PrimTable& prims = geometry.tracer->prims();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    int affine = 0, trilinear = 0;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        const detail::Prim prim = prims[i];
        if (!prim.textured) continue;
        EXPECT_EQ(prim.affine, prim.cell.affine()) << i;
        (prim.affine ? affine : trilinear) += 1;
        for (int k = 0; k < 20; ++k) {
            const Vec3 r(u(rng), u(rng), u(rng));
            EXPECT_EQ(detail::localScale(prim, r), detail::localScale(prim.cell, r, prim.map)) << i;
            EXPECT_EQ(detail::tiledJacobianInverse(prim, r), Mat3(detail::tiledJacobian(prim, r).inverse())) << i;
        }
    }
    EXPECT_EQ(affine, 4);
    EXPECT_EQ(trilinear, 9);
}

// TrilinearCell::size and faceTwist are computed when asked (cells are rebuilt per ray): the
// largest corner distance and (p10 − p00) × (p01 − p11), as their definitions say.
TEST(PrimTable, CellSizeAndTwistFollowTheirDefinitions) {
    const Scene scene = primScene();
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    for (std::size_t i = 0; i < 9; ++i) {
        const TrilinearCell cell = geometry.tracer->prims().cell(i);
        double size = 0;
        for (const Vec3& a : cell.corners())
            for (const Vec3& b : cell.corners()) size = std::max(size, (a - b).norm());
        EXPECT_EQ(cell.size(), size);
        for (int face = 0; face < 6; ++face) {
            const auto c = cell.faceCorners(face);
            EXPECT_EQ(cell.faceTwist(face), Vec3((c[1] - c[0]).cross(c[2] - c[3]))) << face;
        }
    }
    EXPECT_EQ(TrilinearCell().size(), 0.0);
}

}  // namespace
}  // namespace vtex::render::test
