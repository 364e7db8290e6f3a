/// @file
/// @brief Error metrics between two images (DESIGN.md, "Reporting error against run time").
///
/// RMSE on linear RGB (alpha and AOVs are not compared), PSNR with a peak of 1 (the linear value
/// the PNG preview shows as white), SSIM (Wang, Bovik, Sheikh and Simoncelli 2004) on linear
/// luminance with an 11×11 Gaussian window of σ = 1.5, K₁ = 0.01, K₂ = 0.03 and dynamic range 1,
/// the window truncated and renormalised at the borders so every pixel counts.
///
/// The error is also split by scale, to tell a wrong brightness or blur from pixel noise: the
/// coarse error is the RMSE between the two images' 4×4 box means (a block cut by the right or
/// bottom border is the mean of the pixels it has, and counts as one block like the others); the
/// pixel error is the RMSE of what the box means leave out, (a − up(box₄ a)) − (b − up(box₄ b)),
/// with up() giving every pixel its block's mean. When width and height are multiples of 4 the
/// two are orthogonal and rmse² = rmseCoarse² + rmsePixel² (to rounding); otherwise the border
/// blocks weigh as whole blocks in rmseCoarse but by their pixels in rmse, and the sum is only
/// approximate.
#pragma once

#include <vtex/render/image.h>

#include <array>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vtex::render {

struct ImageComparison {
    int width = 0;
    int height = 0;
    double rmse = 0;                                            ///< √(mean over pixels and R,G,B of Δ²)
    double psnr = std::numeric_limits<double>::infinity();      ///< dB, 10·log₁₀(1/MSE); ∞ when identical
    double ssim = 1;                                            ///< mean SSIM of the luminance
    int worstX = 0, worstY = 0;                                 ///< the pixel of largest RGB error
    double worstError = 0;                                      ///< its RMS over R, G, B
    std::array<double, 3> meanA{}, meanB{};                     ///< mean R, G, B over all pixels
    /// meanA / meanB − 1 per channel (a's relative brightness error when b is the truth); NaN
    /// where meanB is 0.
    std::array<double, 3> bias{};
    double rmseCoarse = 0;                                      ///< RMSE of the 4×4 box means
    double rmsePixel = 0;                                       ///< RMSE of the residuals below 4×4
};

/// One horizontal band of rows of two compared images: where in the image the error is (a far
/// view's distant rows against its near ones, say).
struct BandComparison {
    int firstRow = 0, endRow = 0;             ///< rows [firstRow, endRow), row 0 at the top
    std::array<double, 3> meanA{}, meanB{};   ///< mean R, G, B over the band's pixels
    std::array<double, 3> bias{};             ///< meanA / meanB − 1 per channel; NaN where meanB is 0
    double rmse = 0;                          ///< over the band's pixels and R, G, B
};

/// The images cut into `bands` bands of rows, band k holding rows [k·h/bands, (k+1)·h/bands)
/// (so every row is in one band, and the bands' sizes differ by one row at most). Throws
/// std::invalid_argument when the sizes differ or bands is not in [1, height].
std::vector<BandComparison> compareRowBands(const Image& a, const Image& b, int bands);

/// The first pixel (x, y) with a colour channel that is not finite or is beyond ±1e30, if any:
/// such an image has no RMSE (inf prints as null) and its SSIM overflows (its squares reach
/// float's range); callers refuse it naming the file.
std::optional<std::pair<int, int>> firstUnmeasurablePixel(const Image& image);

/// Compares two images of equal size. Throws std::invalid_argument when the sizes differ or an
/// image has an unmeasurable pixel (firstUnmeasurablePixel).
ImageComparison compareImages(const Image& a, const Image& b);

/// Per-pixel RMS error over R, G, B mapped to a black–red–yellow–white ramp, full scale at
/// `fullScale` (> 0; pass the worst error for a self-scaled map). Equal sizes required.
Image errorHeatMap(const Image& a, const Image& b, double fullScale);

/// A heat map's full scale for the comparisons against `truth`: the truth's RMS value over pixels
/// and R, G, B (white: a pixel wrong by as much as the image is bright). It depends on the truth alone, so that every image measured against
/// one truth (a study) shares one scale and a 64-spp map is darker than a 1-spp one, where a map
/// scaled to its own worst pixel made both look as hot; 0 for a black truth.
double heatMapScale(const Image& truth);

/// The colour channels of an EXR file that take part in a comparison (its channel names less
/// the AOVs "Z" and "level"), sorted. Throws vtex::InputError when the file cannot be read.
std::vector<std::string> comparedChannels(const std::filesystem::path& exrFile);

}  // namespace vtex::render
