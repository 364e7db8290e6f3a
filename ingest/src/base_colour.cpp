// Base-colour lookups shared by the sampler (averages over voxel pieces) and the reference
// renderer (one value per hit point), so that both see the same colours.
#include <vtex/ingest/mesh.h>

#include <array>
#include <cmath>

namespace vtex::ingest {
namespace {

const std::array<float, 256>& srgbToLinearTable() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) {
            const double c = i / 255.0;
            t[std::size_t(i)] = float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
        }
        return t;
    }();
    return table;
}

}  // namespace

Eigen::Vector3f sampleBaseColour(const Image& image, float u, float v) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4)
        return Eigen::Vector3f::Ones();
    if (!std::isfinite(u) || !std::isfinite(v)) return Eigen::Vector3f::Ones();
    // REPEAT: only the fractional part matters, and taking it first keeps the pixel indices
    // small for any UV.
    u -= std::floor(u);
    v -= std::floor(v);
    const auto& lut = srgbToLinearTable();
    const float x = u * float(image.width) - 0.5f, y = v * float(image.height) - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    auto wrap = [](long i, int n) { return int(((i % n) + n) % n); };
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const int px = wrap(long(fx) + dx, image.width), py = wrap(long(fy) + dy, image.height);
            const std::uint8_t* p = &image.rgba[(std::size_t(py) * std::size_t(image.width) + std::size_t(px)) * 4];
            const float w = (dx ? tx : 1 - tx) * (dy ? ty : 1 - ty);
            sum += w * Eigen::Vector3f(lut[p[0]], lut[p[1]], lut[p[2]]);
        }
    return sum;
}

}  // namespace vtex::ingest
