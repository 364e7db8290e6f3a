// Ray–bilinear-patch intersection, cell spans and the inverse trilinear map.
#include <vtex/render/geometry.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <random>

using namespace vtex::render;

namespace {

Vec3 bilerp(const Vec3& p00, const Vec3& p10, const Vec3& p01, const Vec3& p11, double u, double v) {
    return (1 - u) * (1 - v) * p00 + u * (1 - v) * p10 + (1 - u) * v * p01 + u * v * p11;
}

Vec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<double> n;
    Vec3 v(n(rng), n(rng), n(rng));
    return v.normalized();
}

// A random cell over the unit square with corner jitter `jitter`, normals tilted by up to
// `tilt` and height h; `twist` rotates the top corners about the vertical axis (radians).
TrilinearCell randomCell(std::mt19937& rng, double jitter, double tilt, double h, double twist = 0) {
    std::uniform_real_distribution<double> u(-1, 1);
    std::array<Vec3, 4> p = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
    std::array<Vec3, 4> n;
    for (int i = 0; i < 4; ++i) {
        p[std::size_t(i)] += jitter * Vec3(u(rng), u(rng), u(rng));
        const Vec3 c = p[std::size_t(i)] - Vec3(0.5, 0.5, 0);
        const Vec3 twisted(c.x() * std::cos(twist) - c.y() * std::sin(twist), c.x() * std::sin(twist) + c.y() * std::cos(twist), 0);
        n[std::size_t(i)] = (twisted - Vec3(c.x(), c.y(), 0)) / h + Vec3(tilt * u(rng), tilt * u(rng), 1);
    }
    return TrilinearCell(p, n, h, false);
}

// An independent oracle for the patch test: pbrt-v4's IntersectBilinearPatch set-up (the quadratic
// from the corners, v and t from two 3×3 determinants), in double precision, returning both roots.
int pbrtPatchHits(const Vec3& o, const Vec3& d, const Vec3& p00, const Vec3& p10, const Vec3& p01,
                  const Vec3& p11, std::array<PatchHit, 2>& hits) {
    const double a = (p10 - p00).cross(p01 - p11).dot(d);
    const double c = (p00 - o).cross(d).dot(p01 - p00);
    const double b = (p10 - o).cross(d).dot(p11 - p10) - (a + c);
    std::vector<double> us;
    if (a == 0) {
        if (b != 0) us.push_back(-c / b);
    } else {
        const double disc = b * b - 4 * a * c;
        if (disc >= 0) {
            us.push_back((-b - std::sqrt(disc)) / (2 * a));
            us.push_back((-b + std::sqrt(disc)) / (2 * a));
        }
    }
    int count = 0;
    for (const double u : us) {
        if (u < 0 || u > 1) continue;
        const Vec3 uo = p00 + u * (p10 - p00);
        const Vec3 ud = p01 + u * (p11 - p01) - uo;
        const Vec3 deltao = uo - o;
        const Vec3 perp = d.cross(ud);
        const double p2 = perp.squaredNorm();
        const double v = deltao.dot(d.cross(perp)) / p2;
        const double t = deltao.dot(ud.cross(perp)) / p2;
        if (v < 0 || v > 1 || t <= 0) continue;
        hits[std::size_t(count++)] = PatchHit{t, u, v};
    }
    if (count == 2 && hits[1].t < hits[0].t) std::swap(hits[0], hits[1]);
    return count;
}

}  // namespace

TEST(BilinearPatch, PlanarSquareHitsWhereExpected) {
    const Vec3 p00(0, 0, 0), p10(2, 0, 0), p01(0, 2, 0), p11(2, 2, 0);
    const auto hit = intersectBilinearPatch(Vec3(0.5, 1.5, 3), Vec3(0, 0, -1), p00, p10, p01, p11, 0, 1e30);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->t, 3, 1e-12);
    EXPECT_NEAR(hit->u, 0.25, 1e-12);
    EXPECT_NEAR(hit->v, 0.75, 1e-12);
    EXPECT_FALSE(intersectBilinearPatch(Vec3(2.5, 1, 3), Vec3(0, 0, -1), p00, p10, p01, p11, 0, 1e30));
    EXPECT_FALSE(intersectBilinearPatch(Vec3(0.5, 1.5, 3), Vec3(0, 0, -1), p00, p10, p01, p11, 0, 2.5));
}

// Seeded property loop: rays aimed at a random point of a random (twisted) patch hit it there
// or nearer, and every reported hit lies on both the ray and the patch.
TEST(BilinearPatch, RandomPatchesReintersect) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u01(0, 1), u(-1, 1);
    int missed = 0;
    for (int k = 0; k < 2000; ++k) {
        const Vec3 p00(u(rng), u(rng), u(rng)), p10 = Vec3(2, 0, 0) + Vec3(u(rng), u(rng), u(rng)),
                   p01 = Vec3(0, 2, 0) + Vec3(u(rng), u(rng), u(rng)), p11 = Vec3(2, 2, 0) + Vec3(u(rng), u(rng), u(rng));
        const double a = u01(rng), b = u01(rng);
        const Vec3 target = bilerp(p00, p10, p01, p11, a, b);
        const Vec3 o = target + 5 * randomUnit(rng);
        const Vec3 d = (target - o).normalized();
        std::array<PatchHit, 2> hits;
        const int n = intersectBilinearPatchAll(o, d, p00, p10, p01, p11, 0, 1e30, hits);
        bool found = false;
        for (int i = 0; i < n; ++i) {
            const Vec3 onRay = o + hits[std::size_t(i)].t * d;
            const Vec3 onPatch = bilerp(p00, p10, p01, p11, hits[std::size_t(i)].u, hits[std::size_t(i)].v);
            EXPECT_LT((onRay - onPatch).norm(), 1e-9);
            found = found || std::abs(hits[std::size_t(i)].t - 5) < 1e-9;
        }
        missed += !found;
    }
    EXPECT_EQ(missed, 0);
}

// The patch test against the pbrt-v4 oracle on random twisted patches (corners jittered by ±1
// out of a 2×2 square), away from the world origin and near it, with rays aimed at points inside
// and outside the patch: the same hits, to 1e-9 relative in t and 1e-9 in (u, v).
TEST(BilinearPatch, AgreesWithPbrtOracleOnTwistedPatches) {
    std::mt19937 rng(19);
    std::uniform_real_distribution<double> u(-1, 1), aim(-0.3, 1.3);
    int hitsSeen = 0;
    for (int k = 0; k < 4000; ++k) {
        const Vec3 shift = k % 2 ? Vec3(300, -200, 50) : Vec3::Zero();
        const Vec3 p00 = shift + Vec3(u(rng), u(rng), u(rng)),
                   p10 = shift + Vec3(2, 0, 0) + Vec3(u(rng), u(rng), u(rng)),
                   p01 = shift + Vec3(0, 2, 0) + Vec3(u(rng), u(rng), u(rng)),
                   p11 = shift + Vec3(2, 2, 0) + Vec3(u(rng), u(rng), u(rng));
        const Vec3 target = bilerp(p00, p10, p01, p11, aim(rng), aim(rng));
        const Vec3 o = target + 5 * randomUnit(rng);
        const Vec3 d = (target - o).normalized();
        std::array<PatchHit, 2> hits, expected;
        const int n = intersectBilinearPatchAll(o, d, p00, p10, p01, p11, 0, 1e30, hits);
        const int m = pbrtPatchHits(o, d, p00, p10, p01, p11, expected);
        ASSERT_EQ(n, m) << k;
        for (std::size_t i = 0; i < std::size_t(n); ++i) {
            EXPECT_NEAR(hits[i].t, expected[i].t, 1e-9 * expected[i].t) << k;
            EXPECT_NEAR(hits[i].u, expected[i].u, 1e-9) << k;
            EXPECT_NEAR(hits[i].v, expected[i].v, 1e-9) << k;
        }
        hitsSeen += n;
    }
    // Both outcomes are exercised: about half the rays are aimed off the patch.
    EXPECT_GT(hitsSeen, 1500);
    EXPECT_LT(hitsSeen, 3500);
}

TEST(BilinearPatch, CollapsedEdgeIsATriangle) {
    // p01 == p11: the triangle (0,0) (1,0) (apex at (0.5,1)).
    const Vec3 p00(0, 0, 0), p10(1, 0, 0), apex(0.5, 1, 0);
    EXPECT_TRUE(intersectBilinearPatch(Vec3(0.5, 0.5, 1), Vec3(0, 0, -1), p00, p10, apex, apex, 0, 1e30));
    EXPECT_FALSE(intersectBilinearPatch(Vec3(0.1, 0.9, 1), Vec3(0, 0, -1), p00, p10, apex, apex, 0, 1e30));
}

TEST(Cell, SpansThroughAUnitCube) {
    const std::array<Vec3, 4> p = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
    const std::array<Vec3, 4> n = {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)};
    const TrilinearCell cell(p, n, 1, false);
    std::array<CellSpan, 4> spans;
    // Along x at height 0.5: enters u=0 at t=1, leaves u=1 at t=2.
    ASSERT_EQ(cellSpans(cell, Vec3(-1, 0.3, 0.5), Vec3(1, 0, 0), spans), 1);
    EXPECT_NEAR(spans[0].tIn, 1, 1e-12);
    EXPECT_NEAR(spans[0].tOut, 2, 1e-12);
    EXPECT_EQ(spans[0].faceIn, 2);
    EXPECT_EQ(spans[0].faceOut, 3);
    EXPECT_NEAR((spans[0].rIn - Vec3(0, 0.3, 0.5)).norm(), 0, 1e-12);
    // From inside, straight down: one span from 0, leaving through the bottom.
    ASSERT_EQ(cellSpans(cell, Vec3(0.5, 0.5, 0.5), Vec3(0, 0, -1), spans), 1);
    EXPECT_EQ(spans[0].faceIn, -1);
    EXPECT_EQ(spans[0].faceOut, 0);
    EXPECT_NEAR(spans[0].tOut, 0.5, 1e-12);
    // Through an edge (two faces at the same t) still gives one span.
    ASSERT_EQ(cellSpans(cell, Vec3(-1, -1, 0.5), Vec3(1, 1, 0).normalized(), spans), 1);
    EXPECT_NEAR(spans[0].tIn, std::sqrt(2.0), 1e-9);
    // Placement under: the cell is [0,1]² × [−1, 0].
    const TrilinearCell under(p, n, 1, true);
    ASSERT_EQ(cellSpans(under, Vec3(0.5, 0.5, 5), Vec3(0, 0, -1), spans), 1);
    EXPECT_NEAR(spans[0].tIn, 5, 1e-12);
    EXPECT_EQ(spans[0].faceIn, 1);
    EXPECT_NEAR(spans[0].tOut, 6, 1e-12);
}

// A ray through a convex-ish random cell: the span's ends map back to their world points.
TEST(Cell, RandomCellSpansAreConsistent) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u01(0, 1);
    for (int k = 0; k < 500; ++k) {
        const TrilinearCell cell = randomCell(rng, 0.15, 0.3, 0.5);
        const Vec3 target = cell.map(Vec3(u01(rng), u01(rng), u01(rng)));
        const Vec3 o = target + 4 * randomUnit(rng);
        const Vec3 d = (target - o).normalized();
        std::array<CellSpan, 4> spans;
        const int n = cellSpans(cell, o, d, spans);
        ASSERT_GE(n, 1) << k;
        bool contains = false;
        for (int i = 0; i < n; ++i) {
            const CellSpan& s = spans[std::size_t(i)];
            EXPECT_LE(s.tIn, s.tOut);
            EXPECT_LT((cell.map(s.rIn) - (o + s.tIn * d)).norm(), 1e-9);
            EXPECT_LT((cell.map(s.rOut) - (o + s.tOut * d)).norm(), 1e-9);
            contains = contains || (s.tIn <= 4 + 1e-9 && s.tOut >= 4 - 1e-9);
        }
        EXPECT_TRUE(contains) << k;
    }
}

// cellSpans shares work between the six faces of a cell; on random twisted cells and rays aimed
// in and around them, it must agree with the plain patch test on each face: every span end is a
// hit of that face's patch at that t and those cell coordinates, a ray from outside that meets
// some face has a span, and one that meets none has none.
TEST(Cell, SpansAgreeWithThePatchTestOfEachFace) {
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> aim(-0.4, 1.4);
    int withSpans = 0, without = 0;
    for (int k = 0; k < 2000; ++k) {
        const TrilinearCell cell = randomCell(rng, 0.2, 0.4, 0.7, k % 3 ? 0.8 : 0.0);
        const Vec3 target = cell.map(Vec3(aim(rng), aim(rng), aim(rng)));
        const Vec3 o = target + 6 * randomUnit(rng);
        const Vec3 d = (target - o).normalized();
        std::array<std::array<PatchHit, 2>, 6> faceHits;
        std::array<int, 6> faceCount;
        int anyHit = 0;
        for (int face = 0; face < 6; ++face) {
            const auto p = cell.faceCorners(face);
            faceCount[std::size_t(face)] = intersectBilinearPatchAll(
                o, d, p[0], p[1], p[2], p[3], 0, 1e30, faceHits[std::size_t(face)]);
            anyHit += faceCount[std::size_t(face)];
        }
        const auto isFaceHit = [&](int face, double t, const Vec3& r) {
            for (int h = 0; h < faceCount[std::size_t(face)]; ++h) {
                const PatchHit& hit = faceHits[std::size_t(face)][std::size_t(h)];
                if (std::abs(hit.t - t) <= 1e-9 * t &&
                    (TrilinearCell::faceToCell(face, hit.u, hit.v) - r).norm() <= 1e-9)
                    return true;
            }
            return false;
        };
        std::array<CellSpan, 4> spans;
        const int n = cellSpans(cell, o, d, spans);
        EXPECT_EQ(n > 0, anyHit > 0) << k;
        for (int i = 0; i < n; ++i) {
            const CellSpan& s = spans[std::size_t(i)];
            ASSERT_GE(s.faceIn, 0) << k;  // the origin is outside the cell
            EXPECT_TRUE(isFaceHit(s.faceIn, s.tIn, s.rIn)) << k;
            EXPECT_TRUE(isFaceHit(s.faceOut, s.tOut, s.rOut)) << k;
        }
        (n > 0 ? withSpans : without) += 1;
    }
    EXPECT_GT(withSpans, 500);
    EXPECT_GT(without, 300);
}

// The inverse trilinear map on random cells and on strongly twisted ones (top rotated by up to
// 80° against the bottom, normals tilted): every success has a residual below 1e-5 of the
// cell size; a failure is an empty optional, never a wrong answer.
TEST(Cell, InverseMapOnRandomAndTwistedCells) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u01(0, 1);
    struct Case {
        double jitter, tilt, height, twist;
        double minSuccess;
    };
    const Case cases[] = {{0.1, 0.2, 0.3, 0.0, 1.0},   {0.3, 0.5, 1.0, 0.0, 0.999},
                          {0.1, 0.2, 0.5, 1.0, 0.999}, {0.2, 0.5, 1.0, 1.4, 0.99},
                          {0.1, 0.1, 1e-3, 0.0, 1.0},  {0.1, 0.1, 20.0, 0.5, 0.99}};
    for (const Case& c : cases) {
        int successes = 0, total = 0;
        for (int k = 0; k < 200; ++k) {
            const TrilinearCell cell = randomCell(rng, c.jitter, c.tilt, c.height, c.twist);
            for (int s = 0; s < 10; ++s) {
                const Vec3 r(u01(rng), u01(rng), u01(rng));
                const Vec3 x = cell.map(r);
                const auto found = cell.inverse(x, Vec3(0.5, 0.5, 0.5), 1e-7, 1e-3);
                ++total;
                if (!found) continue;
                ++successes;
                EXPECT_LT((cell.map(*found) - x).norm(), 1e-5 * cell.size());
            }
        }
        EXPECT_GE(double(successes) / total, c.minSuccess)
            << "jitter " << c.jitter << " twist " << c.twist << " height " << c.height;
    }
}

TEST(Cell, InverseMapRefusesPointsOutside) {
    const std::array<Vec3, 4> p = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
    const std::array<Vec3, 4> n = {Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)};
    const TrilinearCell cell(p, n, 1, false);
    EXPECT_FALSE(cell.inverse(Vec3(3, 0.5, 0.5)));
    const auto inside = cell.inverse(Vec3(0.25, 0.5, 0.75));
    ASSERT_TRUE(inside);
    EXPECT_NEAR((*inside - Vec3(0.25, 0.5, 0.75)).norm(), 0, 1e-7);
    // A degenerate (zero-height) cell: a clear failure off the face, not a NaN.
    const TrilinearCell flat(p, n, 0, false);
    const auto off = flat.inverse(Vec3(0.5, 0.5, 0.5));
    EXPECT_FALSE(off);
}

// A random parallelepiped cell (sheared, tilted, scaled; every fifth under its face) from dyadic
// values, so that the corners' sums are exact and the trilinear map's mixed terms exactly zero,
// and the same cell with one top corner moved by 1e-13 of its size, which makes it trilinear: the
// oracle for what the affine fast paths must give. `s`: the cell's scale.
struct AffinePair {
    TrilinearCell affine, trilinear;
    double s;
    bool exactlyAffine() const {
        const auto& c = affine.corners();
        return (c[3] - c[1] - c[2] + c[0]).isZero(0) && (c[5] - c[1] - c[4] + c[0]).isZero(0) &&
               (c[6] - c[2] - c[4] + c[0]).isZero(0) && (c[7] - c[3] - c[5] + c[1]).isZero(0);
    }
};
AffinePair randomParallelepiped(std::mt19937& rng, int k) {
    std::uniform_real_distribution<double> uniform(-1, 1), scale(0.2, 3);
    const auto u = [&] { return std::round(uniform(rng) * 256) / 256; };
    const double s = std::round(scale(rng) * 16) / 16;
    const Vec3 a = s * (Vec3(1, 0, 0) + 0.25 * Vec3(u(), u(), u()));
    const Vec3 b = s * (Vec3(0, 1, 0) + 0.25 * Vec3(u(), u(), u()));
    const Vec3 base = 4 * Vec3(u(), u(), u());
    const Vec3 normal = Vec3(0.375 * u(), 0.375 * u(), 1);
    const double h = s * (0.25 + std::abs(u()));
    const std::array<Vec3, 4> p = {base, base + a, base + b, base + a + b};
    const std::array<Vec3, 4> n = {normal, normal, normal, normal};
    std::array<Vec3, 4> q = p;
    q[3] += 1e-13 * s * Vec3(1, 1, 1);
    return {TrilinearCell(p, n, h, k % 5 == 0), TrilinearCell(q, n, h, k % 5 == 0), s};
}

// A cell whose trilinear map is affine takes the slab test instead of the six patch tests; it must
// give what the patch tests give on the perturbed (trilinear) cell. Rays aimed in and around random
// parallelepipeds, from outside and from inside.
TEST(Cell, AffineCellsTakeTheSlabTestWithTheSameSpans) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> aim(-0.3, 1.3);
    int compared = 0, hits = 0, exactlyAffine = 0;
    for (int k = 0; k < 3000; ++k) {
        const AffinePair pair = randomParallelepiped(rng, k);
        const TrilinearCell &affine = pair.affine, &trilinear = pair.trilinear;
        const double s = pair.s;
        exactlyAffine += pair.exactlyAffine();
        const Vec3 target = affine.map(Vec3(aim(rng), aim(rng), aim(rng)));
        const Vec3 o = k % 4 == 0 ? affine.map(Vec3(0.5, 0.5, 0.5)) : target + 4 * s * randomUnit(rng);
        const Vec3 d = k % 4 == 0 ? randomUnit(rng) : Vec3((target - o).normalized());
        std::array<CellSpan, 4> fast, slow;
        const int nf = cellSpans(affine, o, d, fast), ns = cellSpans(trilinear, o, d, slow);
        ASSERT_EQ(nf, ns) << k;
        ++compared;
        for (int i = 0; i < nf; ++i) {
            const CellSpan &x = fast[std::size_t(i)], &y = slow[std::size_t(i)];
            ++hits;
            EXPECT_EQ(x.faceIn, y.faceIn) << k;
            EXPECT_EQ(x.faceOut, y.faceOut) << k;
            EXPECT_NEAR(x.tIn, y.tIn, 1e-9 * s) << k;
            EXPECT_NEAR(x.tOut, y.tOut, 1e-9 * s) << k;
            if (x.faceIn >= 0) {
                EXPECT_LT((x.rIn - y.rIn).norm(), 1e-9) << k;
            }
            EXPECT_LT((x.rOut - y.rOut).norm(), 1e-9) << k;
        }
    }
    EXPECT_EQ(compared, 3000);
    EXPECT_GT(exactlyAffine, 2900);  // the slab test is what is tested
    EXPECT_GT(hits, 1500);
}

// The Jacobian, which a parallelepiped keeps from its construction instead of interpolating its
// edges at every point, against the derivative of the trilinear map written out here: the
// bilinear blend of the four edges along each axis. The parallelepipeds are recognised as affine
// and the perturbed cells not; a point that is not finite gets no finite Jacobian.
TEST(Cell, JacobianIsTheBlendOfTheEdgesOnAffineAndTrilinearCells) {
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> around(-0.2, 1.2);
    const auto blend = [](const TrilinearCell& cell, const Vec3& r) {
        const auto& c = cell.corners();
        const double u = r.x(), v = r.y(), w = r.z();
        const auto edges = [](const Vec3& e0, const Vec3& e1, const Vec3& e2, const Vec3& e3, double a, double b) {
            return Vec3((1 - a) * (1 - b) * e0 + a * (1 - b) * e1 + (1 - a) * b * e2 + a * b * e3);
        };
        Mat3 j;
        j.col(0) = edges(c[1] - c[0], c[3] - c[2], c[5] - c[4], c[7] - c[6], v, w);
        j.col(1) = edges(c[2] - c[0], c[3] - c[1], c[6] - c[4], c[7] - c[5], u, w);
        j.col(2) = edges(c[4] - c[0], c[5] - c[1], c[6] - c[2], c[7] - c[3], u, v);
        return j;
    };
    for (int k = 0; k < 500; ++k) {
        const AffinePair pair = randomParallelepiped(rng, k);
        ASSERT_TRUE(pair.exactlyAffine()) << k;
        EXPECT_TRUE(pair.affine.affine()) << k;
        EXPECT_FALSE(pair.trilinear.affine()) << k;
        const auto& c = pair.affine.corners();
        EXPECT_EQ(pair.affine.affineJacobian().col(0), c[1] - c[0]) << k;
        EXPECT_EQ(pair.affine.affineJacobian().col(1), c[2] - c[0]) << k;
        EXPECT_EQ(pair.affine.affineJacobian().col(2), c[4] - c[0]) << k;
        for (const TrilinearCell* cell : {&pair.affine, &pair.trilinear}) {
            const Vec3 r(around(rng), around(rng), around(rng));
            const Mat3 expected = blend(*cell, r);
            EXPECT_LT((cell->jacobian(r) - expected).norm(), 1e-12 * expected.norm()) << k;
        }
        EXPECT_FALSE(pair.affine.jacobian(Vec3(NAN, 0.5, 0.5)).allFinite()) << k;
    }
    for (int k = 0; k < 200; ++k) {  // jittered, tilted and twisted cells: trilinear
        const TrilinearCell cell = randomCell(rng, 0.2, 0.3, 0.5, k % 2 ? 0.8 : 0.0);
        EXPECT_FALSE(cell.affine()) << k;
        const Vec3 r(around(rng), around(rng), around(rng));
        EXPECT_LT((cell.jacobian(r) - blend(cell, r)).norm(), 1e-12 * blend(cell, r).norm()) << k;
    }
}

// An affine cell's inverse map is one linear solve instead of Newton's iterations; it must find
// what Newton finds on the perturbed (trilinear) cell, and refuse what Newton refuses: points
// inside, on the faces and outside random parallelepipeds.
TEST(Cell, AffineCellsInvertByOneSolveAsNewtonDoes) {
    std::mt19937 rng(37);
    std::uniform_real_distribution<double> inside(0, 1), around(-0.2, 1.2);
    int found = 0, refused = 0;
    for (int k = 0; k < 2000; ++k) {
        const AffinePair pair = randomParallelepiped(rng, k);
        ASSERT_TRUE(pair.exactlyAffine()) << k;
        Vec3 r(inside(rng), inside(rng), inside(rng));
        if (k % 3 == 1) r[k % 2 ? 0 : 2] = double(k % 4 == 1);  // on a face
        if (k % 3 == 2) r = Vec3(around(rng), around(rng), around(rng));
        const Vec3 x = pair.affine.map(r);
        const auto fast = pair.affine.inverse(x), slow = pair.trilinear.inverse(x);
        ASSERT_EQ(bool(fast), bool(slow)) << k;
        if (!fast) {
            ++refused;
            continue;
        }
        ++found;
        EXPECT_LT((*fast - *slow).norm(), 1e-9) << k;
        // Within the cell the solve is exact up to rounding (outside, within the slack, both clamp).
        if ((r.array() >= 0).all() && (r.array() <= 1).all()) {
            EXPECT_LT((pair.affine.map(*fast) - x).norm(), 1e-12 * pair.s * 8) << k;
        }
    }
    EXPECT_GT(found, 1400);
    EXPECT_GT(refused, 300);
}
