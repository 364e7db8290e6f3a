/// @file
/// @brief Rendered images and their files: linear OpenEXR (RGBA + optional AOVs), sRGB PNG.
///
/// DESIGN.md, "Rendering" and "Radiometry": EXR holds linear radiance, the PNG is sRGB-encoded
/// and clamped. Every file is written through vtex::AtomicOutputFile.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

namespace vtex {
class AtomicOutputFile;
}

namespace vtex::render {

/// Row-major images, row 0 at the top.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> rgba;   ///< 4 floats per pixel, linear RGB radiance and coverage alpha
    std::vector<float> depth;  ///< AOV (optional): camera distance where the pixel turned opaque, 0 where nothing was hit
    std::vector<float> level;  ///< AOV (optional): opacity-weighted mean octree level, −1 where no texel was seen

    Image() = default;
    Image(int w, int h, bool aovs);
    std::size_t pixels() const { return std::size_t(width) * std::size_t(height); }
    bool hasAovs() const { return !depth.empty(); }
};

/// Writes R, G, B, A (32-bit float, ZIP) and, when present, the AOV channels "Z" (depth) and
/// "level". Throws vtex::IoError.
void writeExr(const Image& image, const std::filesystem::path& file);
/// The same into an output the caller commits (commitAll: several outputs all or none).
void writeExr(const Image& image, AtomicOutputFile& out);
/// Reads an EXR written by writeExr (or any RGBA EXR; missing channels read as 0, A as 1).
/// Throws vtex::InputError.
Image readExr(const std::filesystem::path& file);
/// Reads an 8-bit (or 16-bit) PNG as writePng writes it: colours sRGB-decoded to linear, alpha as
/// stored, no AOVs. Throws vtex::InputError.
Image readPng(const std::filesystem::path& file);
/// readExr or readPng by the file's extension (.exr or .png, any case); another is refused
/// (vtex::InputError).
Image readImage(const std::filesystem::path& file);
/// "exr" or "png" for a file name of that extension (any case), "" otherwise: the image formats
/// vtex reads and writes (an output named without an extension is written as EXR).
std::string imageFormat(const std::filesystem::path& file);
/// Writes an 8-bit sRGB PNG with alpha, colours clamped to [0,1]. Throws vtex::IoError.
void writePng(const Image& image, const std::filesystem::path& file);
void writePng(const Image& image, AtomicOutputFile& out);

/// Linear → sRGB transfer function on [0,1], and its inverse.
double linearToSrgb(double linear);
double srgbToLinear(double encoded);

/// Mean of each 2×2 block (the box-downsampled image; width and height are halved, odd ones
/// rounded down). AOVs are dropped.
Image downsample2x(const Image& image);

}  // namespace vtex::render
