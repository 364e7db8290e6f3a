// Random chords of boxes, shared by the chord measure and the density fit. Internal.
#pragma once

#include <vtex/octree/ellipsoid.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace vtex::octree::detail {

// A pure function of its inputs (splitmix64 finaliser), so chords do not depend on threads.
inline std::uint64_t mix(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

struct ChordRng {
    std::uint64_t state;
    double next() {
        state = mix(state);
        return double(state >> 11) * 0x1.0p-53;
    }
};

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


}  // namespace vtex::octree::detail
