// See demo_topiary.h.
#include "demo_topiary.h"

#include <vtex/core/atomic_file.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

namespace vtex::pipelines::detail {
namespace {

using Vec3 = Eigen::Vector3d;

struct SplitMix {
    std::uint64_t state;
    double next() {
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return double((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    }
};

bool inside(TopiaryShape shape, const Vec3& p) {
    switch (shape) {
    case TopiaryShape::Ball: return (p - Vec3(0.5, 0.5, 0.45)).norm() < 0.36;
    case TopiaryShape::Block: return (p.array() > Eigen::Array3d(0.22, 0.22, 0.08)).all() && (p.array() < Eigen::Array3d(0.78, 0.78, 0.64)).all();
    case TopiaryShape::Cone: {
        const double t = (p.z() - 0.08) / 0.8;  // 0 at the base, 1 at the tip
        return t > 0 && t < 1 && std::hypot(p.x() - 0.5, p.y() - 0.5) < 0.34 * (1 - t);
    }
    }
    return false;
}

// A mesh under construction: vertices and triangles (0-based).
struct Mesh {
    std::vector<Vec3> v;
    std::vector<std::array<std::size_t, 3>> f;
    void triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
        const std::size_t i = v.size();
        v.insert(v.end(), {a, b, c});
        f.push_back({i, i + 1, i + 2});
    }
    void quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
        triangle(a, b, c);
        triangle(a, c, d);
    }
    // The closed box between corners lo and hi.
    void box(const Vec3& lo, const Vec3& hi) {
        const auto c = [&](int i) { return Vec3(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()); };
        for (const auto& q : std::array<std::array<int, 4>, 6>{{{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}})
            quad(c(q[0]), c(q[1]), c(q[2]), c(q[3]));
    }
};

void element(Mesh& mesh, TopiaryElement kind, const Vec3& p, const Eigen::Matrix3d& turn) {
    const Vec3 x = turn.col(0), y = turn.col(1), z = turn.col(2);
    switch (kind) {
    case TopiaryElement::Leaves: {  // a leaf 0.05 across
        const double r = 0.025;
        mesh.quad(p - r * x - r * y, p + r * x - r * y, p + r * x + r * y, p - r * x + r * y);
        break;
    }
    case TopiaryElement::Needles: {  // a triangular prism 0.1 long, 0.006 across
        const double h = 0.05, w = 0.003;
        std::array<Vec3, 3> e;
        for (int k = 0; k < 3; ++k) {
            const double a = 2 * std::numbers::pi * k / 3;
            e[std::size_t(k)] = w * (std::cos(a) * x + std::sin(a) * y);
        }
        for (int k = 0; k < 3; ++k) {
            const Vec3& a = e[std::size_t(k)];
            const Vec3& b = e[std::size_t((k + 1) % 3)];
            mesh.quad(p + a - h * z, p + b - h * z, p + b + h * z, p + a + h * z);
        }
        break;
    }
    case TopiaryElement::Beads: {  // an octahedron of radius 0.02
        const double r = 0.02;
        const std::array<Vec3, 6> c = {p + r * x, p - r * x, p + r * y, p - r * y, p + r * z, p - r * z};
        for (int a : {0, 1})
            for (int b : {2, 3})
                for (int d : {4, 5}) mesh.triangle(c[std::size_t(a)], c[std::size_t(b)], c[std::size_t(d)]);
        break;
    }
    }
}

}  // namespace

void writeTopiaryObj(const std::filesystem::path& file, TopiaryShape shape, TopiaryElement kind, int count,
                     std::uint64_t seed) {
    SplitMix rng{seed * 0x2545F4914F6CDD1Dull + std::uint64_t(shape) * 3 + std::uint64_t(kind)};
    Mesh mesh;
    for (int placed = 0, tries = 0; placed < count && tries < 100 * count; ++tries) {
        const Vec3 p(rng.next(), rng.next(), rng.next());
        if (!inside(shape, p)) continue;
        const Eigen::Quaterniond q(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5);
        element(mesh, kind, p, q.normalized().toRotationMatrix());
        ++placed;
    }
    // The frame: bars 0.02 thick along the twelve edges of [0.01, 0.99]² × [0, 0.98].
    const double lo = 0.01, hi = 0.99, top = 0.98, t = 0.02;
    for (double a : {lo, hi - t}) {
        for (double b : {lo, hi - t}) mesh.box(Vec3(a, b, 0), Vec3(a + t, b + t, top));  // uprights
        for (double z : {0.0, top - t}) {
            mesh.box(Vec3(lo, a, z), Vec3(hi, a + t, z + t));  // along x
            mesh.box(Vec3(a, lo, z), Vec3(a + t, hi, z + t));  // along y
        }
    }
    std::ostringstream obj;
    obj.precision(7);
    obj << "# vtex demo: Fig. 5, a trimmed bush in its frame, " << mesh.f.size() << " triangles\n";
    for (const Vec3& p : mesh.v) obj << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    for (const auto& f : mesh.f) obj << "f " << f[0] + 1 << ' ' << f[1] + 1 << ' ' << f[2] + 1 << '\n';
    writeFileAtomically(file, obj.str());
}

}  // namespace vtex::pipelines::detail
