// `vtex compare a.exr b.exr [--json] [--diff heat.png] [--bands N]`: RMSE, PSNR and SSIM between two
// images, the channel means and a's bias against b, the RMSE split into 4×4-block and pixel
// scales, and optionally the means, bias and RMSE per band of rows.
#include "cli.h"
#include "json_number.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/render/compare.h>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace vtex::cli {
namespace {

std::string joinNames(const std::vector<std::string>& names) {
    std::string joined;
    for (const auto& n : names) {
        if (!joined.empty()) joined += ',';
        joined += n;
    }
    return joined.empty() ? "none" : joined;
}

nlohmann::json triple(const std::array<double, 3>& v, bool nullable) {
    nlohmann::json j = nlohmann::json::array();
    for (double x : v) j.push_back(nullable ? jsonNumber(x) : nlohmann::json(x));
    return j;
}

nlohmann::json toJson(const render::ImageComparison& c, const std::string& a, const std::string& b) {
    return {{"a", a},
            {"b", b},
            {"width", c.width},
            {"height", c.height},
            {"rmse", c.rmse},
            {"psnr", jsonNumber(c.psnr)},
            {"ssim", c.ssim},
            {"worst_pixel", {{"x", c.worstX}, {"y", c.worstY}, {"error", c.worstError}}},
            {"mean_a", triple(c.meanA, false)},
            {"mean_b", triple(c.meanB, false)},
            {"bias", triple(c.bias, true)},
            {"rmse_coarse", c.rmseCoarse},
            {"rmse_pixel", c.rmsePixel}};
}

// "+12.345%", or "n/a" where b's channel is black.
std::string percent(double bias) {
    if (!std::isfinite(bias)) return "n/a";
    char text[32];
    std::snprintf(text, sizeof text, "%+.3f%%", 100 * bias);
    return text;
}

nlohmann::json bandsJson(const std::vector<render::BandComparison>& bands) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& band : bands)
        j.push_back({{"rows", {band.firstRow, band.endRow}},
                     {"mean_a", triple(band.meanA, false)},
                     {"mean_b", triple(band.meanB, false)},
                     {"bias", triple(band.bias, true)},
                     {"rmse", band.rmse}});
    return j;
}

void printBands(const std::vector<render::BandComparison>& bands) {
    char line[256];
    for (const auto& band : bands) {
        std::snprintf(line, sizeof line, "rows %d-%d  RMSE %.6g  mean A %.6g %.6g %.6g  mean B %.6g %.6g %.6g  ",
                      band.firstRow, band.endRow - 1, band.rmse, band.meanA[0], band.meanA[1], band.meanA[2],
                      band.meanB[0], band.meanB[1], band.meanB[2]);
        std::cout << line << "bias " << percent(band.bias[0]) << ' ' << percent(band.bias[1]) << ' '
                  << percent(band.bias[2]) << '\n';
    }
}

void printText(const render::ImageComparison& c) {
    char line[512];
    std::snprintf(line, sizeof line, "RMSE %.6g  PSNR %s dB  SSIM %.6f  worst pixel (%d, %d) error %.6g\n", c.rmse,
                  std::isfinite(c.psnr) ? std::to_string(c.psnr).c_str() : "inf", c.ssim, c.worstX, c.worstY,
                  c.worstError);
    std::cout << line;
    std::snprintf(line, sizeof line, "RMSE 4x4 blocks %.6g  pixel %.6g  mean A %.6g %.6g %.6g  mean B %.6g %.6g %.6g  ",
                  c.rmseCoarse, c.rmsePixel, c.meanA[0], c.meanA[1], c.meanA[2], c.meanB[0], c.meanB[1], c.meanB[2]);
    std::cout << line << "bias " << percent(c.bias[0]) << ' ' << percent(c.bias[1]) << ' ' << percent(c.bias[2])
              << '\n';
}

const bool registered = registerCommand(60, [](CLI::App& app) -> Action {
    app.name("compare");
    app.description("Measure the error between two images: RMSE (linear RGB), PSNR (peak 1), SSIM (luminance), "
                    "the worst pixel, the R, G, B means and A's bias against B, the RMSE of the 4x4-block "
                    "means and of the pixel-scale rest; optionally a heat map of the difference");
    struct Options {
        std::string a, b, diff;
        bool json = false;
        int bands = 0;
    };
    auto o = std::make_shared<Options>();
    app.add_option("A", o->a, "First image (.exr), e.g. the texel render")->required();
    app.add_option("B", o->b, "Second image (.exr), e.g. the reference")->required();
    app.add_flag("--json", o->json, "Print the metrics as JSON on stdout");
    app.add_option("--diff", o->diff, "Write a PNG heat map of the per-pixel error, full scale at the worst pixel");
    app.add_option("--bands", o->bands,
                   "Also measure N horizontal bands of rows, top to bottom (their means, A's bias and the RMSE): "
                   "where in the image the error is")
        ->check(CLI::Range(1, 16384));
    return [o](const GlobalOptions&) {
        if (!o->diff.empty()) checkOutputPath(o->diff, {o->a, o->b});  // before any work (atomic_file.h)
        const auto channelsA = render::comparedChannels(o->a);
        const auto channelsB = render::comparedChannels(o->b);
        if (channelsA != channelsB)
            throw InputError(o->b, "channel sets differ: " + joinNames(channelsA) + " in " + o->a + ", " +
                                       joinNames(channelsB) + " here");
        const render::Image a = render::readImage(o->a);
        const render::Image b = render::readImage(o->b);
        if (a.width != b.width || a.height != b.height)
            throw InputError(o->b, "size " + std::to_string(b.width) + "x" + std::to_string(b.height) +
                                       " differs from " + o->a + " (" + std::to_string(a.width) + "x" +
                                       std::to_string(a.height) + ")");
        for (const auto& [image, file] : {std::pair{&a, o->a}, std::pair{&b, o->b}})
            if (const auto p = render::firstUnmeasurablePixel(*image))
                throw InputError(file, "pixel (" + std::to_string(p->first) + ", " + std::to_string(p->second) +
                                           ") is not finite or beyond ±1e30: such an image has no error to measure");
        if (o->bands > a.height)
            throw CLI::ValidationError("--bands", std::to_string(o->bands) + " bands, more than the images' " +
                                                      std::to_string(a.height) + " rows");
        const render::ImageComparison c = render::compareImages(a, b);
        const std::vector<render::BandComparison> bands =
            o->bands > 0 ? render::compareRowBands(a, b, o->bands) : std::vector<render::BandComparison>{};
        if (!o->diff.empty()) render::writePng(render::errorHeatMap(a, b, c.worstError), o->diff);
        if (o->json) {
            nlohmann::json j = toJson(c, o->a, o->b);
            if (o->bands > 0) j["bands"] = bandsJson(bands);
            std::cout << j.dump(2) << '\n';
        } else {
            printText(c);
            printBands(bands);
        }
    };
});

}  // namespace
}  // namespace vtex::cli
