// Random chords of a texel, shared by the measures of chord_transmittance.cpp and
// lit_fractions.cpp (and bench/chord_families.cpp): a counter-based generator (a pure function of
// seed and chord index, so that a measure does not depend on the thread count), the isotropic
// chords of inspect's measure, the shell's cosine-weighted directions, the
// tiling of a segment into unit-cube pieces, a shadow ray's depth to the top.
#pragma once

#include <vtex/octree/chord_medium.h>
#include <vtex/octree/octree.h>

#include "hash.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace vtex::octree::detail {

struct ChordRng {
    std::uint64_t state;
    double next() {
        state = mix64(state);
        return double(state >> 11) * 0x1.0p-53;
    }
};

using Segments = std::vector<std::pair<Vec3, Vec3>>;

struct Chord {
    Vec3 a, b, direction;
    double length = 0;
};

// An isotropic uniform random line through the box [lo, lo + h]³: a uniform direction, then an
// entry point uniform over the box's projection along it, drawn as a face facing −ω chosen with
// probability ∝ |ω_axis| (the faces' projected areas) and a uniform point on that face.
inline Chord randomChord(const Vec3& lo, double h, ChordRng& rng) {
    const double z = 2 * rng.next() - 1, phi = 2 * std::numbers::pi * rng.next();
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    const Vec3 w(r * std::cos(phi), r * std::sin(phi), z);
    const Vec3 aw = w.cwiseAbs();
    const double pick = rng.next() * (aw.x() + aw.y() + aw.z());
    const int axis = pick < aw.x() ? 0 : pick < aw.x() + aw.y() ? 1 : 2;
    Vec3 entry = lo + h * Vec3(rng.next(), rng.next(), rng.next());
    entry[axis] = w[axis] > 0 ? lo[axis] : lo[axis] + h;
    // Exit: the nearest of the three far faces along w.
    double t = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
        if (aw[k] < 1e-300) continue;
        const double face = w[k] > 0 ? lo[k] + h : lo[k];
        t = std::min(t, (face - entry[k]) / w[k]);
    }
    t = std::max(t, 0.0);
    return {entry, entry + t * w, w, t};
}

/// A direction of the upper hemisphere, cosine-weighted (the flux through a horizontal face), zenith
/// angles up to 80°: cos² uniform over [cos² 80°, 1].
inline Vec3 randomUpward(ChordRng& rng) {
    constexpr double kMinCos = 0.17364817766693033;  // cos 80°
    const double mu = std::sqrt(kMinCos * kMinCos + (1 - kMinCos * kMinCos) * rng.next());
    const double phi = 2 * std::numbers::pi * rng.next();
    const double sinTheta = std::sqrt(std::max(0.0, 1 - mu * mu));
    return {sinTheta * std::cos(phi), sinTheta * std::sin(phi), mu};
}

/// The segment a → a + delta cut where it crosses the tiling's x and y planes into segments of
/// the unit cube, each shifted back into it (the texel tiled in x and y, as a flat field repeats it).
inline Segments tiledSegments(const Vec3& a, const Vec3& delta) {
    std::vector<double> cuts{0.0, 1.0};
    for (int k = 0; k < 2; ++k) {
        if (!(std::abs(delta[k]) > 0)) continue;
        const double lo = std::min(a[k], a[k] + delta[k]), hi = std::max(a[k], a[k] + delta[k]);
        for (double plane = std::floor(lo) + 1; plane < hi; plane += 1) cuts.push_back((plane - a[k]) / delta[k]);
    }
    std::sort(cuts.begin(), cuts.end());
    Segments segments;
    for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
        if (!(cuts[i + 1] > cuts[i])) continue;
        const Vec3 middle = a + 0.5 * (cuts[i] + cuts[i + 1]) * delta;
        const Vec3 shift(std::floor(middle.x()), std::floor(middle.y()), 0.0);
        const auto inCube = [&](double t) { return (a + t * delta - shift).cwiseMax(Vec3::Zero()).cwiseMin(Vec3::Ones()).eval(); };
        segments.emplace_back(inCube(cuts[i]), inCube(cuts[i + 1]));
    }
    return segments;
}

/// A shell chord (see ShellChordFit): from a uniform point of the top face down to the floor along
/// a cosine-weighted direction, through the tiled texel.
inline Segments randomShellChord(ChordRng& rng) {
    const Vec3 up = randomUpward(rng);
    const Vec3 a(rng.next(), rng.next(), 1.0);
    return tiledSegments(a, Vec3(up.x(), up.y(), -up.z()) / up.z());  // down to z = 0
}

/// The optical depth of `level` along a chord cut into segments (ChordMedium::depth of each).
inline double chordDepth(const ChordMedium& medium, std::uint32_t level, const Segments& segments) {
    double depth = 0;
    for (const auto& [a, b] : segments) depth += medium.depth(level, a, b);
    return depth;
}

/// The segments from p along the unit upward direction `up` to the top face, through the tiled texel.
inline Segments toTheTop(const Vec3& p, const Vec3& up) { return tiledSegments(p, up * (std::max(0.0, 1 - p.z()) / up.z())); }

/// The optical depth ∫ρÂ toward the top from p along the unit upward `up` at `level`, through the
/// tiled texel, the density of the voxel p lies in times 1 − ownShare up to where the ray leaves it
/// (voxelExit): a shadow ray from a lit voxel as the renderer's queries take it, the piece it
/// lights not shadowing it (docs/render.md, "A lit voxel's own leaf").
inline double shadowDepth(const ChordMedium& medium, std::uint32_t level, const Vec3& p, const Vec3& up, double ownShare) {
    if (ownShare == 0) return chordDepth(medium, level, toTheTop(p, up));
    const Vec3 end = p + voxelExit(p, up, int(level), std::max(0.0, 1 - p.z()) / up.z()) * up;
    return (1 - ownShare) * medium.depth(level, p, end) + chordDepth(medium, level, toTheTop(end, up));
}

}  // namespace vtex::octree::detail
