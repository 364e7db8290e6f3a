/// @file
/// @brief Where the points of a texel cell are in its texel's reference volume: the one map the
/// texel renderer, the reference renderer and the reference's deformed meshes all take, with the
/// per-face perturbation of the reference volume.
///
/// Paper §3: "agrandir, déplacer ou faire tourner le volume de référence pour chaque texel", to
/// avoid repeating the 3-D pattern exactly. Cell coordinates r = (u, v, w) ∈ [0,1]³
/// (geometry.h) go to tiled reference coordinates p = (A·(u, v) + b, w), where
///   - A = diag(extent) · S, S one of the eight symmetries of the unit square about its centre (a
///     quarter turn about z, then a mirror), extent the rectangle's size (`repeat`, or the
///     sub-rectangle's sides);
///   - b places the rectangle (`subrect`'s corner, 0 for `repeat`), makes S turn about the
///     square's centre, and adds the face's shift.
/// x and y beyond [0, 1) are the volume's tiled copies: the march and the source BVH take them
/// modulo 1, which is how `repeat` lays copies side by side. The inverse is exact (A is a scaled
/// signed permutation). The map is affine, so a straight segment in the cell is a straight
/// segment in reference space: the marchers' assumption is unchanged by it.
#pragma once

#include <vtex/render/scene.h>

#include <Eigen/Core>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vtex::render {

/// One face's transform, drawn from a Perturbation (drawFaceTransform).
struct FaceTransform {
    int quarterTurns = 0;   ///< counter-clockwise about the cell's vertical axis, 0…3
    bool mirror = false;    ///< x → 1 − x, after the turn
    Eigen::Vector2d shift{0, 0};  ///< reference units, in [0, 1)² (cyclic texels only)
};

/// The face's transform under `perturb`: a pure function of the seed and the face index (the
/// same face gets the same transform in every render and in both renderers). Off: the identity.
/// Turns and a mirror together reach all eight symmetries of the square (two mirrors make a
/// half turn, so one suffices).
inline FaceTransform drawFaceTransform(const Perturbation& perturb, std::uint64_t face) {
    FaceTransform t;
    if (!perturb.any()) return t;
    // SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators",
    // OOPSLA 2014) of seed and face: every bit of both reaches every bit drawn.
    std::uint64_t state = perturb.seed * 0x9E3779B97F4A7C15ull + face;
    const auto next = [&state] {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    };
    const std::uint64_t turn = next(), mirror = next(), sx = next(), sy = next();
    if (perturb.rotate) t.quarterTurns = int(turn & 3u);
    if (perturb.mirror) t.mirror = (mirror & 1u) != 0;
    // 53 random bits as a double in [0, 1).
    if (perturb.shift) t.shift = {double(sx >> 11) * 0x1p-53, double(sy >> 11) * 0x1p-53};
    return t;
}

/// The affine map of one cell into tiled reference space (see the file comment).
struct CellMap {
    Eigen::Matrix2d a = Eigen::Matrix2d::Identity();
    Eigen::Matrix2d aInverse = Eigen::Matrix2d::Identity();
    Eigen::Vector2d b{0, 0};

    /// Cell coordinates → tiled reference coordinates (z unchanged).
    Eigen::Vector3d toReference(const Eigen::Vector3d& r) const {
        const Eigen::Vector2d xy = a * r.head<2>() + b;
        return {xy.x(), xy.y(), r.z()};
    }
    /// Tiled reference coordinates → cell coordinates.
    Eigen::Vector3d toCell(const Eigen::Vector3d& p) const {
        const Eigen::Vector2d uv = aInverse * (p.head<2>() - b);
        return {uv.x(), uv.y(), p.z()};
    }
    /// ∂p/∂r: A with 1 for z.
    Eigen::Matrix3d linear() const {
        Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
        m.topLeftCorner<2, 2>() = a;
        return m;
    }
    /// ∂r/∂p.
    Eigen::Matrix3d linearInverse() const {
        Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
        m.topLeftCorner<2, 2>() = aInverse;
        return m;
    }
    /// Reference area per unit of cell area, |det A|.
    double areaScale() const { return std::abs(a.determinant()); }
    /// The longest side of the reference rectangle the cell shows.
    double maxExtent() const { return std::max(a.col(0).norm(), a.col(1).norm()); }
    /// The reference-space rectangle [lo, hi] the cell's unit square maps onto.
    void bounds(Eigen::Vector2d& lo, Eigen::Vector2d& hi) const {
        lo = hi = b;
        for (int c = 1; c < 4; ++c) {
            const Eigen::Vector2d p = a * Eigen::Vector2d(c & 1, c >> 1) + b;
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    }
};

/// The map of a face covered by `placing` with transform `t`: the rectangle [0, repeat] or
/// `subrect`, turned and mirrored about its cell's centre, then shifted.
inline CellMap makeCellMap(const TexelPlacing& placing, const FaceTransform& t) {
    Eigen::Vector2d corner(0, 0), extent(placing.repeat[0], placing.repeat[1]);
    if (placing.subrect) {
        const auto& r = *placing.subrect;
        corner = {r[0], r[1]};
        extent = {r[2] - r[0], r[3] - r[1]};
    }
    // S: the turns (counter-clockwise: (u, v) → (−v, u)), then the mirror, about (½, ½).
    Eigen::Matrix2d s = Eigen::Matrix2d::Identity();
    Eigen::Matrix2d quarter;
    quarter << 0, -1, 1, 0;
    for (int k = 0; k < (t.quarterTurns & 3); ++k) s = quarter * s;
    if (t.mirror) s.row(0) *= -1;
    const Eigen::Vector2d half(0.5, 0.5);
    CellMap map;
    map.a = extent.asDiagonal() * s;
    map.aInverse = s.transpose() * extent.cwiseInverse().asDiagonal();  // S is orthogonal
    // p = diag(extent)·(S·(r − ½) + ½) + corner + shift.
    map.b = extent.asDiagonal() * (half - s * half) + corner + t.shift;
    return map;
}

}  // namespace vtex::render
