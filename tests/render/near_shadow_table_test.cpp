// The near shadow table (render/src/near_shadow_table.h) against the march it stands for: exact
// where its entries were measured, close on average over random queries in a bush, and on a bush
// field's image within the 0.5 % an approximation on by default may move the mean.
#include "bush_field.h"
#include "fixtures.h"
#include "../../render/src/near_shadow_table.h"

#include <vtex/render/compare.h>
#include <vtex/render/texel_march.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

using namespace vtex::render;
using namespace vtex::render::test;

namespace {

const Eigen::Vector3d kLight = Eigen::Vector3d(1, 0.5, 1).normalized();  // toward the light
constexpr double kStretch = 0.5;  // four steps of the default lattice of 8 per tile

// The exact march a query stands for: p0 toward the light for kStretch or up to the tile's
// sides, top or floor (the tile being [0, 1]² in x and y around p0's).
double marchFrom(const MarchVolume& volume, int level, const Eigen::Vector3d& p0, double& step) {
    step = kStretch;
    for (int a = 0; a < 3; ++a) {
        const double lo = a < 2 ? std::floor(p0[a]) : 0.0;
        step = std::min(step, ((kLight[a] > 0 ? lo + 1 : lo) - p0[a]) / kLight[a]);
    }
    return marchTransmittance(volume, 1.0, p0, p0 + step * kLight, level, 1e-6).transmittance;
}

}  // namespace

// Where its entries were measured the table is the march: a query whose path leaves its voxel
// exactly at one of the points of a face the entry marched from, and whose stretch the tile's
// sides or top end (as they end the entry's), gets the voxel's share exactly and the entry's
// march, so the two agree to the float precision the entries are stored in. (Where the stretch's length ends it instead, the
// query's is shorter than the entry's by its share in its own voxel, taken off at the extinction
// where the face's middle march ends: measured below.)
TEST(NearShadowTable, IsTheMarchWhereItsEntriesWereMeasured) {
    const MarchVolume volume(makeBush(400, 32).tree);
    detail::NearShadowTable table;
    const int slot = table.slotFor(0, 0, kLight);
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> voxel(0, 15);
    std::uniform_real_distribution<double> back(0.01, 0.3);
    const int level = 4;
    const LevelGrid& grid = *volume.grid(level);
    int compared = 0;
    double worst = 0;
    for (int q = 0; q < 2000; ++q) {
        const int face = q % 3, u = (face + 1) % 3, v = (face + 2) % 3;
        Eigen::Vector3d exit(voxel(rng) + 0.5, voxel(rng) + 0.5, voxel(rng) + 0.5);
        exit[face] += 0.5;  // the face toward the light
        // One of the points the entry marched from: the middles of a kSide × kSide division.
        constexpr int side = detail::NearShadowTable::kSide;
        exit[u] += ((q / 4) % side + 0.5) / side - 0.5;
        exit[v] += ((q / 16) % side + 0.5) / side - 0.5;
        exit /= 16.0;
        if (exit.z() >= 1) continue;
        // Back from the march point into the voxel, not so far that it leaves by another face.
        Eigen::Vector3d p0 = exit - back(rng) / 16.0 * kLight;
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside &= std::floor(p0[a] * 16) == std::floor((exit[a] - 1e-9 * kLight[a]) * 16);
        if (!inside || p0.z() < 0) continue;
        double step;
        const double march = marchFrom(volume, level, p0, step);
        if (!(step < kStretch)) continue;
        const double fromTable = table.transmittance(slot, volume, grid, 1.0, level, p0, step, kStretch);
        worst = std::max(worst, std::abs(fromTable - march));
        ++compared;
    }
    std::cout << compared << " queries at march points: largest difference " << worst << "\n";
    EXPECT_GT(compared, 300);
    EXPECT_LT(worst, 1e-5);
}

// Anywhere else the rest of the stretch is interpolated across the face it leaves by. Random
// queries in the voxels of a 2000-leaf bush at 64³ (the bush field's texel, smaller), at the
// shadow levels the field uses (4, 5): measured mean transmittance table / march 1.0004 (4) and
// 1.0009 (5), mean |difference| 0.011 (with 2×2 points a face: 0.995 and 0.021, the midpoint
// rule's bias on a convex function). Bound: means within 0.5 %, mean difference 0.02.
TEST(NearShadowTable, IsCloseToTheMarchOnAverageInABush) {
    const MarchVolume volume(makeBush(2000, 64).tree);
    detail::NearShadowTable table;
    const int slot = table.slotFor(0, 0, kLight);
    for (const int level : {4, 5}) {
        const LevelGrid& grid = *volume.grid(level);
        double step = 0;  // the march's stretch, which the table's query takes (march comes first)
        const TableAgreement a = agreementInVoxels(
            grid, 8, 20000,
            [&](const Eigen::Vector3d& p0) { return table.transmittance(slot, volume, grid, 1.0, level, p0, step, kStretch); },
            [&](const Eigen::Vector3d& p0) { return marchFrom(volume, level, p0, step); });
        std::cout << "level " << level << ": mean table / march " << a.ratio << ", mean |difference| " << a.meanDifference
                  << "\n";
        EXPECT_NEAR(a.ratio, 1.0, 0.005) << "level " << level;
        EXPECT_LT(a.meanDifference, 0.02) << "level " << level;
    }
}

// Whole renders: the bush field of the approximation test (3×3 cells of 400-leaf bushes at 64³,
// the benchmark's light and camera direction), with the table against every query marching its
// stretch. Measured: bias −0.001 / −0.004 / −0.002 %, RMSE 0.0001 against an image mean of 0.021
// (the benchmark's 256³ field: within 0.02 % at far and mid). Bound: every channel's mean within
// 0.5 %, RMSE below 5 % of the image mean; and the table does take the queries' work (blocks
// 109 k against 162 k, the floor shadow table on in both).
TEST(NearShadowTable, MovesABushFieldsMeanByAtMostHalfAPercent) {
    Scene scene = baseScene(Eigen::Vector3d(2.2, -5.5, 4.0), Eigen::Vector3d(0.5, 0.5, 0.4), 40, 96);
    scene.lights[0].direction = -kLight;
    const auto texel = addTexel(scene, makeBush(400, 64).tree);
    scene.texels[texel].material.specular = Color::Zero();
    addSurface(scene, gridMesh(-1, -1, 2, 2, 0, 3), texel, 1.0);
    scene.surfaces.back().material.diffuse = Color(0.35, 0.28, 0.2);
    RenderOptions options;
    // The field is the scene's only surface: its inner cells would take the volume table instead.
    options.approximations.fieldShadowVolume = false;
    const RenderResult withTable = renderQuiet(scene, options);
    options.approximations.nearShadowTable = false;
    const RenderResult marched = renderQuiet(scene, options);
    const ImageComparison c = compareImages(withTable.image, marched.image);
    const double mean = (c.meanB[0] + c.meanB[1] + c.meanB[2]) / 3;
    std::cout << "near table against marches: bias " << 100 * c.bias[0] << " / " << 100 * c.bias[1] << " / "
              << 100 * c.bias[2] << " %, RMSE " << c.rmse << " (image mean " << mean << "); blocks "
              << withTable.stats.voxelsVisited << " vs " << marched.stats.voxelsVisited << "\n";
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(c.bias[std::size_t(k)]), 0.005) << "channel " << k;
    EXPECT_LT(c.rmse, 0.05 * mean);
    EXPECT_LT(double(withTable.stats.voxelsVisited), 0.8 * double(marched.stats.voxelsVisited));
}
