// The octree issue's measure (issue 13): each level's transmittance against its source mesh,
// along chords of the whole texel and over multi-voxel beams of the level, on a texel of random
// opaque discs. Small discs placed and turned uniformly at random are a Poisson medium, whose
// transmittance is exactly exponential in its mean extinction n·πr²/2: levels whose voxels hold
// many discs must measure an error near zero, and the levels finer than a disc, where a voxel
// across an opaque disc lets e^−1 through, must measure it too transparent. Two independent
// methods meet: the sampled volume marched exactly, and the discs ray-traced.
#include "fixtures.h"

#include <vtex/octree/chord_transmittance.h>
#include <vtex/octree/octree.h>
#include <vtex/render/source_visibility.h>
#include <vtex/sampler/sampler.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <numbers>
#include <random>

namespace {

// `count` opaque discs of radius `r`, centres uniform in [r, 1 − r]³, normals uniform on the
// sphere, each a fan of 16 triangles.
vtex::ingest::TriangleMesh randomDiscs(int count, float r, std::uint32_t seed) {
    vtex::ingest::TriangleMesh mesh;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0, 1);
    constexpr int kSides = 16;
    for (int d = 0; d < count; ++d) {
        const Eigen::Vector3f c(r + (1 - 2 * r) * unit(rng), r + (1 - 2 * r) * unit(rng), r + (1 - 2 * r) * unit(rng));
        const float z = 2 * unit(rng) - 1, phi = 2 * std::numbers::pi_v<float> * unit(rng);
        const Eigen::Vector3f n(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
        const Eigen::Vector3f u = n.unitOrthogonal(), v = n.cross(u);
        const auto first = std::uint32_t(mesh.positions.size());
        mesh.positions.push_back(c);
        mesh.normals.push_back(n);
        for (int k = 0; k < kSides; ++k) {
            const float a = 2 * std::numbers::pi_v<float> * float(k) / kSides;
            mesh.positions.push_back(c + r * (std::cos(a) * u + std::sin(a) * v));
            mesh.normals.push_back(n);
            mesh.triangles.push_back({first, first + 1 + std::uint32_t(k), first + 1 + std::uint32_t((k + 1) % kSides)});
        }
    }
    return mesh;
}

}  // namespace

// Closed form: a texel of constant density seen against nothing. Every chord of a beam lets
// through exp(−ρÂℓ) and misses the (absent) mesh, so a beam's error is exp(−ρÂℓ) − 1 with no
// spread and no noise, and −ln(1 + error)/ℓ is the same extinction at every level, ℓ being four
// voxels of the level, at most 0.5.
TEST(BeamTransmittance, AConstantTexelMeasuresItsOwnExponential) {
    const auto tree = vtex::render::test::makeOctree(5, [](int, int, int) { return std::optional(vtex::render::test::sphereVoxel(2.0f)); });
    const auto beams = vtex::octree::measureBeamTransmittance(*tree, [](const auto&, const auto&) { return true; });
    ASSERT_EQ(beams.size(), 6u);
    const auto extinction = [&](std::size_t l) { return -std::log1p(beams[l].mean) / std::min(4 * std::ldexp(1.0, -int(l)), 0.5); };
    for (std::size_t l = 0; l < beams.size(); ++l) {
        EXPECT_LT(beams[l].mean, 0.0);
        EXPECT_NEAR(beams[l].meanAbs, -beams[l].mean, 1e-12);
        EXPECT_NEAR(beams[l].p95Abs, -beams[l].mean, 1e-9);
        EXPECT_EQ(beams[l].noise, 0.0);
        EXPECT_NEAR(extinction(l), extinction(0), 1e-9 * extinction(0)) << "level " << l;
    }
}

TEST(BeamTransmittance, APoissonMediumOfDiscsIsExponentialCoarseAndTooTransparentFine) {
    // 12 000 discs of radius 0.01: mean extinction n·πr²/2 ≈ 1.9 per unit length, a transmittance
    // of about 0.3 across the texel's mean chord; a disc spans 1.3 voxels of level 6.
    const float r = 0.01f;
    const vtex::ingest::TriangleMesh mesh = randomDiscs(12000, r, 7);
    vtex::sampler::SampleOptions sampling;
    sampling.resolution = 64;
    sampling.bounds = vtex::sampler::BoundsMode::Unit;
    vtex::NullProgress quiet;
    const vtex::octree::SparseVolume volume = vtex::sampler::sampleMesh(mesh, sampling, quiet);
    const vtex::octree::Octree tree = vtex::octree::buildOctree(volume, {}, quiet);
    const vtex::render::SourceVisibility visibility(mesh, tree.info.source);
    const auto visible = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return visibility.visible(a, b); };
    const auto chords = vtex::octree::measureChordTransmittance(tree, visible);
    const auto beams = vtex::octree::measureBeamTransmittance(tree, visible);
    ASSERT_EQ(chords.size(), 7u);
    ASSERT_EQ(beams.size(), 7u);
    for (std::size_t l = 0; l < chords.size(); ++l)
        std::cout << "level " << l << ": chords " << chords[l].error() << ", beams mean " << beams[l].mean << " |mean| "
                  << beams[l].meanAbs << " p95 " << beams[l].p95Abs << " (noise " << beams[l].noise << ")\n";
    // Levels 0–3: a voxel (≥ 0.125) holds hundreds of discs, and the model must be exponential
    // within 0.03 of transmittance, about 5 % of the extinction (measured: chords −0.012 …
    // −0.006, beams' mean +0.003 … +0.023; what is left is the SGGX filter's mean of S, whose
    // projected area √(ωᵀS̄ω) exceeds the mean of the discs' own by Jensen, and this one
    // realisation of the medium), where the bush's coarse levels measure 0.11–0.19. A beam's
    // spread stays within its own sampling noise plus 0.02.
    for (std::size_t l = 0; l <= 3; ++l) {
        EXPECT_LT(std::abs(chords[l].error()), 0.03) << "level " << l;
        EXPECT_LT(std::abs(beams[l].mean), 0.03) << "level " << l;
        EXPECT_LT(beams[l].meanAbs, beams[l].noise + 0.02) << "level " << l;
        EXPECT_LT(beams[l].p95Abs, 2.5 * beams[l].noise + 0.03) << "level " << l;
    }
    // Level 6: a voxel is smaller than a disc; where one crosses it the voxel lets e^−1 through
    // (the finest levels are too transparent, docs/render.md's hybrid). Measured along whole
    // chords, beyond their noise.
    EXPECT_GT(chords[6].error(), 0.031);
    // The p95 of the finest level's beams is well above its noise: the measure sees the error
    // that a mean over the texel would hide.
    EXPECT_GT(beams[6].p95Abs, 3 * beams[6].noise);
}

namespace {

std::uint64_t splitmix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

std::shared_ptr<const vtex::octree::Octree> makeOctreeOf(int levels, float density) {
    return vtex::render::test::makeOctree(levels, [density](int, int, int) { return std::optional(vtex::render::test::sphereVoxel(density)); });
}

// A uniform number in [0, 1) that is a function of the segment alone.
double segmentHash(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    std::uint64_t h = 0;
    for (int k = 0; k < 3; ++k) {
        h = splitmix(h ^ std::bit_cast<std::uint64_t>(a[k]));
        h = splitmix(h ^ std::bit_cast<std::uint64_t>(b[k]));
    }
    return double(h >> 11) * 0x1.0p-53;
}

// `clusters` clumps of `perCluster` opaque discs of radius `r`, each clump's discs within
// `spread` of its centre: leaves of bushes, correlated where randomDiscs is not.
vtex::ingest::TriangleMesh clusteredDiscs(int clusters, int perCluster, float spread, float r, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0, 1);
    vtex::ingest::TriangleMesh mesh;
    for (int c = 0; c < clusters; ++c) {
        const float margin = spread + r;
        const Eigen::Vector3f centre(margin + (1 - 2 * margin) * unit(rng), margin + (1 - 2 * margin) * unit(rng),
                                     margin + (1 - 2 * margin) * unit(rng));
        vtex::ingest::TriangleMesh clump = randomDiscs(perCluster, r, rng());
        const auto first = std::uint32_t(mesh.positions.size());
        // randomDiscs fills [r, 1 − r]³: squeeze it into the clump's cube.
        for (Eigen::Vector3f& p : clump.positions) p = centre + 2 * spread * (p - Eigen::Vector3f::Constant(0.5f));
        // Squeezing scales the discs too; grow them back to radius r about their centres (the
        // first vertex of each fan).
        constexpr std::size_t kFan = 17;
        for (std::size_t d = 0; d + kFan <= clump.positions.size(); d += kFan)
            for (std::size_t k = 1; k < kFan; ++k)
                clump.positions[d + k] = clump.positions[d] + (clump.positions[d + k] - clump.positions[d]) / (2 * spread);
        mesh.positions.insert(mesh.positions.end(), clump.positions.begin(), clump.positions.end());
        mesh.normals.insert(mesh.normals.end(), clump.normals.begin(), clump.normals.end());
        for (auto t : clump.triangles) mesh.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
    }
    return mesh;
}

// clusteredDiscs sampled at `resolution`³ into the unit cube and built, with the visibility of
// segments through the discs.
struct DiscTexel {
    vtex::ingest::TriangleMesh mesh;
    vtex::octree::Octree tree;
    std::unique_ptr<const vtex::render::SourceVisibility> visibility;
    bool visible(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const { return visibility->visible(a, b); }
};
std::unique_ptr<DiscTexel> clusteredDiscTexel(int clusters, int perCluster, std::uint32_t seed, int resolution) {
    auto texel = std::make_unique<DiscTexel>();
    texel->mesh = clusteredDiscs(clusters, perCluster, 0.06f, 0.012f, seed);
    vtex::sampler::SampleOptions sampling;
    sampling.resolution = resolution;
    sampling.bounds = vtex::sampler::BoundsMode::Unit;
    vtex::NullProgress quiet;
    texel->tree = vtex::octree::buildOctree(vtex::sampler::sampleMesh(texel->mesh, sampling, quiet), {}, quiet);
    texel->visibility = std::make_unique<const vtex::render::SourceVisibility>(texel->mesh, texel->tree.info.source);
    return texel;
}

}  // namespace

// Closed forms for the chords of the shell fit. Their directions are cosine-weighted over zenith
// angles up to 80° and each runs from the top face to the floor, so its length is 1/μ and the
// mean length E[1/μ] = 2/(1 + cos 80°); a thin constant medium (ρ = 1e-4) lets through 1 − ρ·E[L]
// (16384 chords: a standard error of 0.007 in E[L]).
// A "mesh" that hides each unit-cube piece of a chord with probability 1 − e^(−κℓ), independently,
// is a Poisson medium of extinction κ: the fitted scale of a constant texel of density ρ is κ/ρ,
// within the noise of 4096 such draws.
TEST(ShellChords, FollowTheirClosedForms) {
    const double cos80 = std::cos(80 * std::numbers::pi / 180);
    const auto thin = makeOctreeOf(1, 1e-4f);
    const auto thinFit = vtex::octree::measureShellChords(*thin, [](const auto&, const auto&) { return true; }, 1, 1.0, 1, 16384);
    EXPECT_NEAR((1 - thinFit.transmittance) / 1e-4, 2 / (1 + cos80), 0.03);
    EXPECT_EQ(thinFit.visibility, 1.0);
    const double rho = 2, kappa = 1.3;
    const auto constant = makeOctreeOf(3, float(rho));
    const auto poisson = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
        return segmentHash(a, b) < std::exp(-kappa * (b - a).norm());
    };
    const auto fits = vtex::octree::fitShellChords(*constant, poisson);
    ASSERT_EQ(fits.size(), 4u);
    for (std::size_t l = 0; l < fits.size(); ++l) {
        EXPECT_NEAR(fits[l].scale, kappa / rho, 0.05 * kappa / rho) << "level " << l;
        EXPECT_NEAR(fits[l].scale, fits[0].scale, 1e-9) << "level " << l;  // one medium, one answer
    }
}

// The fit on a texel whose leaves cluster, as a bush's do: its coarse levels spread each clump
// over whole voxels and are too opaque, its finest too transparent; once fitted, every level
// lets through what the discs do, on shell chords it was not fitted on, within their noise.
TEST(ShellChords, AFittedLevelLetsThroughWhatTheMeshDoesOnOtherChords) {
    const auto discs = clusteredDiscTexel(40, 120, 11, 64);
    const vtex::octree::Octree& tree = discs->tree;
    const auto visible = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return discs->visible(a, b); };
    constexpr int kChords = 16384;
    const auto fits = vtex::octree::fitShellChords(tree, visible, 1, kChords);
    ASSERT_EQ(fits.size(), 7u);
    for (std::size_t l = 0; l < fits.size(); ++l) {
        const auto other = vtex::octree::measureShellChords(tree, visible, std::uint32_t(l), fits[l].scale, 1, kChords, 2);
        const auto unfitted = vtex::octree::measureShellChords(tree, visible, std::uint32_t(l), 1.0, 1, kChords, 2);
        std::cout << "level " << l << ": scale " << fits[l].scale << ", error on other chords " << unfitted.error()
                  << " before, " << other.error() << " after\n";
        // The fit's error on its own chords is 0; on others it is the difference of two means of
        // T − v over 16384 chords, each with a standard error ≤ 1/√16384 = 0.008 (|T − v| ≤ 1).
        EXPECT_LT(std::abs(other.error()), 0.03) << "level " << l;
    }
    EXPECT_LT(fits[0].scale, 0.9);  // clumps spread over the whole texel: too opaque
    EXPECT_LT(vtex::octree::measureShellChords(tree, visible, 0, 1.0, 1, kChords, 2).error(), -0.1);
    EXPECT_GT(fits[6].scale, 1.0);  // a voxel across one disc: too transparent
}

// A τ per level (the fitted levels' figures in `vtex inspect --source`) walks the same chords as
// one τ: level l with tauPerLevel[l] gives what the one-τ measure gives at τ = tauPerLevel[l],
// bit for bit, and only the levels given are measured.
TEST(ChordTransmittance, ATauPerLevelIsTheOneTauMeasureAtThatTau) {
    const auto discs = clusteredDiscTexel(20, 60, 5, 32);
    const vtex::octree::Octree& tree = discs->tree;
    const auto visible = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return discs->visible(a, b); };
    const std::vector<double> taus = {0.3, 1.7, 0.9, 2.5};
    const auto perLevel = vtex::octree::measureChordTransmittance(tree, visible, taus, 512, 3);
    ASSERT_EQ(perLevel.size(), taus.size());
    for (std::size_t l = 0; l < taus.size(); ++l) {
        const auto one = vtex::octree::measureChordTransmittance(tree, visible, taus[l], 512, 3);
        EXPECT_EQ(perLevel[l].visibility, one[l].visibility) << "level " << l;
        EXPECT_EQ(perLevel[l].transmittance, one[l].transmittance) << "level " << l;
    }
    // A larger τ lets less through on the same chords.
    EXPECT_LT(perLevel[3].transmittance, vtex::octree::measureChordTransmittance(tree, visible, 0.1, 512, 3)[3].transmittance);
}

namespace {

// A Poisson "mesh" of extinction κ for the lit-fraction measures: a segment's first hit at an
// exponential depth drawn from the segment's hash, so a segment is seen through with
// probability e^(−κℓ) and the same segment always gives the same answer.
vtex::octree::ChordFirstHit poissonHit(double kappa) {
    return [kappa](const Eigen::Vector3d& a, const Eigen::Vector3d& b) -> std::optional<double> {
        const double s = -std::log(segmentHash(a, b)) / (kappa * (b - a).norm());
        return s <= 1 ? std::optional<double>(s) : std::nullopt;
    };
}
vtex::octree::ChordVisibility poissonVisible(double kappa) {
    return [hit = poissonHit(kappa)](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return !hit(a, b); };
}

}  // namespace

// The lit fractions (octree::measureLitFractions) of a Poisson medium of extinction κ over a
// constant texel whose fitted density is κ: the mesh's first hits lie where the march's weight
// T·σ puts the volume's points (both exponential in depth at rate κ), and a Poisson medium lets
// a ray toward the light through with probability e^(−κℓ), as the volume does. So every camera
// and shadow level lights what the "mesh" sees as often as it does, within the noise of 16384
// chords (each fraction's standard error ≤ 0.5/√(chords seen), here ≈ 0.005; bound ≈ 4σ of the
// difference); and in a constant texel every level gives the same transmittance from the same
// point, to rounding.
TEST(LitFractions, APoissonMediumIsLitAsItsExponentialVolume) {
    const double rho = 2, kappa = 1.3;
    const auto constant = makeOctreeOf(3, float(rho));
    const auto hit = poissonHit(kappa);
    const auto visible = poissonVisible(kappa);
    const std::vector<double> scales(4, kappa / rho);
    const auto lit = vtex::octree::measureLitFractions(*constant, hit, visible, 1, scales, 3, 16384);
    ASSERT_EQ(lit.volume.size(), 4u);
    EXPECT_GT(lit.seen, 8000u);
    EXPECT_GT(lit.mesh, 0.2);
    EXPECT_LT(lit.mesh, 0.8);
    EXPECT_LT(lit.meshStandardError(), 0.006);
    for (std::size_t c = 0; c < 4; ++c)
        for (std::size_t l = 0; l < 4; ++l) {
            if (l + 1 < c) {
                EXPECT_TRUE(std::isnan(lit.volume[c][l])) << c << " " << l;  // never narrower than the camera's cone
                continue;
            }
            EXPECT_NEAR(lit.error(c, l), 0, 0.025) << "camera " << c << " shadow " << l;
            EXPECT_NEAR(lit.volume[c][l], lit.volume[3][3], 1e-9) << "camera " << c << " shadow " << l;
        }
    // A texel lit less than the mesh would be caught: the same chords through twice the density.
    const std::vector<double> dense(4, 2 * kappa / rho);
    EXPECT_LT(vtex::octree::measureLitFractions(*constant, hit, visible, 1, dense, 3, 16384).error(3, 3), -0.05);
}

// A lit-fraction measure's own shares (the renderer's queries from a lit voxel take its own
// voxel's density times 1 − its own share): shares of 0 change no bit; a share above 0 at one
// shadow level lights more at that level only, and the more the larger it is.
TEST(LitFractions, AShadowRayTakesItsOwnVoxelLessItsShare) {
    const auto constant = makeOctreeOf(3, 2.0f);
    const auto hit = poissonHit(1.3);
    const auto visible = poissonVisible(1.3);
    const std::vector<double> scales(4, 0.65);
    const auto measure = [&](const std::vector<double>& shares) {
        return vtex::octree::measureLitFractions(*constant, hit, visible, 1, scales, 3, 1024, 1, {}, shares);
    };
    const auto none = measure({}), zeros = measure({0, 0, 0, 0}), half = measure({0, 0, 0, 0.5}), all = measure({0, 0, 0, 1});
    for (std::size_t c = 0; c < 4; ++c)
        for (std::size_t l = c == 0 ? 0 : c - 1; l < 4; ++l) {
            EXPECT_EQ(zeros.volume[c][l], none.volume[c][l]) << c << " " << l;
            if (l < 3) {
                EXPECT_EQ(half.volume[c][l], none.volume[c][l]) << c << " " << l;
            } else {
                EXPECT_GT(half.volume[c][l], none.volume[c][l] + 0.005) << c;
                EXPECT_GT(all.volume[c][l], half.volume[c][l] + 0.005) << c;
            }
        }
}

// Pairs left out of a lit-fraction measure (its `wanted` argument, which the renderer uses to skip
// fine shadow levels' walks) are NaN; the others are what the whole measure gives, bit for bit.
TEST(LitFractions, PairsLeftOutAreNotMeasuredAndTheOthersDoNotChange) {
    const auto constant = makeOctreeOf(3, 2.0f);
    const auto hit = poissonHit(1.3);
    const auto visible = poissonVisible(1.3);
    const std::vector<double> scales(4, 0.65);
    const auto all = vtex::octree::measureLitFractions(*constant, hit, visible, 1, scales, 3, 1024);
    const vtex::octree::LitPairs wanted = [](std::size_t c, std::size_t l) { return l <= 1 || l + 1 == c; };
    const auto some = vtex::octree::measureLitFractions(*constant, hit, visible, 1, scales, 3, 1024, 1, wanted);
    ASSERT_EQ(some.volume.size(), all.volume.size());
    EXPECT_EQ(some.mesh, all.mesh);
    std::size_t measured = 0;
    for (std::size_t c = 0; c < all.volume.size(); ++c)
        for (std::size_t l = 0; l < all.volume[c].size(); ++l) {
            if (std::isnan(all.volume[c][l]) || !wanted(c, l)) {
                EXPECT_TRUE(std::isnan(some.volume[c][l])) << c << " " << l;
                continue;
            }
            EXPECT_EQ(some.volume[c][l], all.volume[c][l]) << c << " " << l;
            ++measured;
        }
    EXPECT_EQ(measured, 6u);  // camera levels 0 and 1: shadow levels 0–1; 2: 1; 3: 2
}
