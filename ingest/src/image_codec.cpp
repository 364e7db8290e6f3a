// Base-colour textures: decoded here with libpng and libjpeg(-turbo), never by tinygltf's
// bundled stb_image (a fuzzer finds a heap overflow in it within seconds, see deps.md). The
// declared dimensions are checked against IngestOptions caps before any pixel is allocated.
#include "detail.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <jpeglib.h>

namespace vtex::ingest::detail {
namespace {

bool dimensionsAllowed(std::uint64_t width, std::uint64_t height, const IngestOptions& options,
                       std::string& why) {
    if (width == 0 || height == 0) {
        why = "image has zero width or height";
        return false;
    }
    if (width > std::uint64_t(options.maxTextureDimension) ||
        height > std::uint64_t(options.maxTextureDimension) ||
        width * height > options.maxTexturePixels) {
        why = "image of " + std::to_string(width) + "x" + std::to_string(height) +
              " pixels exceeds the texture size limit";
        return false;
    }
    return true;
}

std::optional<Image> decodePng(std::string_view bytes, const IngestOptions& options,
                               std::string& why) {
    // libpng's simplified API reports errors through the png_image (no setjmp on our side)
    // and prints nothing.
    png_image png;
    std::memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&png, bytes.data(), bytes.size())) {
        why = std::string("bad PNG: ") + png.message;
        return std::nullopt;
    }
    if (!dimensionsAllowed(png.width, png.height, options, why)) {
        png_image_free(&png);
        return std::nullopt;
    }
    png.format = PNG_FORMAT_RGBA;
    Image image;
    image.width = int(png.width);
    image.height = int(png.height);
    image.rgba.resize(PNG_IMAGE_SIZE(png));
    if (!png_image_finish_read(&png, nullptr, image.rgba.data(), 0, nullptr)) {
        why = std::string("bad PNG: ") + png.message;
        png_image_free(&png);
        return std::nullopt;
    }
    return image;
}

struct JpegErrorManager {
    jpeg_error_mgr base;
    std::jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void jpegErrorExit(j_common_ptr info) {
    auto* manager = reinterpret_cast<JpegErrorManager*>(info->err);
    (*info->err->format_message)(info, manager->message);
    std::longjmp(manager->jump, 1);
}

void jpegSilence(j_common_ptr) {}  // libraries never print

// A progressive JPEG can make the decoder loop over thousands of tiny scans; a real texture
// has at most a few dozen.
void jpegLimitScans(j_common_ptr info) {
    auto* decompress = reinterpret_cast<j_decompress_ptr>(info);
    if (decompress->input_scan_number > 256) {
        auto* manager = reinterpret_cast<JpegErrorManager*>(info->err);
        std::snprintf(manager->message, sizeof manager->message, "too many progressive scans");
        std::longjmp(manager->jump, 1);
    }
}

std::optional<Image> decodeJpeg(std::string_view bytes, const IngestOptions& options,
                                std::string& why) {
    // Everything that lives across setjmp is either plain data or allocated before it: the
    // longjmp from jpegErrorExit must not skip a destructor.
    jpeg_decompress_struct info;
    JpegErrorManager errors;
    jpeg_progress_mgr progress;
    std::memset(&progress, 0, sizeof progress);
    progress.progress_monitor = jpegLimitScans;
    Image image;
    std::vector<std::uint8_t> row;
    info.err = jpeg_std_error(&errors.base);
    errors.base.error_exit = jpegErrorExit;
    errors.base.output_message = jpegSilence;
    errors.message[0] = '\0';
    if (setjmp(errors.jump)) {
        jpeg_destroy_decompress(&info);
        why = std::string("bad JPEG: ") + errors.message;
        return std::nullopt;
    }
    jpeg_create_decompress(&info);
    info.progress = &progress;
    jpeg_mem_src(&info, reinterpret_cast<const unsigned char*>(bytes.data()),
                 static_cast<unsigned long>(bytes.size()));
    jpeg_read_header(&info, TRUE);
    if (!dimensionsAllowed(info.image_width, info.image_height, options, why)) {
        jpeg_destroy_decompress(&info);
        return std::nullopt;
    }
    info.out_color_space = JCS_RGB;
    jpeg_start_decompress(&info);
    if (info.output_components != 3) {
        jpeg_destroy_decompress(&info);
        why = "bad JPEG: unexpected component count";
        return std::nullopt;
    }
    image.width = int(info.output_width);
    image.height = int(info.output_height);
    image.rgba.resize(std::size_t(image.width) * image.height * 4);
    row.resize(std::size_t(image.width) * 3);
    while (info.output_scanline < info.output_height) {
        JSAMPROW rows[1] = {row.data()};
        const JDIMENSION y = info.output_scanline;
        if (jpeg_read_scanlines(&info, rows, 1) != 1) break;
        std::uint8_t* out = image.rgba.data() + std::size_t(y) * image.width * 4;
        for (int x = 0; x < image.width; ++x) {
            out[4 * x + 0] = row[3 * x + 0];
            out[4 * x + 1] = row[3 * x + 1];
            out[4 * x + 2] = row[3 * x + 2];
            out[4 * x + 3] = 255;
        }
    }
    jpeg_finish_decompress(&info);
    jpeg_destroy_decompress(&info);
    return image;
}

}  // namespace

std::optional<Image> decodeImage(std::string_view bytes, const IngestOptions& options,
                                 std::string& why) {
    static constexpr unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPng, 8) == 0)
        return decodePng(bytes, options, why);
    if (bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
        static_cast<unsigned char>(bytes[1]) == 0xD8 && static_cast<unsigned char>(bytes[2]) == 0xFF)
        return decodeJpeg(bytes, options, why);
    why = bytes.empty() ? "image has no data" : "image is neither PNG nor JPEG";
    return std::nullopt;
}

}  // namespace vtex::ingest::detail

namespace vtex::ingest {

std::optional<Image> decodePngRgba(std::string_view bytes, std::string& why) {
    static constexpr unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kPng, 8) != 0) {
        why = "not a PNG";
        return std::nullopt;
    }
    return detail::decodeImage(bytes, IngestOptions{}, why);
}

std::string encodePng(const Image& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgba.size() != std::size_t(image.width) * image.height * 4)
        throw std::runtime_error("encodePng: image size does not match its pixels");
    png_image png;
    std::memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    png.width = png_uint_32(image.width);
    png.height = png_uint_32(image.height);
    png.format = PNG_FORMAT_RGBA;
    png_alloc_size_t size = 0;
    if (!png_image_write_to_memory(&png, nullptr, &size, 0, image.rgba.data(), 0, nullptr))
        throw std::runtime_error(std::string("PNG encoding failed: ") + png.message);
    std::string out(size, '\0');
    if (!png_image_write_to_memory(&png, out.data(), &size, 0, image.rgba.data(), 0, nullptr))
        throw std::runtime_error(std::string("PNG encoding failed: ") + png.message);
    out.resize(size);
    return out;
}

}  // namespace vtex::ingest
