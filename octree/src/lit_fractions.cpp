// See chord_transmittance.h, measureLitFractions.
#include <vtex/octree/chord_transmittance.h>

#include "chord_sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace vtex::octree {
namespace {

using detail::ChordRng;
using detail::mix64;
using detail::Segments;
using detail::shadowDepth;
using detail::toTheTop;

// The point of the chord at which its optical depth (∫ρÂ · scale) reaches `target`; the chord's
// end where it never does (rounding). Inside a profiled voxel the density is taken as its mean
// over the segment (DensityProfile::meanFactor): the renderer shades such a voxel at its
// segment's middle, too.
Vec3 pointAtDepth(const ChordMedium& medium, std::uint32_t level, const Segments& segments, double scale,
                  double target) {
    double depth = 0;
    for (const auto& segment : segments) {
        // Not a structured binding: Clang 14 (the fuzz build) cannot capture one in a lambda.
        const Vec3& a = segment.first;
        const Vec3 w = (segment.second - a).normalized();
        DensityProfile::Line line(medium.profile(), int(level), a, w);
        std::optional<Vec3> found;
        medium.forEachVoxel(level, a, segment.second, [&](double extinction, double t0, double t1) {
            const double sigma = scale * extinction * line.mean(t0, t1);
            if (sigma > 0 && depth + sigma * (t1 - t0) >= target) found = a + (t0 + (target - depth) / sigma) * w;
            else depth += sigma * (t1 - t0);
            return !found;
        });
        if (found) return *found;
    }
    return segments.back().second;
}

// What one chord gives: whether the mesh sees a surface there and lights it; per camera level the
// volume's opacity and, per shadow level, its transmittance toward the light.
struct ChordLight {
    bool seen = false, lit = false;
    std::vector<double> opacity, shadow;  ///< [c], [c · levels + l]
};

}  // namespace

LitFractions measureLitFractions(const ChordMedium& medium, const ChordFirstHit& hit, const ChordVisibility& visible,
                                 double tau, const std::vector<double>& scales, std::size_t finestShadowLevel,
                                 int chords, std::uint64_t seed, const LitPairs& wanted,
                                 const std::vector<double>& ownShares) {
    const Octree& tree = medium.tree();
    const std::size_t levels = std::min(scales.size(), tree.levels.size());
    // Camera level c needs shadow levels c − 1 and finer: none past finestShadowLevel.
    const std::size_t shadowEnd = std::min(finestShadowLevel + 1, levels), cameraEnd = shadowEnd;
    LitFractions out;
    out.volume.assign(cameraEnd, std::vector<double>(levels, std::numeric_limits<double>::quiet_NaN()));
    if (chords <= 0 || levels == 0) return out;
    // A shadow ray leaves a mesh surface this far along the light (1e-5 of the cube, the renderer's
    // gap) so that the surface does not shadow itself.
    constexpr double kGap = 1e-5;
    const auto firstShadow = [](std::size_t c) { return c == 0 ? std::size_t(0) : c - 1; };
    const auto measured = [&](std::size_t c, std::size_t l) { return !wanted || wanted(c, l); };
    std::vector<ChordLight> traced(static_cast<std::size_t>(chords));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, traced.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t j = r.begin(); j != r.end(); ++j) {
            ChordRng rng{mix64(seed ^ mix64(0x117ull + std::uint64_t(j)))};
            const Segments chord = detail::randomShellChord(rng);
            const Vec3 light = detail::randomUpward(rng);
            const double u = rng.next();
            ChordLight& t = traced[j];
            for (const auto& [a, b] : chord)
                if (const std::optional<double> s = hit(a, b)) {
                    t.seen = true;
                    t.lit = true;
                    for (const auto& [c, d] : toTheTop(a + *s * (b - a) + kGap * light, light)) t.lit = t.lit && visible(c, d);
                    break;
                }
            t.opacity.assign(cameraEnd, 0.0);
            t.shadow.assign(cameraEnd * levels, 0.0);
            for (std::size_t c = 0; c < cameraEnd; ++c) {
                const double scale = tau * scales[c];
                const double alpha = 1 - std::exp(-scale * detail::chordDepth(medium, std::uint32_t(c), chord));
                t.opacity[c] = alpha;
                if (!(alpha > 0)) continue;
                // Inverse-CDF sampling of the weight T·σ: the depth d at which 1 − e^−d = u·α.
                const Vec3 p = pointAtDepth(medium, std::uint32_t(c), chord, scale, -std::log1p(-u * alpha));
                for (std::size_t l = firstShadow(c); l < shadowEnd; ++l)
                    if (measured(c, l)) {
                        const double own = l < ownShares.size() ? ownShares[l] : 0.0;
                        t.shadow[c * levels + l] = std::exp(-tau * scales[l] * shadowDepth(medium, std::uint32_t(l), p, light, own));
                    }
            }
        }
    });
    double seen = 0, lit = 0;  // in chord order: the same whatever the schedule
    for (const ChordLight& t : traced) {
        seen += t.seen;
        lit += t.lit;
    }
    out.mesh = seen > 0 ? lit / seen : 1;
    out.seen = std::size_t(seen);
    for (std::size_t c = 0; c < cameraEnd; ++c) {
        double weight = 0;
        std::vector<double> sum(levels, 0.0);
        for (const ChordLight& t : traced) {
            weight += t.opacity[c];
            for (std::size_t l = firstShadow(c); l < shadowEnd; ++l) sum[l] += t.opacity[c] * t.shadow[c * levels + l];
        }
        for (std::size_t l = firstShadow(c); l < shadowEnd; ++l)
            if (measured(c, l)) out.volume[c][l] = weight > 0 ? sum[l] / weight : 1;
    }
    return out;
}

}  // namespace vtex::octree
