// See chord_transmittance.h.
#include <vtex/octree/chord_transmittance.h>

#include <vtex/octree/voxel.h>

#include "chord_sampling.h"
#include "hash.h"


#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace vtex::octree {
namespace {

using detail::ChordRng;
using detail::mix64;
using detail::Chord;
using detail::randomChord;
using detail::randomShellChord;

}  // namespace

void forEachVoxelOnSegment(const Octree& tree, std::uint32_t level, const Vec3& a, const Vec3& b,
                           const std::function<void(const OctreeNode&, double, double)>& visit) {
    detail::walkOctree(tree, level, a, b, [&](const OctreeNode& node, double t0, double t1) {
        visit(node, t0, t1);
        return true;
    });
}

namespace {

// measureChordTransmittance's one body: levels 0 … levels − 1, level l at τ = tauAt(l).
std::vector<ChordTransmittance> measureChords(const ChordMedium& medium, const ChordVisibility& visible,
                                              const std::function<double(std::size_t)>& tauAt, std::size_t levels,
                                              int chords, std::uint64_t seed, const EnoughLevels& enough) {
    const Octree& tree = medium.tree();
    std::vector<ChordTransmittance> out(std::min(levels, tree.levels.size()));
    if (chords <= 0) return out;
    const std::size_t count = std::size_t(chords);
    std::vector<Chord> lines(count);
    std::vector<char> misses(count, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t j = r.begin(); j != r.end(); ++j) {
            ChordRng rng{mix64(seed ^ mix64(0xC0FFEEull + std::uint64_t(j)))};
            lines[j] = randomChord(Vec3::Zero(), 1.0, rng);
            misses[j] = visible(lines[j].a, lines[j].b) ? 1 : 0;
        }
    });
    double visibility = 0;
    for (char m : misses) visibility += m;
    visibility /= double(count);
    for (std::size_t level = 0; level < out.size(); ++level) {
        const double tau = tauAt(level);
        std::vector<double> transmittance(count);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t j = r.begin(); j != r.end(); ++j)
                transmittance[j] = std::exp(-tau * medium.depth(std::uint32_t(level), lines[j].a, lines[j].b));
        });
        double sum = 0;  // in chord order: the same whatever the schedule
        for (double t : transmittance) sum += t;
        out[level] = {visibility, sum / double(count)};
        if (enough && enough(level, out[level])) {
            out.resize(level + 1);
            break;
        }
    }
    return out;
}

}  // namespace

std::vector<ChordTransmittance> measureChordTransmittance(const ChordMedium& medium, const ChordVisibility& visible,
                                                          double tau, int chords, std::uint64_t seed) {
    return measureChordTransmittance(medium, visible, tau, chords, seed, {});
}

std::vector<ChordTransmittance> measureChordTransmittance(const ChordMedium& medium, const ChordVisibility& visible,
                                                          double tau, int chords, std::uint64_t seed,
                                                          const EnoughLevels& enough) {
    return measureChords(medium, visible, [tau](std::size_t) { return tau; }, medium.tree().levels.size(), chords, seed,
                         enough);
}

std::vector<ChordTransmittance> measureChordTransmittance(const ChordMedium& medium, const ChordVisibility& visible,
                                                          const std::vector<double>& tauPerLevel, int chords,
                                                          std::uint64_t seed) {
    return measureChords(medium, visible, [&](std::size_t l) { return tauPerLevel[l]; }, tauPerLevel.size(), chords, seed,
                         {});
}

namespace {

struct Beam {
    Vec3 origin, direction, across, up;  ///< a corner of the cross-section; its two edge directions
    double length = 0, side = 0;
};

// A beam of `level` (see BeamError): a uniform direction, then a corner drawn uniformly in the
// cube until the whole bundle (the four corners of both end squares) lies inside it.
Beam randomBeam(std::uint32_t level, ChordRng& rng) {
    const double h = std::ldexp(1.0, -int(level));
    Beam beam;
    beam.length = std::min(4 * h, 0.5);
    beam.side = std::min(h, 0.25);
    const double z = 2 * rng.next() - 1, phi = 2 * std::numbers::pi * rng.next();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    beam.direction = Vec3(r * std::cos(phi), r * std::sin(phi), z);
    beam.across = beam.direction.unitOrthogonal();
    beam.up = beam.direction.cross(beam.across);
    const auto inside = [](const Vec3& p) { return (p.array() >= 0.0).all() && (p.array() <= 1.0).all(); };
    for (int attempt = 0; attempt < 10000; ++attempt) {
        beam.origin = Vec3(rng.next(), rng.next(), rng.next());
        bool fits = true;
        for (int c = 0; c < 8 && fits; ++c)
            fits = inside(beam.origin + (c & 1 ? beam.side : 0.0) * beam.across + (c & 2 ? beam.side : 0.0) * beam.up +
                          (c & 4 ? beam.length : 0.0) * beam.direction);
        if (fits) return beam;
    }
    beam.length = 0;  // cannot happen for length ≤ 0.5 and side ≤ 0.25; an empty beam counts nothing
    return beam;
}

double percentile95(std::vector<double> values) {
    if (values.empty()) return 0;
    const std::size_t k = std::min(values.size() - 1, std::size_t(std::ceil(0.95 * double(values.size()))) - 1);
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
    return values[k];
}

// The chords of fitShellChords: whether each misses the source, and its optical depth ∫ρÂ at
// every level.
struct ShellChords {
    std::vector<char> misses;
    std::vector<std::vector<double>> depth;  ///< [level][chord]
};
ShellChords traceShellChords(const ChordMedium& medium, const ChordVisibility& visible, int chords, std::uint64_t seed,
                             std::size_t firstLevel, std::size_t endLevel) {
    const std::size_t count = std::size_t(std::max(chords, 0));
    ShellChords out;
    out.misses.assign(count, 0);
    out.depth.assign(endLevel - firstLevel, std::vector<double>(count, 0.0));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t j = r.begin(); j != r.end(); ++j) {
            ChordRng rng{mix64(seed ^ mix64(0x5E11ull + std::uint64_t(j)))};
            const auto segments = randomShellChord(rng);
            bool misses = true;
            for (const auto& [a, b] : segments) misses = misses && visible(a, b);
            out.misses[j] = misses ? 1 : 0;
            for (std::size_t level = firstLevel; level < endLevel; ++level)
                for (const auto& [a, b] : segments) out.depth[level - firstLevel][j] += medium.depth(std::uint32_t(level), a, b);
        }
    });
    return out;
}

double meanTransmittance(const std::vector<double>& depth, double tauScale) {
    double sum = 0;  // in chord order: the same whatever the schedule
    for (double d : depth) sum += std::exp(-tauScale * d);
    return depth.empty() ? 0 : sum / double(depth.size());
}

double meanMisses(const std::vector<char>& misses) {
    double sum = 0;
    for (char m : misses) sum += m;
    return misses.empty() ? 0 : sum / double(misses.size());
}

}  // namespace

std::vector<ShellChordFit> fitShellChords(const ChordMedium& medium, const ChordVisibility& visible, double tau, int chords,
                                          std::uint64_t seed, std::uint32_t finestLevel) {
    const Octree& tree = medium.tree();
    std::vector<ShellChordFit> out(std::min(tree.levels.size(), std::size_t(finestLevel) + 1));
    if (chords <= 0 || out.empty()) return out;
    const ShellChords traced = traceShellChords(medium, visible, chords, seed, 0, out.size());
    const double visibility = meanMisses(traced.misses);
    for (std::size_t level = 0; level < out.size(); ++level) {
        const std::vector<double>& depth = traced.depth[level];
        ShellChordFit& fit = out[level];
        fit.visibility = visibility;
        fit.transmittance = meanTransmittance(depth, tau);
        if (std::all_of(depth.begin(), depth.end(), [](double d) { return !(d > 0); })) continue;
        // The mean transmittance falls strictly with the scale: bisection in log scale.
        double lo = std::log(1.0 / 64), hi = std::log(64.0);
        if (meanTransmittance(depth, tau * std::exp(hi)) >= visibility) lo = hi;
        else if (meanTransmittance(depth, tau * std::exp(lo)) <= visibility) hi = lo;
        for (int i = 0; i < 64 && hi - lo > 1e-12; ++i) {
            const double mid = 0.5 * (lo + hi);
            (meanTransmittance(depth, tau * std::exp(mid)) > visibility ? lo : hi) = mid;
        }
        fit.scale = std::exp(0.5 * (lo + hi));
    }
    return out;
}

ShellChordFit measureShellChords(const ChordMedium& medium, const ChordVisibility& visible, std::uint32_t level, double scale,
                                 double tau, int chords, std::uint64_t seed) {
    const Octree& tree = medium.tree();
    ShellChordFit out;
    if (chords <= 0 || level >= tree.levels.size()) return out;
    const ShellChords traced = traceShellChords(medium, visible, chords, seed, level, level + 1);
    out.visibility = meanMisses(traced.misses);
    out.transmittance = meanTransmittance(traced.depth[0], tau * scale);
    out.scale = scale;
    return out;
}

std::vector<BeamError> measureBeamTransmittance(const ChordMedium& medium, const ChordVisibility& visible, double tau,
                                                int beams, int chordsPerBeam, std::uint64_t seed) {
    const Octree& tree = medium.tree();
    std::vector<BeamError> out(tree.levels.size());
    const int grid = int(std::sqrt(double(std::max(chordsPerBeam, 1))));
    if (beams <= 0 || grid <= 0) return out;
    for (std::size_t level = 0; level < tree.levels.size(); ++level) {
        std::vector<double> error(std::size_t(beams), 0.0), noise(std::size_t(beams), 0.0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, std::size_t(beams), 4), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t j = r.begin(); j != r.end(); ++j) {
                ChordRng rng{mix64(seed ^ mix64(0xBEA3ull + 0x9E37ull * level + (std::uint64_t(j) << 20)))};
                const Beam beam = randomBeam(std::uint32_t(level), rng);
                if (!(beam.length > 0)) continue;
                double missing = 0, transmitted = 0;
                for (int u = 0; u < grid; ++u)
                    for (int v = 0; v < grid; ++v) {
                        // Stratified: one jittered chord per cell of the cross-section's grid.
                        const Vec3 a = beam.origin + beam.side * ((u + rng.next()) / grid) * beam.across +
                                       beam.side * ((v + rng.next()) / grid) * beam.up;
                        const Vec3 b = a + beam.length * beam.direction;
                        missing += visible(a, b) ? 1 : 0;
                        transmitted += std::exp(-tau * medium.depth(std::uint32_t(level), a, b));
                    }
                const double n = double(grid) * double(grid), f = missing / n;
                error[j] = transmitted / n - f;
                noise[j] = std::sqrt(f * (1 - f) / n);
            }
        });
        BeamError e;
        std::vector<double> magnitude(error.size());
        for (std::size_t j = 0; j < error.size(); ++j) {  // in beam order: the same whatever the schedule
            e.mean += error[j];
            e.meanAbs += std::abs(error[j]);
            e.noise += noise[j];
            magnitude[j] = std::abs(error[j]);
        }
        e.mean /= double(beams);
        e.meanAbs /= double(beams);
        e.noise /= double(beams);
        e.p95Abs = percentile95(std::move(magnitude));
        out[level] = e;
    }
    return out;
}

}  // namespace vtex::octree
