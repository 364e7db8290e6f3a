// `vtex compare` and its metrics: zero error against itself, the known RMSE and PSNR of a
// known perturbation, SSIM's defining properties, hand-derived channel biases and 4×4/pixel error
// splits (a full-block image and one with border blocks), and exit 3 for images that cannot be
// compared.
#include "run_vtex.h"

#include <vtex/render/compare.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
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

// An 8×4 image with structure in every channel, so a split that mixed up a's and b's block means
// would not come out zero by luck. Channel means: R 0.1 + 0.05·3.5 = 0.275, G 0.2 + 0.1·1.5 = 0.35,
// B half 0.5 and half 0.1 = 0.3.
Image rampImage() {
    Image image(8, 4, false);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 8; ++x) {
            float* p = &image.rgba[4 * std::size_t(y * 8 + x)];
            p[0] = 0.1f + 0.05f * float(x);
            p[1] = 0.2f + 0.1f * float(y);
            p[2] = (x + y) % 2 == 0 ? 0.5f : 0.1f;
            p[3] = 1;
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

TEST(Compare, AConstantOffsetIsAllBiasAndCoarseError) {
    // a = b + δ everywhere: bias δ / mean(b) per channel, the whole error at the 4×4 scale.
    const Image b = rampImage();
    Image a = b;
    for (std::size_t p = 0; p < a.pixels(); ++p)
        for (int c = 0; c < 3; ++c) a.rgba[4 * p + c] += 0.05f;
    const auto c = compareImages(a, b);
    EXPECT_NEAR(c.meanB[0], 0.275, 1e-7);
    EXPECT_NEAR(c.meanB[1], 0.35, 1e-7);
    EXPECT_NEAR(c.meanB[2], 0.3, 1e-7);
    EXPECT_NEAR(c.meanA[1], 0.4, 1e-7);
    EXPECT_NEAR(c.bias[0], 0.05 / 0.275, 1e-6);
    EXPECT_NEAR(c.bias[1], 0.05 / 0.35, 1e-6);
    EXPECT_NEAR(c.bias[2], 0.05 / 0.3, 1e-6);
    EXPECT_NEAR(c.rmseCoarse, 0.05, 1e-7);
    EXPECT_NEAR(c.rmsePixel, 0, 1e-7);
}

TEST(Compare, BiasIsPerChannelAndRelativeToTheSecondImage) {
    // a = (1.1 R, 0.9 G, 1.3 B) of b: bias +0.1, −0.1, +0.3 (b/a − 1 would give −0.091, +0.111, −0.231).
    const Image b = rampImage();
    Image a = b;
    const float scale[3] = {1.1f, 0.9f, 1.3f};
    for (std::size_t p = 0; p < a.pixels(); ++p)
        for (int c = 0; c < 3; ++c) a.rgba[4 * p + c] *= scale[c];
    const auto c = compareImages(a, b);
    EXPECT_NEAR(c.bias[0], 0.1, 1e-6);
    EXPECT_NEAR(c.bias[1], -0.1, 1e-6);
    EXPECT_NEAR(c.bias[2], 0.3, 1e-6);

    const Image black(8, 4, false);
    const auto againstBlack = compareImages(a, black);
    for (double bias : againstBlack.bias) EXPECT_TRUE(std::isnan(bias));
}

TEST(Compare, ACheckerboardIsAllPixelError) {
    // a = b ± s alternating per pixel: every 4×4 block averages it away (coarse 0, mean 0), the
    // pixel residual is ±s everywhere.
    const Image b = rampImage();
    Image a = b;
    for (std::size_t p = 0; p < a.pixels(); ++p) {
        const std::size_t x = p % 8, y = p / 8;
        for (int c = 0; c < 3; ++c) a.rgba[4 * p + c] += (x + y) % 2 == 0 ? 0.04f : -0.04f;
    }
    const auto c = compareImages(a, b);
    EXPECT_NEAR(c.rmseCoarse, 0, 1e-7);
    EXPECT_NEAR(c.rmsePixel, 0.04, 1e-7);
    EXPECT_NEAR(c.rmse, 0.04, 1e-7);
    for (double bias : c.bias) EXPECT_NEAR(bias, 0, 1e-6);
}

TEST(Compare, BorderBlocksAverageThePixelsTheyHave) {
    // 6×5: blocks of 4×4, 2×4, 4×1 and 2×1 pixels. G off by δ in column 5 only (5 of 30 pixels):
    // the two right blocks have mean δ/2 (not δ/4 or δ/16, as padding would give), so
    // rmseCoarse² = 2·(δ/2)² / (4 blocks · 3 channels) = δ²/24, and their 10 pixels have residual
    // ±δ/2: rmsePixel² = 10·δ²/4 / 90 = δ²/36. rmse² = 5δ²/90 = δ²/18 < δ²/24 + δ²/36: border
    // blocks make the split approximate.
    const double delta = 0.12;
    Image b(6, 5, false);
    for (std::size_t p = 0; p < b.pixels(); ++p)
        for (int c = 0; c < 4; ++c) b.rgba[4 * p + c] = 0.5f;
    Image a = b;
    for (int y = 0; y < 5; ++y) a.rgba[4 * std::size_t(y * 6 + 5) + 1] += float(delta);
    const auto c = compareImages(a, b);
    EXPECT_NEAR(c.rmseCoarse, delta / std::sqrt(24.0), 1e-7);
    EXPECT_NEAR(c.rmsePixel, delta / 6, 1e-7);
    EXPECT_NEAR(c.rmse, delta / std::sqrt(18.0), 1e-7);
    EXPECT_NEAR(c.bias[1], delta / 6 / 0.5, 1e-6);
    EXPECT_NEAR(c.bias[0], 0, 1e-12);
}

TEST(Compare, WholeBlocksSplitTheSquaredErrorExactly) {
    // Width and height multiples of 4: rmse² = rmseCoarse² + rmsePixel² (orthogonal parts).
    for (unsigned seed = 10; seed < 20; ++seed) {
        const auto c = compareImages(noiseImage(32, 24, seed), noiseImage(32, 24, seed + 100));
        EXPECT_NEAR(c.rmse * c.rmse, c.rmseCoarse * c.rmseCoarse + c.rmsePixel * c.rmsePixel, 1e-12) << seed;
        EXPECT_GT(c.rmseCoarse, 0);
        EXPECT_GT(c.rmsePixel, c.rmseCoarse) << "independent noise is mostly pixel-scale";
    }
    const auto self = compareImages(rampImage(), rampImage());
    EXPECT_EQ(self.rmseCoarse, 0);
    EXPECT_EQ(self.rmsePixel, 0);
    for (double bias : self.bias) EXPECT_EQ(bias, 0);
}

// Bands of rows by hand: b is 0.5 everywhere, a the same but for its red in rows 4–6, 10 % higher.
// Cut into 3 bands of 7 rows, [0, 2), [2, 4), [4, 7): the first two have no error; the third a red
// bias of exactly +10 % and an RMSE of √(21 · 0.05² / 63) = 0.05/√3, its green and blue none.
TEST(Compare, RowBandsSayWhichRowsTheErrorIsIn) {
    Image b(8, 7, false);
    for (std::size_t p = 0; p < b.pixels(); ++p)
        for (int c = 0; c < 4; ++c) b.rgba[4 * p + std::size_t(c)] = c < 3 ? 0.5f : 1.0f;
    Image a = b;
    for (std::size_t p = 4 * 8; p < a.pixels(); ++p) a.rgba[4 * p] = 0.55f;
    const auto bands = vtex::render::compareRowBands(a, b, 3);
    ASSERT_EQ(bands.size(), 3u);
    const int rows[4] = {0, 2, 4, 7};
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(bands[std::size_t(k)].firstRow, rows[k]);
        EXPECT_EQ(bands[std::size_t(k)].endRow, rows[k + 1]);
    }
    for (int k = 0; k < 2; ++k) {
        EXPECT_EQ(bands[std::size_t(k)].rmse, 0);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(bands[std::size_t(k)].bias[std::size_t(c)], 0);
    }
    EXPECT_NEAR(bands[2].bias[0], 0.1, 1e-6);
    EXPECT_EQ(bands[2].bias[1], 0);
    EXPECT_EQ(bands[2].bias[2], 0);
    EXPECT_NEAR(bands[2].rmse, 0.05 / std::sqrt(3.0), 1e-6);
    EXPECT_THROW(vtex::render::compareRowBands(a, b, 0), std::invalid_argument);
    EXPECT_THROW(vtex::render::compareRowBands(a, b, 8), std::invalid_argument);
}

// Any cut of two noise images: the bands cover every row once, and their means and squared errors
// weighted by their pixels are the whole image's (one band is the whole comparison).
TEST(Compare, RowBandsAddUpToTheWholeImage) {
    const Image a = noiseImage(13, 29, 11), b = noiseImage(13, 29, 12);
    const auto whole = compareImages(a, b);
    for (const int n : {1, 2, 5, 7, 29}) {
        const auto bands = vtex::render::compareRowBands(a, b, n);
        ASSERT_EQ(bands.size(), std::size_t(n));
        std::array<double, 3> meanA{}, meanB{};
        double squared = 0;
        int next = 0;
        for (const auto& band : bands) {
            EXPECT_EQ(band.firstRow, next);
            EXPECT_GT(band.endRow, band.firstRow);
            next = band.endRow;
            const double pixels = 13.0 * (band.endRow - band.firstRow);
            for (std::size_t c = 0; c < 3; ++c) {
                meanA[c] += band.meanA[c] * pixels / (13.0 * 29);
                meanB[c] += band.meanB[c] * pixels / (13.0 * 29);
            }
            squared += band.rmse * band.rmse * 3 * pixels;
        }
        EXPECT_EQ(next, 29);
        for (std::size_t c = 0; c < 3; ++c) {
            EXPECT_NEAR(meanA[c], whole.meanA[c], 1e-12);
            EXPECT_NEAR(meanB[c], whole.meanB[c], 1e-12);
        }
        EXPECT_NEAR(std::sqrt(squared / (3 * 13.0 * 29)), whole.rmse, 1e-12);
        if (n == 1) {
            for (std::size_t c = 0; c < 3; ++c) EXPECT_NEAR(bands[0].bias[c], whole.bias[c], 1e-12);
        }
    }
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
    // b's red 0.1 above a's everywhere (16×12: whole blocks): all bias and coarse error, in red.
    ASSERT_EQ(j["mean_a"].size(), 3u);
    EXPECT_NEAR(j["mean_b"][0].get<double>() - j["mean_a"][0].get<double>(), 0.1, 1e-6);
    EXPECT_NEAR(j["mean_a"][1].get<double>(), j["mean_b"][1].get<double>(), 1e-12);
    EXPECT_NEAR(j["bias"][0].get<double>(), -0.1 / j["mean_b"][0].get<double>(), 1e-6);
    EXPECT_EQ(j["bias"][2].get<double>(), 0);
    EXPECT_NEAR(j["rmse_coarse"].get<double>(), 0.1 / std::sqrt(3.0), 1e-6);
    EXPECT_NEAR(j["rmse_pixel"].get<double>(), 0, 1e-6);

    const auto self = runVtex({"compare", scratch("a.exr").string(), scratch("a.exr").string(), "--json"});
    ASSERT_EQ(self.exitStatus, 0) << self.err;
    EXPECT_EQ(nlohmann::json::parse(self.out)["rmse"].get<double>(), 0);
    EXPECT_TRUE(nlohmann::json::parse(self.out)["psnr"].is_null());

    // Against a black image the bias has no value: null, not NaN (which JSON cannot hold).
    vtex::render::writeExr(Image(16, 12, false), scratch("black.exr"));
    const auto black = runVtex({"compare", scratch("a.exr").string(), scratch("black.exr").string(), "--json"});
    ASSERT_EQ(black.exitStatus, 0) << black.err;
    const auto jb = nlohmann::json::parse(black.out);
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(jb["bias"][c].is_null()) << jb.dump();

    const auto text = runVtex({"compare", scratch("a.exr").string(), scratch("b.exr").string()});
    ASSERT_EQ(text.exitStatus, 0) << text.err;
    EXPECT_NE(text.out.find("RMSE 4x4 blocks"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("bias "), std::string::npos) << text.out;

    // --bands: the rows cut top to bottom, in the JSON and one line each in the text; more bands
    // than rows is a usage error.
    const auto banded = runVtex({"compare", scratch("a.exr").string(), scratch("b.exr").string(), "--json", "--bands", "5"});
    ASSERT_EQ(banded.exitStatus, 0) << banded.err;
    const auto jn = nlohmann::json::parse(banded.out);
    ASSERT_EQ(jn["bands"].size(), 5u);
    EXPECT_EQ(jn["bands"][0]["rows"][0].get<int>(), 0);
    EXPECT_EQ(jn["bands"][4]["rows"][1].get<int>(), 12);
    for (const auto& band : jn["bands"]) EXPECT_NEAR(band["rmse"].get<double>(), 0.1 / std::sqrt(3.0), 1e-6);
    const auto bandText = runVtex({"compare", scratch("a.exr").string(), scratch("b.exr").string(), "--bands", "3"});
    ASSERT_EQ(bandText.exitStatus, 0) << bandText.err;
    EXPECT_NE(bandText.out.find("rows 8-11"), std::string::npos) << bandText.out;
    const auto tooMany = runVtex({"compare", scratch("a.exr").string(), scratch("b.exr").string(), "--bands", "13"});
    EXPECT_EQ(tooMany.exitStatus, 2) << tooMany.err;
    EXPECT_EQ(runVtex({"compare", scratch("a.exr").string(), scratch("b.exr").string(), "--json"}).out.find("bands"),
              std::string::npos);
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
