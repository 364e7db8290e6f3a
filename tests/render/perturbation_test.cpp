// Per-face perturbation of the reference volume and sub-rectangles (issue 16; paper §3: "agrandir,
// déplacer ou faire tourner le volume de référence pour chaque texel"): the one CellMap, its draw
// per face, and both renderers taking it alike.
#include "fixtures.h"

#include <vtex/core/error.h>
#include <vtex/render/cell_map.h>
#include <vtex/render/compare.h>
#include <vtex/render/reference.h>
#include <vtex/sampler/sampler.h>

#include <gtest/gtest.h>

#include <set>

using namespace vtex::render;
using namespace vtex::render::test;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

namespace {

// The closed box [lo, hi] (x, y, z), outward-facing.
std::shared_ptr<vtex::ingest::TriangleMesh> box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
    auto mesh = std::make_shared<vtex::ingest::TriangleMesh>();
    for (int i = 0; i < 8; ++i) mesh->positions.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    mesh->triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                       {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    mesh->normals.assign(8, Eigen::Vector3f(0, 0, 1));
    mesh->materials.emplace_back();
    mesh->closed = true;
    return mesh;
}

// An opaque block in one corner of the reference volume (x, y, z < ½ of 4³).
std::shared_ptr<const vtex::octree::Octree> cornerBlock() {
    return makeOctree(2, [](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        if (x < 2 && y < 2 && z < 2) return sphereVoxel(40.0f, {0.9f, 0.5f, 0.2f});
        return std::nullopt;
    });
}

Scene gridScene(int n, const Perturbation& perturb) {
    Scene scene = baseScene(Eigen::Vector3d(2, -2.5, 5), Eigen::Vector3d(2, 2, 0), 55, 64);
    addTexel(scene, cornerBlock());
    addSurface(scene, gridMesh(0, 0, 4, 4, 0, n), 0, 0.5);
    scene.surfaces[0].perturb = perturb;
    return scene;
}

RenderResult referenceQuiet(const Scene& scene, ReferenceOptions options = {}) {
    vtex::NullProgress progress;
    return renderReference(scene, options, progress);
}

std::string errorOf(const Scene& scene) {
    try {
        renderQuiet(scene);
    } catch (const vtex::InputError& e) {
        return e.what();
    }
    return "no error";
}

}  // namespace

// The map and its inverse, on every symmetry with a shift and a sub-rectangle: exact round trips,
// the unit square onto the rectangle, and a quarter turn by its literal.
TEST(CellMapTest, InverseAndSymmetries) {
    TexelPlacing placing;
    placing.subrect = std::array<double, 4>{0.25, -0.5, 1.25, 1.5};
    for (int turns = 0; turns < 4; ++turns)
        for (bool mirror : {false, true}) {
            const FaceTransform t{turns, mirror, Eigen::Vector2d(0.3, 0.7)};
            const CellMap map = makeCellMap(placing, t);
            for (const Vec3& r : {Vec3(0.1, 0.2, 0.3), Vec3(0.9, 0.05, 1), Vec3(0.5, 0.5, 0)})
                EXPECT_LT((map.toCell(map.toReference(r)) - r).norm(), 1e-12);
            Eigen::Vector2d lo, hi;
            map.bounds(lo, hi);
            EXPECT_LT((lo - Eigen::Vector2d(0.55, 0.2)).norm(), 1e-12) << turns << mirror;
            EXPECT_LT((hi - Eigen::Vector2d(1.55, 2.2)).norm(), 1e-12) << turns << mirror;
            EXPECT_NEAR(map.areaScale(), 2.0, 1e-12);
            EXPECT_LT((map.linear() * map.linearInverse() - Mat3::Identity()).norm(), 1e-12);
        }
    // A quarter turn counter-clockwise about the cell's centre: (1, 0) → (1, 1), (1, 1) → (0, 1).
    const CellMap turn = makeCellMap(TexelPlacing{}, FaceTransform{1, false, {0, 0}});
    EXPECT_LT((turn.toReference(Vec3(1, 0, 0.5)) - Vec3(1, 1, 0.5)).norm(), 1e-12);
    EXPECT_LT((turn.toReference(Vec3(1, 1, 0)) - Vec3(0, 1, 0)).norm(), 1e-12);
    // The mirror: x → 1 − x.
    const CellMap mirror = makeCellMap(TexelPlacing{}, FaceTransform{0, true, {0, 0}});
    EXPECT_LT((mirror.toReference(Vec3(0.2, 0.3, 0)) - Vec3(0.8, 0.3, 0)).norm(), 1e-12);
    // repeat [2, 3]: (u·2, v·3), as before the map.
    TexelPlacing repeat;
    repeat.repeat = {2, 3};
    EXPECT_LT((makeCellMap(repeat, {}).toReference(Vec3(0.5, 0.5, 0.25)) - Vec3(1, 1.5, 0.25)).norm(), 1e-12);
}

// The draw per face: a function of seed and face only, every turn and both mirror states among a
// few dozen faces, shifts in [0, 1), the identity with everything off.
TEST(CellMapTest, DrawIsDeterministicAndCoversTheSymmetries) {
    const Perturbation all{7, true, true, true};
    std::set<std::pair<int, bool>> seen;
    for (std::uint64_t face = 0; face < 64; ++face) {
        const FaceTransform a = drawFaceTransform(all, face), b = drawFaceTransform(all, face);
        EXPECT_EQ(a.quarterTurns, b.quarterTurns);
        EXPECT_EQ(a.mirror, b.mirror);
        EXPECT_EQ(a.shift, b.shift);
        EXPECT_GE(a.shift.minCoeff(), 0.0);
        EXPECT_LT(a.shift.maxCoeff(), 1.0);
        seen.insert({a.quarterTurns, a.mirror});
    }
    EXPECT_EQ(seen.size(), 8u);
    const FaceTransform off = drawFaceTransform(Perturbation{7, false, false, false}, 3);
    EXPECT_EQ(off.quarterTurns, 0);
    EXPECT_FALSE(off.mirror);
    EXPECT_EQ(off.shift, Eigen::Vector2d(0, 0));
    const FaceTransform rotateOnly = drawFaceTransform(Perturbation{7, true, false, false}, 3);
    EXPECT_FALSE(rotateOnly.mirror);
    EXPECT_EQ(rotateOnly.shift, Eigen::Vector2d(0, 0));
}

// Turning the reference volume per face changes the picture (the corner block moves to other
// corners), the same seed gives the same picture, another seed another one.
TEST(Perturbation, ChangesTheImageAndIsDeterministic) {
    RenderOptions options;
    options.spp = 1;
    const Image plain = renderQuiet(gridScene(4, {}), options).image;
    const Image seven = renderQuiet(gridScene(4, {7, true, false, false}), options).image;
    const Image again = renderQuiet(gridScene(4, {7, true, false, false}), options).image;
    const Image eight = renderQuiet(gridScene(4, {8, true, false, false}), options).image;
    EXPECT_GT(compareImages(seven, plain).rmse, 0.02);
    EXPECT_EQ(compareImages(seven, again).rmse, 0.0);
    EXPECT_GT(compareImages(seven, eight).rmse, 0.02);
    // The reference renderer turns the same faces the same way.
    Scene scene = gridScene(4, {7, true, false, false});
    scene.texels[0].sourceData = box({0, 0, 0}, {0.5f, 0.5f, 0.5f});
    Scene unperturbed = scene;
    unperturbed.surfaces[0].perturb = {};
    ReferenceOptions reference;
    reference.spp = 1;
    EXPECT_GT(compareImages(referenceQuiet(scene, reference).image, referenceQuiet(unperturbed, reference).image).rmse, 0.02);
}

// A shift needs a cyclic texel, and so does a sub-rectangle beyond the unit square: refused,
// naming the key; within the square a sub-rectangle of any texel is fine.
TEST(Perturbation, ShiftOnANonCyclicTexelIsRefused) {
    Scene scene = gridScene(2, {7, false, false, true});
    scene.file = "grid.toml";
    const std::string shift = errorOf(scene);
    EXPECT_NE(shift.find("grid.toml: surface[0].perturb.shift: texel 't0' is not cyclic"), std::string::npos) << shift;
    scene.surfaces[0].perturb = {};
    scene.surfaces[0].subrect = std::array<double, 4>{0.5, 0, 1.5, 1};
    EXPECT_NE(errorOf(scene).find("surface[0].subrect"), std::string::npos) << errorOf(scene);
    scene.surfaces[0].subrect = std::array<double, 4>{0.25, 0, 0.75, 1};
    EXPECT_EQ(errorOf(scene), "no error");
}

// A sub-rectangle shows that part of the volume stretched over the face: the box [0, ½]²×[0, ½]
// seen through subrect [0, 0, ½, ½] is the slab [0, 1]²×[0, ½] seen whole (the reference renderer,
// both modes).
TEST(Perturbation, SubrectStretchesThatPartOverTheFace) {
    for (const ReferenceMode mode : {ReferenceMode::Embedded, ReferenceMode::Deformed}) {
        ReferenceOptions options;
        options.spp = 1;
        options.mode = mode;
        Scene part = gridScene(2, {});
        part.texels[0].sourceData = box({0, 0, 0}, {0.5f, 0.5f, 0.5f});
        part.surfaces[0].subrect = std::array<double, 4>{0, 0, 0.5, 0.5};
        Scene whole = gridScene(2, {});
        whole.texels[0].sourceData = box({0, 0, 0}, {1, 1, 0.5f});
        const ImageComparison c = compareImages(referenceQuiet(part, options).image, referenceQuiet(whole, options).image);
        EXPECT_LT(c.rmse, 0.01) << "worst (" << c.worstX << ", " << c.worstY << ") " << c.worstError;
        Scene unclipped = part;
        unclipped.surfaces[0].subrect.reset();
        EXPECT_GT(compareImages(referenceQuiet(unclipped, options).image, referenceQuiet(whole, options).image).rmse, 0.02);
    }
}

// The opaque-cube comparison of reference_test (TexelRenderOfOpaqueCubesMatchesTheReference) with
// the cube off the cell's centre, every perturbation on and a sub-rectangle that crosses the
// volume's edge: the texel render and the reference agree within the same tolerances as without.
TEST(Perturbation, TexelRenderMatchesTheReference) {
    // Voxels [1, 4) × [2, 6) × [2, 6) of 8³, the faces moved in by 1/1024 (the sampler's voxels
    // are half-open).
    constexpr float e = 1.0f / 1024;
    const auto cube = box({0.125f + e, 0.25f + e, 0.25f + e}, {0.5f - e, 0.75f - e, 0.75f - e});
    vtex::sampler::SampleOptions sampling;
    sampling.resolution = 8;
    sampling.solid = vtex::sampler::SolidMode::On;
    vtex::NullProgress progress;
    const auto volume = vtex::sampler::sampleMesh(*cube, sampling, progress);
    auto cyclic = std::make_shared<vtex::octree::Octree>(vtex::octree::buildOctree(volume, {}, progress));
    // Cyclic, so that the shift is allowed: the sampler takes a solid interior or periodic
    // boundaries, not both, and a cube clear of the volume's sides samples the same either way.
    cyclic->info.source.cyclic = true;
    const std::shared_ptr<const vtex::octree::Octree> tree = cyclic;

    Scene scene = baseScene(Eigen::Vector3d(-1.3, -2.4, 2.6), Eigen::Vector3d(1, 1, 0.3), 35, 64);
    const auto texel = addTexel(scene, tree, 16);
    scene.texels[texel].sourceData = cube;
    addSurface(scene, gridMesh(0, 0, 2, 2, 0, 2), texel, 1.0);
    scene.surfaces[0].subrect = std::array<double, 4>{0.125, 0, 1.125, 1};
    // The first seed under which no face cuts its cube at its sides: a cube cut by a cell's side
    // is an open mesh in the reference but a solid block in the volume, a difference of the two
    // models (the paper's note 10: a perturbed texel cuts what straddles its sides), not of the
    // map. The shifts stay random fractions of the volume.
    const Eigen::Vector2d cubeLo(0.125, 0.25), cubeHi(0.5, 0.75);
    const auto cutsNoCube = [&](std::uint64_t seed) {
        for (std::uint64_t face = 0; face < 4; ++face) {
            Eigen::Vector2d lo, hi;
            makeCellMap(scene.surfaces[0].placing(0), drawFaceTransform({seed, true, true, true}, face)).bounds(lo, hi);
            for (int kx = -2; kx <= 2; ++kx)
                for (int ky = -2; ky <= 2; ++ky) {
                    const Eigen::Vector2d a = cubeLo + Eigen::Vector2d(kx, ky), b = cubeHi + Eigen::Vector2d(kx, ky);
                    const bool inside = (a.array() >= lo.array()).all() && (b.array() <= hi.array()).all();
                    const bool outside = (b.array() <= lo.array()).any() || (a.array() >= hi.array()).any();
                    if (!inside && !outside) return false;
                }
        }
        return true;
    };
    std::uint64_t seed = 0;
    while (!cutsNoCube(seed)) ++seed;
    scene.surfaces[0].perturb = {seed, true, true, true};
    RenderOptions texelOptions;
    texelOptions.spp = 16;
    texelOptions.lodBias = -8;
    texelOptions.hybrid = false;
    const Image texelImage = renderQuiet(scene, texelOptions).image;
    ReferenceOptions referenceOptions;
    referenceOptions.spp = 16;
    const Image referenceImage = referenceQuiet(scene, referenceOptions).image;

    double coverage = 0, coverageDifference = 0, meanTexel = 0, meanReference = 0;
    for (std::size_t i = 0; i < texelImage.pixels(); ++i) {
        coverage += referenceImage.rgba[4 * i + 3];
        coverageDifference += std::abs(texelImage.rgba[4 * i + 3] - referenceImage.rgba[4 * i + 3]);
        for (std::size_t k = 0; k < 3; ++k) {
            meanTexel += texelImage.rgba[4 * i + k];
            meanReference += referenceImage.rgba[4 * i + k];
        }
    }
    ASSERT_GT(coverage, 0.25 * double(texelImage.pixels()));
    const ImageComparison c = compareImages(texelImage, referenceImage);
    std::cout << "perturbed opaque cubes (seed " << seed << "): RMSE " << c.rmse << ", coverage difference "
              << coverageDifference / double(texelImage.pixels()) << ", mean ratio " << meanTexel / meanReference << "\n";
    EXPECT_LT(coverageDifference / double(texelImage.pixels()), 0.005);
    EXPECT_LT(c.rmse, 0.2) << "worst (" << c.worstX << ", " << c.worstY << ") " << c.worstError;
    EXPECT_GT(meanTexel / meanReference, 0.5);
    EXPECT_LT(meanTexel / meanReference, 1.1);
    // And the perturbation is there: the unperturbed reference is another picture.
    Scene unperturbed = scene;
    unperturbed.surfaces[0].perturb = {};
    EXPECT_GT(compareImages(referenceQuiet(unperturbed, referenceOptions).image, referenceImage).rmse, 0.05);
}
