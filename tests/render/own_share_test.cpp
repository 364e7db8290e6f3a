// The share of a voxel's matter on the surface piece a lit point of it lies on (own_share.h),
// by hand on squares and a lattice of tiles, and what a shadow query does with it.
#include "fixtures.h"

#include "../../render/src/own_share.h"
#include "../../render/src/source_bvh.h"

#include <vtex/render/texel_march.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace vtex::render::test {
namespace {

using detail::measureOwnShares;
using detail::SourceBvh;

// An axis-aligned square in the plane z = `z` over [x0, x1] × [y0, y1], two triangles. `welded`:
// they share two corners' indices; otherwise each triangle has its own three corners (at the
// same positions: a mesh split for its normals).
void addSquare(ingest::TriangleMesh& mesh, double x0, double y0, double x1, double y1, double z, bool welded = true) {
    const auto corner = [&](double x, double y) {
        mesh.positions.emplace_back(float(x), float(y), float(z));
        mesh.normals.emplace_back(0.f, 0.f, 1.f);
        return std::uint32_t(mesh.positions.size() - 1);
    };
    if (welded) {
        const auto a = corner(x0, y0), b = corner(x1, y0), c = corner(x1, y1), d = corner(x0, y1);
        mesh.triangles.push_back({a, b, c});
        mesh.triangles.push_back({a, c, d});
    } else {
        const auto a = corner(x0, y0), b = corner(x1, y0), c = corner(x1, y1);
        mesh.triangles.push_back({a, b, c});
        const auto a2 = corner(x0, y0), c2 = corner(x1, y1), d = corner(x0, y1);
        mesh.triangles.push_back({a2, c2, d});
    }
}

std::vector<double> sharesOf(const ingest::TriangleMesh& mesh, int finest, bool cyclic = false) {
    octree::VolumeInfo info;
    info.levels = 6;
    info.cyclic = cyclic;
    const SourceBvh bvh(mesh, info);
    return measureOwnShares(bvh, finest);
}

// Golden values by hand: a square of area 0.04 across x = ½ and one of 0.01 beside it.
// Level 0: one voxel, (0.04² + 0.01²)/0.05 over 0.05 = 0.68. Level 1: voxel (0,0,0) holds half
// the large square (0.02) and the small one, (0.02² + 0.01²)/0.03; voxel (1,0,0) the other half
// alone, 0.02²/0.02; over 0.05: 0.7333. Level 2: every piece alone in its voxel: 1.
TEST(OwnShare, GoldenValuesOfTwoSquares) {
    for (const bool welded : {true, false}) {
        ingest::TriangleMesh mesh;
        addSquare(mesh, 0.4, 0.05, 0.6, 0.25, 0.2, welded);
        addSquare(mesh, 0.1, 0.1, 0.2, 0.2, 0.2, welded);
        const std::vector<double> s = sharesOf(mesh, 2);
        ASSERT_EQ(s.size(), 3u);
        EXPECT_NEAR(s[0], 0.68, 1e-6) << "welded " << welded;
        EXPECT_NEAR(s[1], (0.0005 / 0.03 + 0.02) / 0.05, 1e-6) << "welded " << welded;
        EXPECT_NEAR(s[2], 1.0, 1e-6) << "welded " << welded;
    }
    // Two squares that touch along an edge are one piece: level 0 gives 1.
    ingest::TriangleMesh joined;
    addSquare(joined, 0.1, 0.1, 0.3, 0.3, 0.2);
    addSquare(joined, 0.3, 0.1, 0.4, 0.2, 0.2);
    EXPECT_NEAR(sharesOf(joined, 0)[0], 1.0, 1e-12);
    EXPECT_EQ(sharesOf(ingest::TriangleMesh{}, 3), std::vector<double>(4, 0.0));
}

// A lattice of 8 × 8 equal separate tiles (area A), one in the middle of each level-3 column: a
// voxel of level L ≤ 3 holds 4^(3−L) of them, s_L = 4^(L−3); level 4 cuts each into four pieces
// alone in their voxels, 1. Shifted by half a column in x, in a cyclic volume, every tile is cut
// in half along x by a level-3 plane and the last one by x = 1, where it wraps: level 3 holds
// two halves a voxel, ½; level 2 per row one tile and two halves, (2A² + 4A²/4)/4A over 4A =
// 3/16; level 1 twelve tiles and eight halves, (12 + 8/4)/16² = 14/256; level 0 every tile
// whole, the wrapped one included, 1/64.
TEST(OwnShare, ALatticeOfEqualTilesSharesAsItsCount) {
    const std::vector<double> expected[2] = {{1.0 / 64, 1.0 / 16, 0.25, 1, 1}, {1.0 / 64, 14.0 / 256, 3.0 / 16, 0.5, 1}};
    for (const int shifted : {0, 1}) {
        ingest::TriangleMesh mesh;
        for (int i = 0; i < 8; ++i)
            for (int j = 0; j < 8; ++j) {
                const double x = (i + 0.5) / 8 + shifted / 16.0, y = (j + 0.5) / 8;
                addSquare(mesh, x - 0.03, y - 0.03, x + 0.03, y + 0.03, 0.3);
            }
        const std::vector<double> s = sharesOf(mesh, 4, true);
        ASSERT_EQ(s.size(), 5u);
        for (std::size_t level = 0; level < 5; ++level)
            EXPECT_NEAR(s[level], expected[shifted][level], 1e-6) << "level " << level << ", shifted " << shifted;
    }
}

// marchTransmittance's ownFactor scales the density of the voxel the segment starts in, up to
// where it leaves it, found here by bisection on the voxel index: on a uniform texel of
// extinction σ, T = exp(−σ (length − (1 − g) e)). The texel stored voxel by voxel and compressed
// into one node alike (a march visits runs of voxels that share a node: the stretch is its own).
TEST(OwnShare, AMarchTakesItsOwnVoxelTimesTheFactor) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0, 1);
    for (const bool compress : {false, true}) {
        const MarchVolume volume(makeOctree(3, [](int, int, int) { return sphereVoxel(3.0f); }, compress));
        for (int trial = 0; trial < 200; ++trial) {
            const Eigen::Vector3d p(unit(rng), unit(rng), 0.05 + 0.9 * unit(rng));
            const Eigen::Vector3d d = Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
            const int level = trial % 4;
            const double length = 0.3 * unit(rng), n = std::ldexp(1.0, level);
            const auto voxelAt = [&](double s) {
                const Eigen::Vector3d q = p + s * d;
                return Eigen::Vector3d(std::floor(q.x() * n), std::floor(q.y() * n), std::floor(q.z() * n));
            };
            double lo = 0, hi = 2;
            for (int i = 0; i < 80; ++i) (voxelAt(0.5 * (lo + hi)) == voxelAt(0) ? lo : hi) = 0.5 * (lo + hi);
            const double exit = std::min(lo, length);
            const double whole = marchTransmittance(volume, 1.0, p, p + length * d, level).transmittance;
            if (!(length > 0) || whole >= 1) continue;
            const double sigma = -std::log(whole) / length;
            for (const double g : {0.0, 0.3, 1.0}) {
                const double t = marchTransmittance(volume, 1.0, p, p + length * d, level, 0, g).transmittance;
                EXPECT_NEAR(t, std::exp(-sigma * (length - (1 - g) * exit)), 1e-9)
                    << "compress " << compress << ", level " << level << ", g " << g;
            }
        }
    }
}

}  // namespace
}  // namespace vtex::render::test
