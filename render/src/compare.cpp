#include <vtex/render/compare.h>

#include <vtex/core/error.h>
#include <vtex/core/input_file.h>

#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace vtex::render {
namespace {

void requireSameSize(const Image& a, const Image& b) {
    if (a.width != b.width || a.height != b.height)
        throw std::invalid_argument("sizes differ: " + std::to_string(a.width) + "×" + std::to_string(a.height) +
                                    " and " + std::to_string(b.width) + "×" + std::to_string(b.height));
}

double pixelSquaredError(const Image& a, const Image& b, std::size_t pixel) {
    double sum = 0;
    for (int c = 0; c < 3; ++c) {
        const double d = double(a.rgba[4 * pixel + c]) - double(b.rgba[4 * pixel + c]);
        sum += d * d;
    }
    return sum;
}

std::vector<double> luminance(const Image& image) {
    std::vector<double> y(image.pixels());
    for (std::size_t p = 0; p < y.size(); ++p)
        y[p] = 0.2126 * image.rgba[4 * p] + 0.7152 * image.rgba[4 * p + 1] + 0.0722 * image.rgba[4 * p + 2];
    return y;
}

// Gaussian-weighted local mean of `values`, separable, truncated and renormalised at borders.
std::vector<double> gaussianMean(const std::vector<double>& values, int width, int height) {
    constexpr int kRadius = 5;
    std::array<double, 2 * kRadius + 1> kernel{};
    for (int i = -kRadius; i <= kRadius; ++i) kernel[std::size_t(i + kRadius)] = std::exp(-0.5 * i * i / (1.5 * 1.5));
    auto pass = [&](const std::vector<double>& in, bool horizontal) {
        std::vector<double> out(in.size());
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                double sum = 0, weight = 0;
                for (int i = -kRadius; i <= kRadius; ++i) {
                    const int sx = horizontal ? x + i : x, sy = horizontal ? y : y + i;
                    if (sx < 0 || sy < 0 || sx >= width || sy >= height) continue;
                    const double w = kernel[std::size_t(i + kRadius)];
                    sum += w * in[std::size_t(sy) * std::size_t(width) + std::size_t(sx)];
                    weight += w;
                }
                out[std::size_t(y) * std::size_t(width) + std::size_t(x)] = sum / weight;
            }
        return out;
    };
    return pass(pass(values, true), false);
}

double meanSsim(const Image& a, const Image& b) {
    const std::vector<double> x = luminance(a), y = luminance(b);
    std::vector<double> xx(x.size()), yy(x.size()), xy(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
        xx[i] = x[i] * x[i];
        yy[i] = y[i] * y[i];
        xy[i] = x[i] * y[i];
    }
    const int w = a.width, h = a.height;
    const auto mx = gaussianMean(x, w, h), my = gaussianMean(y, w, h);
    const auto mxx = gaussianMean(xx, w, h), myy = gaussianMean(yy, w, h), mxy = gaussianMean(xy, w, h);
    constexpr double kC1 = 0.01 * 0.01, kC2 = 0.03 * 0.03;  // (K·L)² with L = 1
    double sum = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double varX = std::max(0.0, mxx[i] - mx[i] * mx[i]);
        const double varY = std::max(0.0, myy[i] - my[i] * my[i]);
        const double cov = mxy[i] - mx[i] * my[i];
        sum += (2 * mx[i] * my[i] + kC1) * (2 * cov + kC2) /
               ((mx[i] * mx[i] + my[i] * my[i] + kC1) * (varX + varY + kC2));
    }
    return sum / double(x.size());
}

// The mean R, G, B of the pixels [first, end) (row-major).
std::array<double, 3> channelMeans(const Image& image, std::size_t first, std::size_t end) {
    std::array<double, 3> sum{};
    for (std::size_t p = first; p < end; ++p)
        for (int c = 0; c < 3; ++c) sum[std::size_t(c)] += image.rgba[4 * p + std::size_t(c)];
    for (double& s : sum) s /= double(end - first);
    return sum;
}

// meanA / meanB − 1 per channel, NaN where meanB is 0.
std::array<double, 3> relativeBias(const std::array<double, 3>& meanA, const std::array<double, 3>& meanB) {
    std::array<double, 3> bias{};
    for (std::size_t c = 0; c < 3; ++c)
        bias[c] = meanB[c] != 0 ? meanA[c] / meanB[c] - 1 : std::numeric_limits<double>::quiet_NaN();
    return bias;
}

constexpr int kBlock = 4;  // the coarse scale of the error split, in pixels

int blockCount(int pixels) { return (pixels + kBlock - 1) / kBlock; }

std::size_t blockOf(const Image& image, std::size_t pixel) {
    const std::size_t x = pixel % std::size_t(image.width), y = pixel / std::size_t(image.width);
    return (y / kBlock) * std::size_t(blockCount(image.width)) + x / kBlock;
}

// R, G, B means of every 4×4 block, row-major; a border block averages the pixels it has.
std::vector<double> blockMeans(const Image& image) {
    const std::size_t blocks = std::size_t(blockCount(image.width)) * std::size_t(blockCount(image.height));
    std::vector<double> sum(3 * blocks, 0.0);
    std::vector<int> count(blocks, 0);
    for (std::size_t p = 0; p < image.pixels(); ++p) {
        const std::size_t b = blockOf(image, p);
        for (std::size_t c = 0; c < 3; ++c) sum[3 * b + c] += image.rgba[4 * p + c];
        ++count[b];
    }
    for (std::size_t b = 0; b < blocks; ++b)
        for (std::size_t c = 0; c < 3; ++c) sum[3 * b + c] /= count[b];
    return sum;
}

// rmseCoarse and rmsePixel of the header's split.
void splitByScale(const Image& a, const Image& b, ImageComparison& result) {
    const std::vector<double> meansA = blockMeans(a), meansB = blockMeans(b);
    double coarse = 0;
    for (std::size_t i = 0; i < meansA.size(); ++i) coarse += (meansA[i] - meansB[i]) * (meansA[i] - meansB[i]);
    double pixel = 0;
    for (std::size_t p = 0; p < a.pixels(); ++p) {
        const std::size_t k = blockOf(a, p);
        for (std::size_t c = 0; c < 3; ++c) {
            const double d = (a.rgba[4 * p + c] - meansA[3 * k + c]) - (b.rgba[4 * p + c] - meansB[3 * k + c]);
            pixel += d * d;
        }
    }
    result.rmseCoarse = std::sqrt(coarse / double(meansA.size()));
    result.rmsePixel = std::sqrt(pixel / (3.0 * double(a.pixels())));
}

}  // namespace

std::optional<std::pair<int, int>> firstUnmeasurablePixel(const Image& image) {
    for (std::size_t i = 0; i < image.rgba.size(); ++i)
        if (i % 4 != 3 && !(std::abs(image.rgba[i]) < 1e30f))
            return std::pair{int(i / 4 % std::size_t(image.width)), int(i / 4 / std::size_t(image.width))};
    return std::nullopt;
}

ImageComparison compareImages(const Image& a, const Image& b) {
    requireSameSize(a, b);
    if (firstUnmeasurablePixel(a) || firstUnmeasurablePixel(b)) throw std::invalid_argument("an image has a pixel that is not finite or is beyond ±1e30");
    ImageComparison result;
    result.width = a.width;
    result.height = a.height;
    if (a.pixels() == 0) {
        result.bias.fill(std::numeric_limits<double>::quiet_NaN());  // meanB is 0 (of nothing)
        return result;
    }
    double total = 0;
    for (std::size_t p = 0; p < a.pixels(); ++p) {
        const double squared = pixelSquaredError(a, b, p);
        total += squared;
        const double rms = std::sqrt(squared / 3);
        if (rms > result.worstError) {
            result.worstError = rms;
            result.worstX = int(p % std::size_t(a.width));
            result.worstY = int(p / std::size_t(a.width));
        }
    }
    const double mse = total / (3.0 * double(a.pixels()));
    result.rmse = std::sqrt(mse);
    result.psnr = mse > 0 ? -10 * std::log10(mse) : std::numeric_limits<double>::infinity();
    result.ssim = meanSsim(a, b);
    result.meanA = channelMeans(a, 0, a.pixels());
    result.meanB = channelMeans(b, 0, b.pixels());
    result.bias = relativeBias(result.meanA, result.meanB);
    splitByScale(a, b, result);
    return result;
}

std::vector<BandComparison> compareRowBands(const Image& a, const Image& b, int bands) {
    requireSameSize(a, b);
    if (bands < 1 || bands > a.height)
        throw std::invalid_argument("cannot cut " + std::to_string(a.height) + " rows into " + std::to_string(bands) + " bands");
    std::vector<BandComparison> out(static_cast<std::size_t>(bands));
    const std::size_t width = std::size_t(a.width);
    for (int k = 0; k < bands; ++k) {
        BandComparison& band = out[std::size_t(k)];
        band.firstRow = int(std::int64_t(k) * a.height / bands);
        band.endRow = int(std::int64_t(k + 1) * a.height / bands);
        const std::size_t first = std::size_t(band.firstRow) * width, end = std::size_t(band.endRow) * width;
        double squared = 0;
        for (std::size_t p = first; p < end; ++p) squared += pixelSquaredError(a, b, p);
        band.meanA = channelMeans(a, first, end);
        band.meanB = channelMeans(b, first, end);
        band.bias = relativeBias(band.meanA, band.meanB);
        const double pixels = double(end - first);
        band.rmse = std::sqrt(squared / (3 * pixels));
    }
    return out;
}

Image errorHeatMap(const Image& a, const Image& b, double fullScale) {
    requireSameSize(a, b);
    if (!(fullScale > 0)) fullScale = 1;
    Image map(a.width, a.height, false);
    for (std::size_t p = 0; p < a.pixels(); ++p) {
        const double t = std::clamp(std::sqrt(pixelSquaredError(a, b, p) / 3) / fullScale, 0.0, 1.0);
        // Black → red → yellow → white in thirds: monotone in brightness, readable in grey.
        map.rgba[4 * p + 0] = float(std::clamp(3 * t, 0.0, 1.0));
        map.rgba[4 * p + 1] = float(std::clamp(3 * t - 1, 0.0, 1.0));
        map.rgba[4 * p + 2] = float(std::clamp(3 * t - 2, 0.0, 1.0));
        map.rgba[4 * p + 3] = 1;
    }
    return map;
}

double heatMapScale(const Image& truth) {
    double sum = 0;
    for (std::size_t p = 0; p < truth.pixels(); ++p)
        for (std::size_t c = 0; c < 3; ++c) sum += double(truth.rgba[4 * p + c]) * double(truth.rgba[4 * p + c]);
    return truth.pixels() > 0 ? std::sqrt(sum / (3.0 * double(truth.pixels()))) : 0.0;
}

std::vector<std::string> comparedChannels(const std::filesystem::path& exrFile) {
    if (imageFormat(exrFile) == "png") return {"A", "B", "G", "R"};  // readPng's, always
    checkInputFile(exrFile, std::uint64_t(4) << 30, "EXR image");  // OpenEXR would hang on a FIFO
    std::vector<std::string> names;
    try {
        Imf::InputFile exr(exrFile.c_str());
        for (auto it = exr.header().channels().begin(); it != exr.header().channels().end(); ++it) {
            const std::string name = it.name();
            if (name != "Z" && name != "level") names.push_back(name);
        }
    } catch (const std::exception& e) {
        throw InputError(exrFile, std::string("cannot read EXR: ") + e.what());
    }
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace vtex::render
