// `vtex compare a.exr b.exr [--json] [--diff heat.png]`: RMSE, PSNR and SSIM between two images.
#include "cli.h"

#include <vtex/core/error.h>
#include <vtex/render/compare.h>

#include <nlohmann/json.hpp>

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

const bool registered = registerCommand(60, [](CLI::App& app) -> Action {
    app.name("compare");
    app.description("Measure the error between two images: RMSE (linear RGB), PSNR (peak 1), SSIM (luminance), "
                    "the worst pixel; optionally a heat map of the difference");
    struct Options {
        std::string a, b, diff;
        bool json = false;
    };
    auto o = std::make_shared<Options>();
    app.add_option("A", o->a, "First image (.exr), e.g. the texel render")->required();
    app.add_option("B", o->b, "Second image (.exr), e.g. the reference")->required();
    app.add_flag("--json", o->json, "Print the metrics as JSON on stdout");
    app.add_option("--diff", o->diff, "Write a PNG heat map of the per-pixel error, full scale at the worst pixel");
    return [o](const GlobalOptions&) {
        const auto channelsA = render::comparedChannels(o->a);
        const auto channelsB = render::comparedChannels(o->b);
        if (channelsA != channelsB)
            throw InputError(o->b, "channel sets differ: " + joinNames(channelsA) + " in " + o->a + ", " +
                                       joinNames(channelsB) + " here");
        const render::Image a = render::readExr(o->a);
        const render::Image b = render::readExr(o->b);
        if (a.width != b.width || a.height != b.height)
            throw InputError(o->b, "size " + std::to_string(b.width) + "x" + std::to_string(b.height) +
                                       " differs from " + o->a + " (" + std::to_string(a.width) + "x" +
                                       std::to_string(a.height) + ")");
        const render::ImageComparison c = render::compareImages(a, b);
        if (!o->diff.empty()) render::writePng(render::errorHeatMap(a, b, c.worstError), o->diff);
        if (o->json) {
            nlohmann::json j = {{"a", o->a},           {"b", o->b},
                                {"width", c.width},    {"height", c.height},
                                {"rmse", c.rmse},      {"ssim", c.ssim},
                                {"worst_pixel", {{"x", c.worstX}, {"y", c.worstY}, {"error", c.worstError}}}};
            // JSON has no infinity: identical images have no finite PSNR.
            j["psnr"] = std::isfinite(c.psnr) ? nlohmann::json(c.psnr) : nlohmann::json(nullptr);
            std::cout << j.dump(2) << '\n';
            return;
        }
        char line[256];
        std::snprintf(line, sizeof line, "RMSE %.6g  PSNR %s dB  SSIM %.6f  worst pixel (%d, %d) error %.6g\n",
                      c.rmse, std::isfinite(c.psnr) ? std::to_string(c.psnr).c_str() : "inf", c.ssim, c.worstX,
                      c.worstY, c.worstError);
        std::cout << line;
    };
});

}  // namespace
}  // namespace vtex::cli
