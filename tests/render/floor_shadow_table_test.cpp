// The floor shadow table (render/src/floor_shadow_table.h) against the line it stands for: exact
// at its points, close between them in a bush; which cells of a field take it; and on a bush
// field with an opaque plate above it, within the 0.5 % an approximation on by default may move
// the image mean, against every floor point casting its exact ray.
#include "bush_field.h"
#include "fixtures.h"
#include "../../render/src/cell_adjacency.h"
#include "../../render/src/floor_shadow_table.h"
#include "../../render/src/frame.h"

#include <vtex/render/compare.h>
#include <vtex/render/texel_march.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

const Eigen::Vector3d kLight = Eigen::Vector3d(1, 0.5, 1).normalized();  // toward the light, the field's

}  // namespace

// At its points the table is the line's march (to the float its optical depth is stored in);
// between them, bilinear in optical depth (exact where the line's chords through the voxels are
// linear in its start, which is everywhere but across the start points whose line grazes a voxel's
// edge), close: random floor points of a 2000-leaf bush at 64³, the shadow levels 3–6. Measured:
// mean table / line 0.9948 at level 3, 0.9985–0.9988 at 4–6 (the geometric mean across those
// kinks darkens), mean |difference| 0.0019–0.0047, the largest 0.11–0.17 (beside a leaf's edge).
// Bound: means within 1 %, mean |difference| 0.01.
TEST(FloorShadowTable, IsTheLineAtItsPointsAndCloseBetween) {
    const MarchVolume volume(makeBush(2000, 64).tree);
    detail::FloorShadowTable table(1);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0, 1);
    for (int level = 3; level <= 6; ++level) {
        const double n = detail::FloorShadowTable::side(level);
        double worstAtPoints = 0;
        for (int q = 0; q < 500; ++q) {
            const double x = std::floor(u(rng) * n) / n, y = std::floor(u(rng) * n) / n;
            const double line = detail::FloorShadowTable::lineTransmittance(volume, 1.0, level, kLight, Eigen::Vector3d(x, y, 0));
            const double fromTable = table.transmittance(0, volume, 1.0, level, kLight, x + 3, y - 2);  // tiles repeat
            if (line > 1e-3) worstAtPoints = std::max(worstAtPoints, std::abs(fromTable / line - 1));
        }
        EXPECT_LT(worstAtPoints, 1e-5) << "level " << level;
        double sumLine = 0, sumTable = 0, sumDiff = 0, worst = 0;
        constexpr int kQueries = 20000;
        for (int q = 0; q < kQueries; ++q) {
            const double x = u(rng), y = u(rng);
            const double line = detail::FloorShadowTable::lineTransmittance(volume, 1.0, level, kLight, Eigen::Vector3d(x, y, 0));
            const double fromTable = table.transmittance(0, volume, 1.0, level, kLight, x, y);
            sumLine += line;
            sumTable += fromTable;
            sumDiff += std::abs(fromTable - line);
            worst = std::max(worst, std::abs(fromTable - line));
        }
        std::cout << "level " << level << ": mean table / line " << sumTable / sumLine << ", mean |difference| "
                  << sumDiff / kQueries << ", largest " << worst << "\n";
        EXPECT_NEAR(sumTable / sumLine, 1.0, 0.01) << "level " << level;
        EXPECT_LT(sumDiff / kQueries, 0.01) << "level " << level;
    }
}

// The volume table (FloorShadowTable::inside) against the march it stands for, from the query
// point to the top: random points in the non-empty voxels of a 2000-leaf bush at 64³, at the
// shadow levels 4 and 5 (the bush field's). Its own voxel is exact and the rest trilinear in the
// depth at 2 points a voxel. Measured: mean table / march 0.9976 (4) and 0.9965 (5), mean
// |difference| 0.0106 and 0.0129 (the near table's, which it replaces in a field alone, 0.011).
// Bound: means within 1 %, mean |difference| 0.02.
TEST(FloorShadowTable, InsideIsCloseToTheMarchToTheTop) {
    const MarchVolume volume(makeBush(2000, 64).tree);
    detail::FloorShadowTable table(1);
    for (const int level : {4, 5}) {
        const LevelGrid& grid = *volume.grid(level);
        const TableAgreement a = agreementInVoxels(
            grid, 12, 20000, [&](const Eigen::Vector3d& p0) { return table.inside(0, volume, grid, 1.0, level, kLight, kLight.cwiseInverse(), p0); },
            [&](const Eigen::Vector3d& p0) {
                return marchTransmittance(volume, 1.0, p0, p0 + ((1 - p0.z()) / kLight.z()) * kLight, level, 1e-6)
                    .transmittance;
            });
        std::cout << "level " << level << ": mean table / march " << a.ratio << ", mean |difference| " << a.meanDifference
                  << "\n";
        EXPECT_NEAR(a.ratio, 1.0, 0.01) << "level " << level;
        EXPECT_LT(a.meanDifference, 0.02) << "level " << level;
    }
}

namespace {

// Which cells of `scene` (one light, toward kLight) take the floor table.
std::vector<bool> floorCells(const Scene& scene) {
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    const auto& prims = geometry.tracer->prims();
    const detail::CellAdjacency adjacency(prims);
    detail::NearShadowTable near;
    std::vector<int> slots(prims.size(), -1);
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (!prims.textured(i)) continue;
        const Vec3 lr = (detail::tiledJacobian(prims[i], Vec3::Constant(0.5)).inverse() * kLight).normalized();
        slots[i] = near.slotFor(0, 0, lr);
    }
    return detail::floorTableCells(prims, adjacency, geometry.surfaces, slots, 1, near);
}

bool oneField(const Scene& scene) {
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    return detail::oneSurfaceOnly(geometry.tracer->prims());
}

Scene fieldScene(int n) {
    Scene scene = baseScene(Eigen::Vector3d(2, -6, 4), Eigen::Vector3d(2, 2, 0));
    scene.lights[0].direction = -kLight;
    addSurface(scene, gridMesh(0, 0, n, n, 0, n), addTexel(scene, makeOctree(2, [](int, int, int) { return std::optional(sphereVoxel(1)); })), 1.0);
    return scene;
}

}  // namespace

// On an n × n field of unit cells one high, the line from a floor point reaches up to one cell
// along x and half a cell along y before the top (light along (1, 0.5, 1)): the cells whose
// neighbours at +x, +y and +x+y are in the field take the table, the last row and column walk
// their rays. An opaque quad standing in the field's bounds, or a field whose cells are not all
// translates of one another, takes it nowhere; a plate above the shells leaves it (the line's
// walk goes on from the top).
TEST(FloorShadowTable, TakesTheCellsWhoseLineStaysInARegularField) {
    constexpr int n = 6;
    const std::vector<bool> cells = floorCells(fieldScene(n));
    ASSERT_EQ(cells.size(), std::size_t(n * n));
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) EXPECT_EQ(cells[std::size_t(j * n + i)], i < n - 1 && j < n - 1) << i << ", " << j;

    EXPECT_TRUE(oneField(fieldScene(n)));
    Scene standing = fieldScene(n);
    addSurface(standing, gridMesh(2.2, 2.2, 2.6, 2.6, 0.5), std::nullopt);
    for (const bool c : floorCells(standing)) EXPECT_FALSE(c);

    Scene above = fieldScene(n);
    addSurface(above, gridMesh(1, 1, 4, 4, 2.5), std::nullopt);
    EXPECT_FALSE(oneField(above));  // the volume table's condition: a query at the top has reached the light
    const std::vector<bool> withPlate = floorCells(above);
    for (int k = 0; k < n * n; ++k) EXPECT_EQ(withPlate[std::size_t(k)], cells[std::size_t(k)]) << k;

    Scene uneven = fieldScene(n);
    auto mesh = gridMesh(0, 0, n, n, 0, n);
    mesh->positions[std::size_t(3 * (n + 1) + 3)].x() += 0.25f;  // one inner vertex moved
    uneven.surfaces[0].meshData = mesh;
    for (const bool c : floorCells(uneven)) EXPECT_FALSE(c);
}

namespace {

// A 9×9 field of 400-leaf bushes at 64³ (the benchmark's light and materials) seen from above;
// with `plate`, an opaque plate high over the field, out of the camera's view, whose shadow falls
// on the floor in view.
Scene bushFieldFromAbove(bool plate) {
    static const auto bush = makeBush(400, 64).tree;
    Scene scene = baseScene(Eigen::Vector3d(0.5, 0.5, 9), Eigen::Vector3d(0.5, 0.5, 0), 30, 96);
    scene.camera.up = Eigen::Vector3d(0, 1, 0);
    scene.lights[0].direction = -kLight;
    const auto texel = addTexel(scene, bush);
    scene.texels[texel].material.specular = Color::Zero();
    addSurface(scene, gridMesh(-4, -4, 5, 5, 0, 9), texel, 1.0);
    scene.surfaces.back().material.diffuse = Color(0.35, 0.28, 0.2);
    if (plate) addSurface(scene, gridMesh(2.5, 1.5, 5, 4, 6), std::nullopt);
    return scene;
}

}  // namespace

// Whole renders: a 9×9 field of 400-leaf bushes at 64³ (the benchmark's light and materials) seen
// from above, with an opaque plate high over the field, out of the camera's view, whose shadow
// falls on the floor in view: the floor's lines reach the plate only through the walk that goes
// on from the shell's top. The table against every floor point casting its exact ray. Measured:
// the plate's shadow takes 11.6 % off the image mean (G); the table moves it by −0.03 / −0.03 /
// −0.03 %, RMSE 0.0010 against an image mean of 0.10; the walks' blocks 0.31 M against 0.54 M.
// Bound: every channel's mean within 0.5 %, RMSE below 5 % of the image mean, fewer blocks marched.
TEST(FloorShadowTable, MovesABushFieldsMeanByAtMostHalfAPercent) {
    const auto field = [](bool plate) { return bushFieldFromAbove(plate); };
    RenderOptions options;
    const RenderResult withTable = renderQuiet(field(true), options);
    const RenderResult unshadowed = renderQuiet(field(false), options);
    options.approximations.floorShadowTable = false;
    const RenderResult walked = renderQuiet(field(true), options);
    const ImageComparison plate = compareImages(walked.image, unshadowed.image);
    const ImageComparison c = compareImages(withTable.image, walked.image);
    const double mean = (c.meanB[0] + c.meanB[1] + c.meanB[2]) / 3;
    std::cout << "the plate's shadow: " << 100 * plate.bias[1] << " % (G); floor table against exact rays: bias "
              << 100 * c.bias[0] << " / " << 100 * c.bias[1] << " / " << 100 * c.bias[2] << " %, RMSE " << c.rmse
              << " (image mean " << mean << "); blocks " << withTable.stats.voxelsVisited << " vs "
              << walked.stats.voxelsVisited << "\n";
    EXPECT_LT(plate.bias[1], -0.03);  // the plate's shadow is in view
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(c.bias[std::size_t(k)]), 0.005) << "channel " << k;
    EXPECT_LT(c.rmse, 0.05 * mean);
    EXPECT_LT(double(withTable.stats.voxelsVisited), 0.8 * double(walked.stats.voxelsVisited));
}

// The volume table on the same field without the plate (a scene of one field, where it applies):
// against the near table and the lattice, the floor table on in both. Measured: bias +0.011 /
// +0.035 / +0.007 %, RMSE 0.0005 against an image mean of 0.12. Bound: every channel's mean within
// 0.5 %, RMSE below 5 % of the image mean; and the images differ (the table took the queries:
// neither path's work shows in the blocks counted, the near table's and the lattice's being
// shared by all pixels).
TEST(FloorShadowTable, TheVolumeTableMovesAFieldsMeanByAtMostHalfAPercent) {
    const Scene scene = bushFieldFromAbove(false);
    RenderOptions options;
    const RenderResult withTable = renderQuiet(scene, options);
    options.approximations.fieldShadowVolume = false;
    const RenderResult nearAndLattice = renderQuiet(scene, options);
    const ImageComparison c = compareImages(withTable.image, nearAndLattice.image);
    const double mean = (c.meanB[0] + c.meanB[1] + c.meanB[2]) / 3;
    std::cout << "volume table against near table and lattice: bias " << 100 * c.bias[0] << " / " << 100 * c.bias[1]
              << " / " << 100 * c.bias[2] << " %, RMSE " << c.rmse << " (image mean " << mean << ")\n";
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(c.bias[std::size_t(k)]), 0.005) << "channel " << k;
    EXPECT_LT(c.rmse, 0.05 * mean);
    EXPECT_GT(c.rmse, 0.0);
}
