// Issue 13's coarse levels against both chord families at once (docs/error-vs-time.md, "Issue 13's
// coarse levels with a factor that depends on the chord's direction" and "A vertical profile
// inside the coarse voxels"): `vtex inspect`'s isotropic chords of one texel and the level fit's
// cosine-weighted shell chords through the tiled texel (octree/src/chord_sampling.h), each drawn
// twice (draw A fits, draw B checks). Per level 0–4, the model transmittance is
// T = exp(−k (D + b X)), D = ∫ρÂ as the renderer marches it, X one of:
//   direction  (w_z² − ⅓) D                    (the chord's direction)
//   linear     ∫ρÂ (z − ½)                     (a vertical gradient of the voxel's density)
//   bulge      ∫ρÂ ((z − ½)² − 1/12)           (a vertical bulge)
//   data       ∫ρÂ (p(z) − 1), b = 1           (the finer level's own layer profile, no free b)
// where p(z) is level 6's mean density in z's layer over its mean across the coarse voxel's
// height. Printed: k fitted on the shell chords alone (as the renderer fits it) and the
// isotropic error, without and with the data profile; then for each model the (k, b) that
// minimises the larger of the two families' mean errors on draw A, and on draw B the whole
// families' errors and the isotropic and shell errors binned by w_z² and (isotropic) by height.
//   usage: vtex_chord_families TEXEL.vto SOURCE_MESH [CHORDS]
#include <vtex/ingest/ingest.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/render/source_visibility.h>

#include "../octree/src/chord_sampling.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

namespace {

using namespace vtex;
using Vec3 = Eigen::Vector3d;
using octree::detail::ChordRng;
using octree::detail::Segments;

constexpr int kLevels = 5;
constexpr int kProfileLevel = 6;
enum Model { kNone, kDirection, kLinear, kBulge, kData, kModels };
const char* const kModelNames[kModels] = {"one factor", "direction", "linear", "bulge", "data"};

// Level kProfileLevel's mean density per z-layer (averaged over x and y).
std::vector<double> layerMeans(const octree::Octree& tree) {
    const int n = 1 << kProfileLevel;
    std::vector<double> layers(std::size_t(n), 0.0);
    for (int x = 0; x < n; ++x)
        for (int y = 0; y < n; ++y) {
            const Vec3 a((x + 0.5) / n, (y + 0.5) / n, 0), b((x + 0.5) / n, (y + 0.5) / n, 1);
            octree::forEachVoxelOnSegment(tree, kProfileLevel, a, b, [&](const octree::OctreeNode& node, double t0, double t1) {
                layers[std::size_t(std::clamp(int(0.5 * (t0 + t1) * n), 0, n - 1))] += double(node.data.density) * (t1 - t0);
            });
        }
    return layers;
}

// p(z) of a voxel of `level`: its layer's mean over the mean of the layers the voxel spans.
double profile(const std::vector<double>& layers, int level, double z) {
    const int n = int(layers.size()), per = n >> level;
    const int i = std::clamp(int(z * n), 0, n - 1);
    if (per <= 1) return 1;
    double mean = 0;
    for (int k = i / per * per; k < (i / per + 1) * per; ++k) mean += layers[std::size_t(k)] / per;
    return mean > 0 ? layers[std::size_t(i)] / mean : 1;
}

struct Family {
    std::vector<char> misses;
    std::vector<double> wz2, height;
    std::array<std::array<std::vector<double>, kModels>, kLevels> depth;  ///< [level][model]: D, then X
};

Family trace(const octree::Octree& tree, const octree::ChordVisibility& visible, const std::vector<double>& layers,
             int chords, bool shell, std::uint64_t seed) {
    Family f;
    const std::size_t count = std::size_t(chords);
    f.misses.assign(count, 0);
    f.wz2.assign(count, 0);
    f.height.assign(count, 0);
    for (auto& level : f.depth)
        for (auto& model : level) model.assign(count, 0);
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t j) {
        ChordRng rng{octree::detail::mix64(seed ^ octree::detail::mix64(j + (shell ? 0x5E11ull : 0xC0FFEEull)))};
        Segments segments;
        if (shell) {
            segments = octree::detail::randomShellChord(rng);
        } else {
            const octree::detail::Chord c = octree::detail::randomChord(Vec3::Zero(), 1.0, rng);
            segments.emplace_back(c.a, c.b);
        }
        bool misses = true;
        double heightSum = 0, length = 0;
        for (const auto& [a, b] : segments) {
            misses = misses && visible(a, b);
            heightSum += 0.5 * (a.z() + b.z()) * (b - a).norm();
            length += (b - a).norm();
        }
        f.misses[j] = misses;
        const Vec3 w = (segments.front().second - segments.front().first).normalized();
        f.wz2[j] = w.z() * w.z();
        f.height[j] = length > 0 ? heightSum / length : 0.5;
        for (int l = 0; l < kLevels; ++l) {
            auto& d = f.depth[std::size_t(l)];
            for (const auto& [a, b] : segments) {
                const double len = (b - a).norm();
                if (!(len > 0)) continue;
                const Vec3 u = (b - a) / len;
                octree::forEachVoxelOnSegment(tree, std::uint32_t(l), a, b, [&](const octree::OctreeNode& node, double t0, double t1) {
                    const double e = octree::voxelExtinction(node, u) * (t1 - t0);
                    const double z = a.z() + u.z() * 0.5 * (t0 + t1);  // z is linear along the piece
                    double p = 0;  // the data profile, averaged over the piece at 16 points
                    for (int q = 0; q < 16; ++q) p += profile(layers, l, a.z() + u.z() * (t0 + (q + 0.5) / 16 * (t1 - t0))) / 16;
                    d[kNone][j] += e;
                    d[kLinear][j] += e * (z - 0.5);
                    d[kBulge][j] += e * ((z - 0.5) * (z - 0.5) - 1.0 / 12);
                    d[kData][j] += e * (p - 1);
                });
            }
            d[kDirection][j] = (f.wz2[j] - 1.0 / 3) * d[kNone][j];
        }
    });
    return f;
}

// Mean model transmittance minus the fraction that misses, over the chords whose key (w_z² or
// height) lies in [lo, hi).
double error(const Family& f, int level, Model model, double k, double b, bool byHeight = false, double lo = -1,
             double hi = 2) {
    const auto& d = f.depth[std::size_t(level)];
    double t = 0, v = 0, n = 0;
    for (std::size_t j = 0; j < f.misses.size(); ++j) {
        const double key = byHeight ? f.height[j] : f.wz2[j];
        if (key < lo || key >= hi) continue;
        n += 1;
        t += std::exp(-k * (d[kNone][j] + b * d[model][j]));
        v += f.misses[j];
    }
    return n > 0 ? (t - v) / n : 0;
}

// The factor k that zeroes `fit`'s error (the transmittance falls with k): bisection in log k.
double fitFactor(const Family& fit, int level, Model model, double b) {
    double lo = std::log(1.0 / 64), hi = std::log(64.0);
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (error(fit, level, model, std::exp(mid), b) > 0 ? lo : hi) = mid;
    }
    return std::exp(0.5 * (lo + hi));
}

// The b range each model's grid searches: where k (1 + b …) stays a density (b = 1 alone for data).
std::array<double, 2> bRange(Model model) {
    switch (model) {
    case kDirection: return {-1.5, 1.5};
    case kLinear: return {-2, 2};
    case kBulge: return {-6, 6};
    default: return {model == kData ? 1.0 : 0.0, model == kData ? 1.0 : 0.0};
    }
}

void printBins(const Family& iso, const Family& shell, int level, Model model, double k, double b) {
    std::printf("      by w_z² iso/shell:");
    for (int q = 0; q < 4; ++q) {
        const double lo = q * 0.25, hi = q == 3 ? 2 : lo + 0.25;
        std::printf(" %+.3f/%+.3f", error(iso, level, model, k, b, false, lo, hi), error(shell, level, model, k, b, false, lo, hi));
    }
    std::printf(" | iso by height:");
    for (int q = 0; q < 4; ++q) std::printf(" %+.3f", error(iso, level, model, k, b, true, q * 0.25, q == 3 ? 2 : q * 0.25 + 0.25));
    std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s TEXEL.vto SOURCE_MESH [CHORDS]\n", argv[0]);
        return 2;
    }
    try {
        const int chords = argc > 3 ? std::max(std::atoi(argv[3]), 16) : 16384;
        const auto tree = octree::openVto(argv[1]);
        tree->loadLevels(30);
        if (int(tree->levels.size()) <= kProfileLevel) throw std::runtime_error("the texel needs a level 6 (64³)");
        const ingest::TriangleMesh mesh = ingest::loadMesh(argv[2]);
        const render::SourceVisibility source(mesh, tree->info.source);
        const octree::ChordVisibility visible = [&](const Vec3& a, const Vec3& b) { return source.visible(a, b); };
        const std::vector<double> layers = layerMeans(*tree);
        std::printf("level %d's mean density per layer, bottom to top, every eighth:", kProfileLevel);
        for (std::size_t i = 0; i < layers.size(); i += 8) std::printf(" %.3g", layers[i]);
        std::printf("\n%d chords a family and draw\n", chords);
        const Family isoA = trace(*tree, visible, layers, chords, false, 1), shellA = trace(*tree, visible, layers, chords, true, 1);
        const Family isoB = trace(*tree, visible, layers, chords, false, 2), shellB = trace(*tree, visible, layers, chords, true, 2);
        for (int l = 0; l < kLevels; ++l) {
            std::printf("level %d\n  shell-fitted k, isotropic error draw A / B, shell draw B:", l);
            for (const Model model : {kNone, kData}) {
                const double b = model == kData ? 1 : 0, k = fitFactor(shellA, l, model, b);
                std::printf("  %s k %.3f: %+.4f / %+.4f, %+.4f;", kModelNames[model], k, error(isoA, l, model, k, b),
                            error(isoB, l, model, k, b), error(shellB, l, model, k, b));
            }
            std::printf("\n");
            for (int m = kNone; m < kModels; ++m) {
                const Model model = Model(m);
                const auto [bLo, bHi] = bRange(model);
                // The grid's rows in parallel, each its best; the first best row wins ties, as in a serial scan.
                struct Best {
                    double worst = INFINITY, k = 1, b = 0;
                };
                std::vector<Best> rows(401);
                tbb::parallel_for(0, 401, [&](int ik) {
                    const double k = std::exp(std::log(1.0 / 16) + std::log(256.0) * ik / 400);
                    for (int ib = 0; ib <= (bHi == bLo ? 0 : 120); ++ib) {
                        const double b = bLo + (bHi - bLo) * ib / 120;
                        const double worst = std::max(std::abs(error(isoA, l, model, k, b)), std::abs(error(shellA, l, model, k, b)));
                        if (worst < rows[std::size_t(ik)].worst) rows[std::size_t(ik)] = {worst, k, b};
                    }
                });
                Best best;
                for (const Best& row : rows)
                    if (row.worst < best.worst) best = row;
                const double bestK = best.k, bestB = best.b;
                std::printf("  minimax %-10s k %.3f b %+.3f: draw A %.4f; draw B iso %+.4f shell %+.4f\n", kModelNames[model],
                            bestK, bestB, best.worst, error(isoB, l, model, bestK, bestB), error(shellB, l, model, bestK, bestB));
                printBins(isoB, shellB, l, model, bestK, bestB);
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 3;
    }
}
