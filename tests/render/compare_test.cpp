// `vtex compare` and its metrics: zero error against itself, the known RMSE and PSNR of a
// known perturbation, SSIM's defining properties, and exit 3 for images that cannot be compared.
#include "run_vtex.h"

#include <vtex/render/compare.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <random>

namespace fs = std::filesystem;
using vtex::render::compareImages;
using vtex::render::Image;
using vtex::test::runVtex;

namespace {

Image noiseImage(int w, int h, unsigned seed) {
    Image image(w, h, false);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> value(0.1f, 0.9f);
    for (std::size_t p = 0; p < image.pixels(); ++p) {
        for (int c = 0; c < 3; ++c) image.rgba[4 * p + c] = value(rng);
        image.rgba[4 * p + 3] = 1;
    }
    return image;
}

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "compare";
    fs::create_directories(dir);
    return dir / name;
}

TEST(Compare, AnImageAgainstItselfHasNoError) {
    const Image a = noiseImage(37, 23, 1);
    const auto c = compareImages(a, a);
    EXPECT_EQ(c.rmse, 0);
    EXPECT_TRUE(std::isinf(c.psnr));
    EXPECT_NEAR(c.ssim, 1.0, 1e-12);
    EXPECT_EQ(c.worstError, 0);
}

TEST(Compare, AConstantOffsetGivesTheKnownRmseAndPsnr) {
    // Every channel of every pixel off by δ = 0.01: RMSE = δ, PSNR = 20·log₁₀(1/δ) = 40 dB.
    const Image a = noiseImage(32, 32, 2);
    Image b = a;
    for (std::size_t p = 0; p < b.pixels(); ++p)
        for (int c = 0; c < 3; ++c) b.rgba[4 * p + c] += 0.01f;
    const auto c = compareImages(a, b);
    EXPECT_NEAR(c.rmse, 0.01, 1e-6);
    EXPECT_NEAR(c.psnr, 40.0, 1e-3);
    EXPECT_LT(c.ssim, 1.0);
    EXPECT_GT(c.ssim, 0.99) << "a small constant shift barely changes structure";
}

TEST(Compare, OneBadPixelIsTheWorstAndSetsTheRmse) {
    Image a(10, 10, false), b(10, 10, false);
    b.rgba[4 * (7 * 10 + 3) + 1] = 0.6f;  // pixel (3, 7), green only
    const auto c = compareImages(a, b);
    EXPECT_EQ(c.worstX, 3);
    EXPECT_EQ(c.worstY, 7);
    EXPECT_NEAR(c.worstError, 0.6 / std::sqrt(3.0), 1e-6);
    EXPECT_NEAR(c.rmse, std::sqrt(0.36 / 300), 1e-7);
}

TEST(Compare, SsimIsSymmetricBoundedAndFallsWithStructuralNoise) {
    const Image a = noiseImage(48, 48, 3);
    const Image b = noiseImage(48, 48, 4);
    Image half = a;
    for (std::size_t p = 0; p < half.pixels(); ++p)
        for (int c = 0; c < 3; ++c) half.rgba[4 * p + c] = 0.5f * (a.rgba[4 * p + c] + b.rgba[4 * p + c]);
    const double ab = compareImages(a, b).ssim, ba = compareImages(b, a).ssim;
    EXPECT_NEAR(ab, ba, 1e-12);
    EXPECT_LT(ab, 0.2) << "independent noise shares no structure";
    EXPECT_GT(ab, -1.0);
    EXPECT_GT(compareImages(a, half).ssim, ab);
    EXPECT_LT(compareImages(a, half).ssim, 1.0);
}

TEST(Compare, CommandLineReportsTheMetricsAndWritesAHeatMap) {
    const Image a = noiseImage(16, 12, 5);
    Image b = a;
    for (std::size_t p = 0; p < b.pixels(); ++p) b.rgba[4 * p] += 0.1f;  // red off by 0.1
    vtex::render::writeExr(a, scratch("a.exr"));
    vtex::render::writeExr(b, scratch("b.exr"));
    const auto r = runVtex({"compare", scratch("a.exr").string(), scratch("b.exr").string(), "--json", "--diff",
                            scratch("heat.png").string()});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j["rmse"].get<double>(), 0.1 / std::sqrt(3.0), 1e-6);
    EXPECT_NEAR(j["psnr"].get<double>(), -10 * std::log10(0.01 / 3), 1e-3);
    EXPECT_TRUE(fs::file_size(scratch("heat.png")) > 0);

    const auto self = runVtex({"compare", scratch("a.exr").string(), scratch("a.exr").string(), "--json"});
    ASSERT_EQ(self.exitStatus, 0) << self.err;
    EXPECT_EQ(nlohmann::json::parse(self.out)["rmse"].get<double>(), 0);
    EXPECT_TRUE(nlohmann::json::parse(self.out)["psnr"].is_null());
}

TEST(Compare, ImagesThatCannotBeComparedAreBadInput) {
    vtex::render::writeExr(noiseImage(16, 12, 6), scratch("small.exr"));
    vtex::render::writeExr(noiseImage(17, 12, 7), scratch("wide.exr"));
    auto r = runVtex({"compare", scratch("small.exr").string(), scratch("wide.exr").string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("size"), std::string::npos) << r.err;
    EXPECT_EQ(vtex::test::lineCount(r.err), 1u) << r.err;

    std::ofstream(scratch("not.exr")) << "not an image";
    r = runVtex({"compare", scratch("small.exr").string(), scratch("not.exr").string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("not.exr"), std::string::npos) << r.err;
    r = runVtex({"compare", scratch("small.exr").string(), scratch("missing.exr").string()});
    EXPECT_EQ(r.exitStatus, 3);

    // Same size, luminance only: not the same channels.
    {
        std::vector<float> y(16 * 12, 0.5f);
        Imf::Header header(16, 12);
        header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
        Imf::OutputFile out(scratch("grey.exr").c_str(), header);
        Imf::FrameBuffer frame;
        frame.insert("Y", Imf::Slice(Imf::FLOAT, (char*)y.data(), sizeof(float), sizeof(float) * 16));
        out.setFrameBuffer(frame);
        out.writePixels(12);
    }
    r = runVtex({"compare", scratch("small.exr").string(), scratch("grey.exr").string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("channel sets differ"), std::string::npos) << r.err;
}

}  // namespace
