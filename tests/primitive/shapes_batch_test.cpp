// Ellipsoid::shapesFromS against shapeFromS, bit for bit: the octree build packs its parents'
// primitives from the batch, and every .vto must stay what the one-at-a-time path made.
#include "shapes.h"

#include <vtex/primitive/ellipsoid.h>
#include <vtex/primitive/packing.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <vector>

namespace vtex::primitive {
namespace {

bool sameBits(const EllipsoidShape& a, const EllipsoidShape& b) {
    return std::memcmp(a.basis.data(), b.basis.data(), sizeof(double) * 9) == 0 &&
           std::memcmp(a.semiAxes.data(), b.semiAxes.data(), sizeof(double) * 3) == 0 &&
           std::memcmp(&a.exactMeanArea, &b.exactMeanArea, sizeof(double)) == 0;
}

// Stored primitives (S unpacked from the float form, as the build reads them) from spheres to
// needles and discs at the axis-ratio floor, means of one to eight of them (a parent's filter),
// random symmetric matrices (indefinite ones among them), and the matrices shapeFromS refuses.
std::vector<Mat3> testMatrices() {
    std::mt19937 rng(2026);
    std::uniform_real_distribution<double> logRatio(-4.5, 0), unit(0, 1), entry(-1, 1);
    const auto stored = [&] {
        Vec3 axes(1, std::pow(10.0, logRatio(rng)), std::pow(10.0, logRatio(rng)));
        if (unit(rng) < 0.1) axes[2] = axes[1];                     // needle or disc
        if (unit(rng) < 0.05) axes = Vec3::Constant(1 + 1e-3 * unit(rng));  // near-sphere: the Gauss rule
        const PackedPrimitive p = pack(Ellipsoid::fromAxes(test::randomRotation(rng), axes));
        return unpackS(p.rotation, p.sigma).matrix();
    };
    std::vector<Mat3> matrices;
    for (int n = 0; n < 20000; ++n) {
        matrices.push_back(stored());
        Mat3 mean = Mat3::Zero();
        for (int c = 0; c <= n % 8; ++c) mean += unit(rng) * stored();
        matrices.push_back(mean);
        Mat3 m;
        for (int j = 0; j < 3; ++j)
            for (int i = j; i < 3; ++i) m(i, j) = m(j, i) = entry(rng);
        matrices.push_back(m);
    }
    matrices.push_back(Mat3::Zero());
    matrices.push_back(Mat3::Identity());
    matrices.push_back(-Mat3::Identity());
    Mat3 notFinite = Mat3::Identity();
    notFinite(1, 1) = std::numeric_limits<double>::quiet_NaN();
    matrices.push_back(notFinite);
    return matrices;
}

TEST(ShapesFromS, AreShapeFromSBitForBit) {
    const std::vector<Mat3> matrices = testMatrices();
    // Batches of every length up to nine: full groups of four, partial ones, refused matrices inside.
    std::size_t begin = 0;
    for (std::size_t length = 1; begin < matrices.size(); length = length % 9 + 1) {
        const std::size_t count = std::min(length, matrices.size() - begin);
        std::vector<std::optional<EllipsoidShape>> batch(count);
        Ellipsoid::shapesFromS(std::span(matrices).subspan(begin, count), batch);
        for (std::size_t i = 0; i < count; ++i) {
            const auto single = Ellipsoid::shapeFromS(matrices[begin + i]);
            ASSERT_EQ(single.has_value(), batch[i].has_value()) << matrices[begin + i];
            if (single) {
                ASSERT_TRUE(sameBits(*single, *batch[i])) << matrices[begin + i];
            }
        }
        begin += count;
    }
}

TEST(ShapesFromS, RefusesMismatchedSizes) {
    const std::vector<Mat3> matrices(3, Mat3::Identity());
    std::vector<std::optional<EllipsoidShape>> shapes(2);
    EXPECT_THROW(Ellipsoid::shapesFromS(matrices, shapes), std::invalid_argument);
}

}  // namespace
}  // namespace vtex::primitive
