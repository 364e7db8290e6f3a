// EXR (OpenEXR 3, 32-bit float channels) and PNG (through ingest's libpng encoder) files of an Image.
#include <vtex/render/image.h>

#include <vtex/ingest/mesh.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/input_file.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ostream>
#include <stdexcept>

namespace vtex::render {

Image::Image(int w, int h, bool aovs) : width(w), height(h) {
    rgba.assign(pixels() * 4, 0.0f);
    if (aovs) {
        depth.assign(pixels(), 0.0f);
        level.assign(pixels(), -1.0f);
    }
}

void writeExr(const Image& image, const std::filesystem::path& file) {
    AtomicOutputFile out(file);
    writeExr(image, out);
    out.commit();
}

namespace {

// OpenEXR writes into the atomic output's own stream, whose failures AtomicOutputFile::finish()
// sees. Given the temporary's name instead, OpenEXR's file stream dropped the error of its last
// flush when it closed: on a full disk an empty EXR was committed and render exited 0.
class ExrOutput final : public Imf::OStream {
public:
    ExrOutput(std::ostream& out, const std::filesystem::path& target) : Imf::OStream(target.c_str()), mOut(out) {}
    void write(const char c[], int n) override {
        if (!mOut.write(c, n)) throw std::runtime_error("write failed (disk full?)");
    }
    std::uint64_t tellp() override { return std::uint64_t(mOut.tellp()); }
    void seekp(std::uint64_t pos) override {
        if (!mOut.seekp(std::streamoff(pos))) throw std::runtime_error("seek failed");
    }

private:
    std::ostream& mOut;
};

}  // namespace

void writeExr(const Image& image, AtomicOutputFile& out) {
    const std::filesystem::path& file = out.target();
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::FrameBuffer frame;
        const std::size_t pixelStride = 4 * sizeof(float);
        const std::size_t rowStride = pixelStride * std::size_t(image.width);
        const char* names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            frame.insert(names[c], Imf::Slice(Imf::FLOAT, (char*)(image.rgba.data() + c), pixelStride, rowStride));
        }
        if (image.hasAovs()) {
            header.channels().insert("Z", Imf::Channel(Imf::FLOAT));
            header.channels().insert("level", Imf::Channel(Imf::FLOAT));
            frame.insert("Z", Imf::Slice(Imf::FLOAT, (char*)image.depth.data(), sizeof(float),
                                         sizeof(float) * std::size_t(image.width)));
            frame.insert("level", Imf::Slice(Imf::FLOAT, (char*)image.level.data(), sizeof(float),
                                             sizeof(float) * std::size_t(image.width)));
        }
        ExrOutput stream(out.stream(), file);
        Imf::OutputFile exr(stream, header);
        exr.setFrameBuffer(frame);
        exr.writePixels(image.height);
    } catch (const std::exception& e) {
        throw IoError(file, std::string("cannot write EXR: ") + e.what());
    }
}

Image readExr(const std::filesystem::path& file) {
    // OpenEXR opens the file by name: a FIFO would hang it (input_file.h). 4 GiB holds the
    // largest image vtex writes (16384² RGBA float and two AOVs) with room to spare.
    checkInputFile(file, std::uint64_t(4) << 30, "EXR image");
    try {
        Imf::InputFile exr(file.c_str());
        const Imath::Box2i window = exr.header().dataWindow();
        const long w = long(window.max.x) - window.min.x + 1;
        const long h = long(window.max.y) - window.min.y + 1;
        if (w <= 0 || h <= 0 || w > 65536 || h > 65536 || w * h > (1L << 28))
            throw InputError(file, "absurd EXR data window");
        const bool aovs = exr.header().channels().findChannel("Z") != nullptr;
        Image image(int(w), int(h), aovs);
        Imf::FrameBuffer frame;
        const std::size_t pixelStride = 4 * sizeof(float);
        const std::size_t rowStride = pixelStride * std::size_t(w);
        const std::ptrdiff_t origin = std::ptrdiff_t(window.min.x) + std::ptrdiff_t(window.min.y) * w;
        const char* names[4] = {"R", "G", "B", "A"};
        for (int c = 0; c < 4; ++c)
            frame.insert(names[c], Imf::Slice(Imf::FLOAT, (char*)(image.rgba.data() + c - 4 * origin),
                                              pixelStride, rowStride, 1, 1, c == 3 ? 1.0 : 0.0));
        if (aovs) {
            frame.insert("Z", Imf::Slice(Imf::FLOAT, (char*)(image.depth.data() - origin), sizeof(float),
                                         sizeof(float) * std::size_t(w)));
            frame.insert("level", Imf::Slice(Imf::FLOAT, (char*)(image.level.data() - origin), sizeof(float),
                                             sizeof(float) * std::size_t(w), 1, 1, -1.0));
        }
        exr.setFrameBuffer(frame);
        exr.readPixels(window.min.y, window.max.y);
        return image;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(file, std::string("cannot read EXR: ") + e.what());
    }
}

double linearToSrgb(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
}

double srgbToLinear(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4);
}

std::string imageFormat(const std::filesystem::path& file) {
    std::string extension = file.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return extension == ".exr" ? "exr" : extension == ".png" ? "png" : "";
}

Image readPng(const std::filesystem::path& file) {
    const std::string bytes = readInputFile(file, std::uint64_t(1) << 30, "PNG image");
    std::string why;
    const auto decoded = ingest::decodePngRgba(bytes, why);
    if (!decoded) throw InputError(file, "cannot read PNG: " + why);
    Image image(decoded->width, decoded->height, false);
    for (std::size_t i = 0; i < image.pixels(); ++i) {
        for (int c = 0; c < 3; ++c) image.rgba[4 * i + std::size_t(c)] = float(srgbToLinear(decoded->rgba[4 * i + std::size_t(c)] / 255.0));
        image.rgba[4 * i + 3] = float(decoded->rgba[4 * i + 3] / 255.0);
    }
    return image;
}

Image readImage(const std::filesystem::path& file) {
    const std::string format = imageFormat(file);
    if (format == "exr") return readExr(file);
    if (format == "png") return readPng(file);
    throw InputError(file, "unknown image format '" + file.extension().string() + "' (expected .exr or .png)");
}

void writePng(const Image& image, const std::filesystem::path& file) {
    AtomicOutputFile out(file);
    writePng(image, out);
    out.commit();
}

void writePng(const Image& image, AtomicOutputFile& out) {
    const std::filesystem::path& file = out.target();
    ingest::Image display;
    display.width = image.width;
    display.height = image.height;
    display.rgba.resize(image.pixels() * 4);
    for (std::size_t i = 0; i < image.pixels(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const double v = std::isfinite(image.rgba[4 * i + c]) ? image.rgba[4 * i + c] : 0.0;
            display.rgba[4 * i + c] = std::uint8_t(std::lround(255 * linearToSrgb(v)));
        }
        const double a = std::clamp(double(image.rgba[4 * i + 3]), 0.0, 1.0);
        display.rgba[4 * i + 3] = std::uint8_t(std::lround(255 * (std::isfinite(a) ? a : 0.0)));
    }
    std::string bytes;
    try {
        bytes = ingest::encodePng(display);
    } catch (const std::runtime_error& e) {
        throw IoError(file, std::string("cannot encode PNG: ") + e.what());
    }
    out.stream().write(bytes.data(), std::streamsize(bytes.size()));
}

Image downsample2x(const Image& image) {
    Image out(image.width / 2, image.height / 2, false);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 4; ++c) {
                double sum = 0;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx)
                        sum += image.rgba[4 * (std::size_t(2 * y + dy) * std::size_t(image.width) + std::size_t(2 * x + dx)) + std::size_t(c)];
                out.rgba[4 * (std::size_t(y) * std::size_t(out.width) + std::size_t(x)) + std::size_t(c)] = float(sum / 4);
            }
    return out;
}

}  // namespace vtex::render
