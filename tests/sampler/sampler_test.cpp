// The sampler: exact area, fitted ellipsoids, albedo, solid interior, cyclic volumes, regions.
#include "meshes.h"

#include <vtex/core/memory_budget.h>
#include <vtex/octree/filtering.h>
#include <vtex/octree/octree.h>
#include <vtex/sampler/clip.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <map>
#include <set>
#include <stdexcept>

namespace vtex::sampler {
namespace {

using namespace test;
using octree::mortonDecode;
using octree::mortonEncode;

SampleOptions optionsFor(std::uint32_t n, bool cyclic = false) {
    SampleOptions o;
    o.resolution = n;
    o.cyclic = cyclic;
    o.bounds = BoundsMode::Unit;
    return o;
}

octree::SparseVolume sample(const ingest::TriangleMesh& mesh, const SampleOptions& o) {
    NullProgress progress;
    return sampleMesh(mesh, o, progress);
}

// Σ ρ · 2V over the surface voxels: the area the volume holds.
double sampledArea(const octree::SparseVolume& v) {
    double area = 0;
    const double voxelVolume = std::ldexp(1.0, -3 * int(v.info.levels));
    for (const auto& b : v.blocks)
        if (!b.isSolid()) area += double(b.data.density) * 2 * voxelVolume;
    return area;
}

// Random triangles, many of them lying exactly on voxel faces, along voxel edges, or with
// vertices on grid points: the cases where a closed-box clipper counts area twice.
ingest::TriangleMesh awkwardMesh(std::uint32_t n, unsigned seed, int count) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::uniform_int_distribution<int> grid(0, int(n));
    auto onGrid = [&] { return double(grid(rng)) / n; };
    ingest::TriangleMesh mesh = emptyMesh();
    for (int i = 0; i < count; ++i) {
        const int kind = i % 5;
        Vec3 p[3];
        for (auto& q : p) q = Vec3(u(rng), u(rng), u(rng));
        if (kind == 1) {  // in a voxel face plane x = k/N (or y, or z)
            const int axis = i % 3;
            const double c = onGrid();
            for (auto& q : p) q[axis] = c;
        } else if (kind == 2) {  // one edge along a voxel edge line
            const double y = onGrid(), z = onGrid();
            p[0] = Vec3(u(rng), y, z);
            p[1] = Vec3(u(rng), y, z);
        } else if (kind == 3) {  // all vertices on grid points
            for (auto& q : p) q = Vec3(onGrid(), onGrid(), onGrid());
        } else if (kind == 4) {  // in the far faces of the volume
            const int axis = (i / 5) % 3;
            for (auto& q : p) q[axis] = (i / 15) % 2 ? 1.0 : 0.0;
        }
        if ((p[1] - p[0]).cross(p[2] - p[0]).norm() < 1e-6) continue;
        addTriangle(mesh, p[0], p[1], p[2]);
    }
    return mesh;
}

TEST(Clip, PiecesPartitionTheTriangleExactly) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-2.0, 10.0), w(0.0, 10.0);  // z does not wrap
    for (int i = 0; i < 2000; ++i) {
        const Vec3 a(u(rng), u(rng), w(rng)), b(u(rng), u(rng), w(rng)), c(u(rng), u(rng), w(rng));
        double sum = 0;
        std::set<std::uint64_t> seen;
        bool duplicate = false;
        clipTriangleToGrid(a, b, c, 1u << 20, true, [&](std::uint32_t x, std::uint32_t y, std::uint32_t z, const ClipPolygon& p) {
            const double area = p.area();
            if (area > 0) duplicate = duplicate || !seen.insert(mortonEncode(x, y, z)).second;
            sum += area;
        });
        const double area = 0.5 * (b - a).cross(c - a).norm();
        ASSERT_NEAR(sum, area, 1e-9 * area) << i;
        ASSERT_FALSE(duplicate) << "a voxel received two pieces of one triangle";
    }
}

TEST(Clip, TriangleOnAVoxelFaceIsCountedOnceOnThePlusSide) {
    // The triangle lies in the plane x = 2 (voxel units), between voxels 1 and 2.
    std::map<std::uint64_t, double> area;
    clipTriangleToGrid(Vec3(2, 0.5, 0.5), Vec3(2, 3.5, 0.5), Vec3(2, 0.5, 3.5), 4, false,
                       [&](std::uint32_t x, std::uint32_t y, std::uint32_t z, const ClipPolygon& p) {
                           area[mortonEncode(x, y, z)] += p.area();
                       });
    double total = 0;
    for (const auto& [key, a] : area) {
        if (a <= 0) continue;
        EXPECT_EQ(mortonDecode(key)[0], 2u);
        total += a;
    }
    EXPECT_NEAR(total, 4.5, 1e-12);
    // On the far face x = N of a closed axis, it goes to the last voxel instead of vanishing.
    area.clear();
    clipTriangleToGrid(Vec3(4, 0.5, 0.5), Vec3(4, 3.5, 0.5), Vec3(4, 0.5, 3.5), 4, false,
                       [&](std::uint32_t x, std::uint32_t y, std::uint32_t z, const ClipPolygon& p) {
                           if (p.area() > 0) {
                               EXPECT_EQ(x, 3u);
                           }
                           area[mortonEncode(x, y, z)] += p.area();
                       });
    total = 0;
    for (const auto& [key, a] : area) total += a;
    EXPECT_NEAR(total, 4.5, 1e-12);
}

TEST(Sampler, AreaIsConservedForAwkwardMeshes) {
    for (std::uint32_t n : {1u, 4u, 16u, 64u}) {
        for (unsigned seed : {1u, 2u}) {
            const auto mesh = awkwardMesh(n, seed, 400);
            const double area = meshArea(mesh);
            for (bool cyclic : {false, true}) {
                const auto volume = sample(mesh, optionsFor(n, cyclic));
                EXPECT_NEAR(sampledArea(volume), area, 1e-4 * area) << "N=" << n << " cyclic=" << cyclic;
                EXPECT_NEAR(volume.info.sourceArea, area, 1e-6 * area);
            }
        }
    }
}

TEST(Sampler, AreaIsConservedForEveryPattern) {
    for (const auto& name : patternNames()) {
        PatternOptions po;
        po.count = name == "bush" ? 300 : 0;
        const auto mesh = makePattern(name, po);
        const auto volume = sample(mesh, optionsFor(32, isCyclicPattern(name)));
        const double area = meshArea(mesh);
        EXPECT_NEAR(sampledArea(volume), area, 1e-4 * area) << name;
    }
}

// The build reads children through their stored eigen-form (octree::storedFilterForm) taking
// their normalisation as exact; on the bush's own voxels every stored parent still equals the
// filter of its stored children rebuilt as Ellipsoids, within the float rounding of σ.
TEST(Sampler, BushParentsAreTheFilterOfTheirChildrenRebuiltAsEllipsoids) {
    PatternOptions po;
    const auto volume = sample(makePattern("bush", po), optionsFor(64));
    for (octree::FilterRule rule : {octree::FilterRule::Sggx, octree::FilterRule::Neyret}) {
        octree::BuildOptions bo;
        bo.rule = rule;
        NullProgress progress;
        const octree::Octree tree = octree::buildOctree(volume, bo, progress);
        std::size_t checked = 0;
        double worst = 0;
        for (std::uint32_t l = 0; l + 1 < tree.levelCount(); ++l)
            for (const auto& node : tree.levels[l]) {
                if (node.childMask == 0) continue;
                std::vector<octree::Ellipsoid> children;
                std::vector<double> weights;
                for (int c = 0; c < std::popcount(unsigned(node.childMask)); ++c) {
                    const auto& child = tree.levels[l + 1][node.firstChild + std::size_t(c)].data;
                    const auto e = octree::unpackEllipsoid(child);
                    ASSERT_TRUE(e);
                    EXPECT_NEAR(e->meanProjectedArea(), 1.0, 1e-6);
                    children.push_back(*e);
                    weights.push_back(child.density);
                }
                const auto reference = octree::filterEllipsoids(children, weights, rule);
                ASSERT_TRUE(reference);
                const octree::Mat3 expected = reference->S(), stored = octree::unpackS(node.data).matrix();
                worst = std::max(worst, (stored - expected).norm() / expected.norm());
                ++checked;
            }
        EXPECT_GT(checked, 1000u);
        EXPECT_LT(worst, 1e-5) << (rule == octree::FilterRule::Sggx ? "sggx" : "neyret");
    }
}

TEST(Sampler, FlatSquareGivesDiscsAlongItsNormal) {
    const Vec3 normal = Vec3(0.3, -0.5, 0.8).normalized();
    const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u), c(0.5, 0.5, 0.5);
    ingest::TriangleMesh mesh = emptyMesh();
    addTriangle(mesh, c - 0.3 * u - 0.3 * v, c + 0.3 * u - 0.3 * v, c + 0.3 * u + 0.3 * v);
    addTriangle(mesh, c - 0.3 * u - 0.3 * v, c + 0.3 * u + 0.3 * v, c - 0.3 * u + 0.3 * v);
    const auto volume = sample(mesh, optionsFor(16));
    ASSERT_GT(volume.blocks.size(), 50u);
    for (const auto& b : volume.blocks) {
        const auto e = octree::unpackEllipsoid(b.data);
        ASSERT_TRUE(e);
        EXPECT_GT(std::abs(e->basis().col(0).dot(normal)), 0.999);  // the short axis
        EXPECT_LT(e->semiAxes()[0] / e->semiAxes()[2], 1e-2);
        EXPECT_NEAR(e->semiAxes()[1] / e->semiAxes()[2], 1.0, 1e-3);
    }
}

TEST(Sampler, CylinderFiltersIntoANeedleAlongItsAxis) {
    // Paper Fig. 3: the side of a cylinder whose section spans several voxels, filtered to one
    // voxel, is a needle (an elongated ellipsoid) along the axis.
    const Vec3 axis = Vec3(0.2, 0.1, 1).normalized();
    const auto mesh = cylinderSide(Vec3(0.5, 0.5, 0.5) - 0.42 * axis, axis, 0.25, 0.84, 48);
    const auto volume = sample(mesh, optionsFor(16));
    for (auto rule : {octree::FilterRule::Sggx, octree::FilterRule::Neyret}) {
        octree::BuildOptions bo;
        bo.rule = rule;
        NullProgress progress;
        const auto tree = octree::buildOctree(volume, bo, progress);
        const auto e = octree::unpackEllipsoid(tree.levels[0][0].data);
        ASSERT_TRUE(e);
        EXPECT_GT(std::abs(e->basis().col(2).dot(axis)), 0.99) << octree::filterRuleName(rule);
        // SGGX keeps the axis direction free of area: a true needle; the paper's rule averages
        // the discs' M into a milder prolate shape (ratio ≈ 1/√2).
        const double ratio = e->semiAxes()[1] / e->semiAxes()[2];
        EXPECT_LT(ratio, rule == octree::FilterRule::Sggx ? 0.05 : 0.8) << octree::filterRuleName(rule);
    }
}

TEST(Sampler, GrassFiltersToItsMeanDirectionAndThinnerWhenFluctuationIsSmaller) {
    // Paper §3.3.1: a meadow of fluctuating blades filtered to one voxel gives an ellipsoid
    // oriented along the mean direction, the thinner the smaller the fluctuation.
    const Vec3 mean(std::sin(0.5), 0, std::cos(0.5));  // lean 0.5 rad toward +x
    double ratios[2];
    const double fluctuations[2] = {0.05, 0.4};
    for (int i = 0; i < 2; ++i) {
        PatternOptions po;
        po.count = 64;
        po.fluctuation = fluctuations[i];
        po.leanDegrees = 0.5 * 180 / std::numbers::pi;
        po.seed = 3;
        const auto volume = sample(makePattern("grass", po), optionsFor(32, true));
        NullProgress progress;
        const auto tree = octree::buildOctree(volume, {}, progress);
        const auto e = octree::unpackEllipsoid(tree.levels[0][0].data);
        ASSERT_TRUE(e);
        EXPECT_GT(std::abs(e->basis().col(2).dot(mean)), i == 0 ? 0.99 : 0.9) << fluctuations[i];
        ratios[i] = e->semiAxes()[1] / e->semiAxes()[2];
    }
    EXPECT_LT(ratios[0], 0.5 * ratios[1]);
}

TEST(Sampler, SolidCubeHasASolidInteriorAndAreaOnlyOnItsBoundary) {
    const Vec3 lo(0.23, 0.27, 0.2), hi(0.71, 0.77, 0.74);
    const std::uint32_t n = 16;
    auto options = optionsFor(n);
    options.solid = SolidMode::Auto;
    const auto volume = sample(boxMesh(lo, hi), options);
    const double rhoSolid = 16.0 * n;
    EXPECT_EQ(volume.info.solidDensity, float(rhoSolid));
    double area = 0;
    std::map<std::uint64_t, const octree::VolumeBlock*> surface;
    std::set<std::uint64_t> solid;
    for (const auto& b : volume.blocks) {
        if (!b.isSolid()) {
            EXPECT_EQ(b.level, volume.info.levels);
            surface[b.key] = &b;
            area += double(b.data.density) * 2 / (n * n * n);
            continue;
        }
        EXPECT_EQ(b.data.density, float(rhoSolid));
        const auto c = mortonDecode(b.key);
        const std::uint32_t size = n >> b.level;
        for (std::uint32_t z = 0; z < size; ++z)
            for (std::uint32_t y = 0; y < size; ++y)
                for (std::uint32_t x = 0; x < size; ++x)
                    solid.insert(mortonEncode(c[0] * size + x, c[1] * size + y, c[2] * size + z));
    }
    const Vec3 ext = hi - lo;
    EXPECT_NEAR(area, 2 * (ext.x() * ext.y() + ext.y() * ext.z() + ext.x() * ext.z()), 1e-5);
    // Every voxel: surface iff the boundary crosses it; solid iff it lies inside without surface.
    for (std::uint32_t z = 0; z < n; ++z)
        for (std::uint32_t y = 0; y < n; ++y)
            for (std::uint32_t x = 0; x < n; ++x) {
                const Vec3 vlo = Vec3(x, y, z) / n, vhi = Vec3(x + 1, y + 1, z + 1) / n;
                const bool inside = (vlo.array() >= lo.array()).all() && (vhi.array() <= hi.array()).all();
                const bool outside = ((vhi.array() <= lo.array()) || (vlo.array() >= hi.array())).any();
                const std::uint64_t key = mortonEncode(x, y, z);
                if (inside) {
                    EXPECT_TRUE(solid.count(key)) << x << " " << y << " " << z;
                    EXPECT_FALSE(surface.count(key));
                } else if (outside) {
                    EXPECT_FALSE(solid.count(key) || surface.count(key)) << x << " " << y << " " << z;
                } else {
                    EXPECT_TRUE(surface.count(key)) << x << " " << y << " " << z;
                }
            }
    // Solid blocks are coarse where they can be: fewer blocks than voxels.
    const std::size_t solidBlocks = volume.blocks.size() - surface.size();
    EXPECT_LT(solidBlocks, solid.size());
    // --solid off: surfaces only.
    options.solid = SolidMode::Off;
    EXPECT_EQ(sample(boxMesh(lo, hi), options).blocks.size(), surface.size());
}

TEST(Sampler, SolidWorksWhenIngestSplitVerticesAlongSeams) {
    // A closed cube whose faces have their own vertices (as flat-shaded glTF stores it).
    const auto shared = boxMesh(Vec3(0.2, 0.2, 0.2), Vec3(0.8, 0.8, 0.8));
    ingest::TriangleMesh split = emptyMesh();
    for (const auto& t : shared.triangles)
        addTriangle(split, shared.positions[t[0]].cast<double>(), shared.positions[t[1]].cast<double>(),
                    shared.positions[t[2]].cast<double>());
    split.closed = true;
    auto options = optionsFor(16);
    EXPECT_EQ(sample(split, options), sample(shared, options));
}

TEST(Sampler, CyclicPatternsSampleToAPeriodicVolume) {
    for (const char* name : {"grass", "fur"}) {
        PatternOptions po;
        po.count = name == std::string("fur") ? 60 : 0;
        const auto mesh = makePattern(name, po);
        for (const auto& p : mesh.positions) {
            ASSERT_GE(p.x(), 0.0f);
            ASSERT_LE(p.x(), 1.0f);
            ASSERT_GE(p.y(), 0.0f);
            ASSERT_LE(p.y(), 1.0f);
        }
        // Shift the tile by (1/4, 1/2): sampled periodically, the volume shifts by (8, 16) voxels.
        auto shifted = mesh;
        for (auto& p : shifted.positions) p += Eigen::Vector3f(0.25f, 0.5f, 0.0f);
        const std::uint32_t n = 32;
        const auto a = sample(mesh, optionsFor(n, true)), b = sample(shifted, optionsFor(n, true));
        std::map<std::uint64_t, float> density;
        for (const auto& blk : b.blocks) density[blk.key] = blk.data.density;
        double mismatch = 0, total = 0;
        for (const auto& blk : a.blocks) {
            const auto c = mortonDecode(blk.key);
            const auto it = density.find(mortonEncode((c[0] + 8) % n, (c[1] + 16) % n, c[2]));
            const double other = it == density.end() ? 0 : it->second;
            mismatch += std::abs(other - blk.data.density);
            total += blk.data.density;
        }
        EXPECT_LT(mismatch, 1e-4 * total) << name;
        EXPECT_NEAR(sampledArea(a), sampledArea(b), 1e-5 * sampledArea(a));
    }
}

TEST(Sampler, WrappingIntoTheTileKeepsTheArea) {
    ingest::TriangleMesh mesh = emptyMesh();
    addTriangle(mesh, Vec3(-0.3, 0.9, 0.1), Vec3(1.4, 0.2, 0.5), Vec3(0.5, 1.7, 0.9));
    const auto wrapped = wrapIntoUnitTile(mesh);
    EXPECT_NEAR(meshArea(wrapped), meshArea(mesh), 1e-6);
    EXPECT_GT(wrapped.triangles.size(), 4u);
    // Sampled periodically, the original and the wrapped mesh are the same volume.
    const auto a = sample(mesh, optionsFor(16, true)), b = sample(wrapped, optionsFor(16, true));
    ASSERT_EQ(a.blocks.size(), b.blocks.size());
    for (std::size_t i = 0; i < a.blocks.size(); ++i) {
        EXPECT_EQ(a.blocks[i].key, b.blocks[i].key);
        EXPECT_NEAR(a.blocks[i].data.density, b.blocks[i].data.density, 1e-4 * a.blocks[i].data.density);
    }
}

TEST(Sampler, RegionSamplingEqualsTheFullSamplingBitForBit) {
    PatternOptions po;
    po.count = 300;
    const auto mesh = makePattern("bush", po);
    const auto full = sample(mesh, optionsFor(32));
    auto options = optionsFor(32);
    options.region = octree::VoxelBox{{5, 3, 10}, {20, 30, 17}};
    const auto part = sample(mesh, options);
    std::vector<octree::VolumeBlock> expected;
    for (const auto& b : full.blocks) {
        const auto c = mortonDecode(b.key);
        if (options.region->contains(c[0], c[1], c[2])) expected.push_back(b);
    }
    ASSERT_GT(expected.size(), 100u);
    EXPECT_EQ(part.blocks, expected);
}

TEST(Sampler, TextureIsDecodedFromSrgbAndSampledWhereThePiecesAre) {
    // A square textured left half sRGB 255 (linear 1), right half sRGB 128 (linear 0.2158).
    ingest::TriangleMesh mesh = emptyMesh();
    ingest::Image image;
    image.width = 64;
    image.height = 1;
    for (int x = 0; x < 64; ++x)
        for (int c = 0; c < 4; ++c) image.rgba.push_back(c == 3 ? 255 : (x < 32 ? 255 : 128));
    mesh.textures.push_back(image);
    mesh.materials[0].baseColorTexture = 0;
    mesh.materials[0].baseColorFactor = Eigen::Vector4f(1.0f, 0.5f, 1.0f, 1.0f);
    addTriangle(mesh, Vec3(0, 0, 0.5), Vec3(1, 0, 0.5), Vec3(1, 1, 0.5));
    addTriangle(mesh, Vec3(0, 0, 0.5), Vec3(1, 1, 0.5), Vec3(0, 1, 0.5));
    mesh.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
    const auto volume = sample(mesh, optionsFor(8));
    ASSERT_EQ(volume.blocks.size(), 64u);
    const double dark = std::pow((128 / 255.0 + 0.055) / 1.055, 2.4);
    for (const auto& b : volume.blocks) {
        const auto c = mortonDecode(b.key);
        // Voxels away from the texture's edges and its seam see one colour only.
        if (c[0] == 1 || c[0] == 2) {
            EXPECT_NEAR(b.data.albedo[0], 1.0, 1e-3);
            EXPECT_NEAR(b.data.albedo[1], 0.5, 1e-3);
        }
        if (c[0] == 5 || c[0] == 6) {
            EXPECT_NEAR(b.data.albedo[0], dark, 1e-3);
            EXPECT_NEAR(b.data.albedo[1], 0.5 * dark, 1e-3);
        }
    }
}

TEST(Sampler, MaxMemoryRefusesUpFront) {
    PatternOptions po;
    po.count = 200;
    const auto mesh = makePattern("bush", po);
    auto options = optionsFor(1024);
    const std::uint64_t estimate = estimateSampleMemory(mesh, options);
    auto small = optionsFor(64);
    EXPECT_GT(estimate, 100 * estimateSampleMemory(mesh, small) / 8);  // grows with the surface
    options.maxMemoryBytes = estimate / 2;
    CountingProgress progress;
    EXPECT_THROW(sampleMesh(mesh, options, progress), vtex::MemoryLimitError);
    EXPECT_EQ(progress.total(), 0u);  // refused before any phase started
    // The estimate is an upper bound of what sampling really needs: the records and voxels.
    small.maxMemoryBytes = estimateSampleMemory(mesh, small);
    const auto volume = sampleMesh(mesh, small, progress);
    EXPECT_LT(volume.blocks.size() * sizeof(octree::VolumeBlock), small.maxMemoryBytes);
}

TEST(Sampler, RejectsBadOptions) {
    const auto mesh = boxMesh(Vec3(0.2, 0.2, 0.2), Vec3(0.8, 0.8, 0.8));
    NullProgress progress;
    EXPECT_THROW(sampleMesh(mesh, optionsFor(12), progress), std::invalid_argument);
    auto options = optionsFor(16, true);
    options.solid = SolidMode::On;
    EXPECT_THROW(sampleMesh(mesh, options, progress), std::invalid_argument);
    options = optionsFor(16);
    options.region = octree::VoxelBox{{0, 0, 0}, {17, 4, 4}};
    EXPECT_THROW(sampleMesh(mesh, options, progress), std::invalid_argument);
}

TEST(Patterns, AreDeterministicPerSeedAndInsideTheUnitCube) {
    for (const auto& name : patternNames()) {
        PatternOptions a;
        a.count = name == "bush" ? 100 : 0;
        PatternOptions b = a;
        b.seed = 2;
        const auto m1 = makePattern(name, a), m2 = makePattern(name, a), m3 = makePattern(name, b);
        EXPECT_EQ(m1.positions, m2.positions) << name;
        EXPECT_NE(m1.positions, m3.positions) << name;
        EXPECT_EQ(m1.triangles.size(), m1.triangleMaterials.size());
        for (const auto& p : m1.positions) {
            ASSERT_TRUE((p.array() >= 0).all() && (p.array() <= 1).all()) << name << " " << p.transpose();
        }
        for (const auto& nrm : m1.normals) ASSERT_NEAR(nrm.norm(), 1.0f, 1e-4f) << name;
    }
    PatternOptions bush;
    EXPECT_EQ(makePattern("bush", bush).triangles.size(), 2000u * 8u);  // 2000 leaves by default
    EXPECT_THROW(makePattern("lawn", bush), std::invalid_argument);
}

// Fig. 5's topiary: each variant is `count` elements of its kind (a leaf two triangles, a
// three-sided needle six) and the frame's twelve bars (twelve triangles each, in the second
// material); an unknown variant is refused.
TEST(Patterns, TopiaryIsItsElementsInAFrame) {
    for (const std::string variant : {"leaves", "needles", "beads"}) {
        PatternOptions o;
        o.count = 100;
        o.variant = variant;
        const auto mesh = makePattern("topiary", o);
        const auto frame = std::count(mesh.triangleMaterials.begin(), mesh.triangleMaterials.end(), 1u);
        EXPECT_EQ(frame, 12 * 12) << variant;
        const std::size_t elements = mesh.triangles.size() - std::size_t(frame);
        if (variant == "leaves") { EXPECT_EQ(elements, 100u * 2) << variant; }
        if (variant == "needles") { EXPECT_EQ(elements, 100u * 6) << variant; }
        if (variant == "beads") { EXPECT_GE(elements, 100u * 8) << variant; }
    }
    PatternOptions bad;
    bad.variant = "radial";
    EXPECT_THROW(makePattern("topiary", bad), std::invalid_argument);
}

TEST(Patterns, BlocksHaveElementsThinnerThanAVoxelAt128) {
    const auto mesh = makePattern("blocks", {});
    double thinnest = 1;
    // Rods (material 2) and plates (material 3) are boxes: 12 consecutive triangles.
    for (std::size_t t = 0; t + 11 < mesh.triangles.size(); ++t) {
        const auto m = mesh.triangleMaterials[t];
        if ((m != 2 && m != 3) || mesh.triangleMaterials[t + 11] != m) continue;
        Eigen::Vector3f lo = mesh.positions[mesh.triangles[t][0]], hi = lo;
        for (std::size_t k = t; k < t + 12; ++k)
            for (auto i : mesh.triangles[k]) {
                lo = lo.cwiseMin(mesh.positions[i]);
                hi = hi.cwiseMax(mesh.positions[i]);
            }
        thinnest = std::min(thinnest, double((hi - lo).minCoeff()));
        t += 11;
    }
    EXPECT_LT(thinnest, 1.0 / 128);
}

}  // namespace
}  // namespace vtex::sampler
