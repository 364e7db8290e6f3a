// Procedural source patterns (F. Neyret 1994, Figs. 1, 5–8, 10, 11). See patterns.h.
#include <vtex/sampler/patterns.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace vtex::sampler {
namespace {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;
constexpr double kPi = std::numbers::pi;

// SplitMix64: the same numbers on every platform and standard library.
class Rng {
public:
    explicit Rng(std::uint64_t seed) : mState(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) {}
    std::uint64_t next() {
        std::uint64_t z = (mState += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    double uniform() { return double(next() >> 11) * 0x1.0p-53; }
    double uniform(double a, double b) { return a + (b - a) * uniform(); }
    double normal() {
        const double u = std::max(uniform(), 1e-300), v = uniform();
        return std::sqrt(-2 * std::log(u)) * std::cos(2 * kPi * v);
    }
    Vec3 unitVector() {
        const double z = uniform(-1, 1), phi = uniform(0, 2 * kPi), r = std::sqrt(std::max(0.0, 1 - z * z));
        return {r * std::cos(phi), r * std::sin(phi), z};
    }
    int index(int n) { return int(uniform() * n) % n; }

private:
    std::uint64_t mState;
};

// Any unit vector orthogonal to d.
Vec3 orthogonal(const Vec3& d) {
    const Vec3 other = std::abs(d.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    return d.cross(other).normalized();
}

// A direction tilted from `mean` by a Gaussian angle of standard deviation `sigma` (radians)
// around a uniformly random azimuth.
Vec3 fluctuate(const Vec3& mean, double sigma, Rng& rng) {
    const double angle = sigma * std::abs(rng.normal());
    const double azimuth = rng.uniform(0, 2 * kPi);
    const Vec3 u = orthogonal(mean), v = mean.cross(u);
    const Vec3 axis = std::cos(azimuth) * u + std::sin(azimuth) * v;
    return (std::cos(angle) * mean + std::sin(angle) * axis).normalized();
}

Vec3 leanDirection(double degrees) {
    const double a = degrees * kPi / 180;
    return {std::sin(a), 0, std::cos(a)};
}

class MeshBuilder {
public:
    int material(float r, float g, float b) {
        ingest::Material m;
        m.baseColorFactor = Eigen::Vector4f(r, g, b, 1);
        mMesh.materials.push_back(m);
        return int(mMesh.materials.size()) - 1;
    }
    std::uint32_t vertex(const Vec3& p, const Vec3& n, const Vec2& uv = Vec2::Zero()) {
        mMesh.positions.push_back(p.cast<float>());
        mMesh.normals.push_back(n.normalized().cast<float>());
        mMesh.uvs.push_back(uv.cast<float>());
        return std::uint32_t(mMesh.positions.size() - 1);
    }
    void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, int material) {
        const Vec3 pa = mMesh.positions[a].cast<double>(), pb = mMesh.positions[b].cast<double>(),
                   pc = mMesh.positions[c].cast<double>();
        if ((pb - pa).cross(pc - pa).norm() < 1e-14) return;  // ingest refuses zero-area faces
        mMesh.triangles.push_back({a, b, c});
        mMesh.triangleMaterials.push_back(std::uint32_t(material));
    }
    // A flat quad a b c d (counter-clockwise seen from its normal side).
    void quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, int material) {
        const Vec3 n = (c - a).cross(d - b);
        if (n.norm() < 1e-14) return;
        const auto ia = vertex(a, n, {0, 0}), ib = vertex(b, n, {1, 0}), ic = vertex(c, n, {1, 1}),
                   id = vertex(d, n, {0, 1});
        triangle(ia, ib, ic, material);
        triangle(ia, ic, id, material);
    }
    // An axis-aligned box [lo, hi], outward faces.
    void box(const Vec3& lo, const Vec3& hi, int material) {
        const Vec3 p[8] = {{lo.x(), lo.y(), lo.z()}, {hi.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), lo.z()},
                           {lo.x(), hi.y(), lo.z()}, {lo.x(), lo.y(), hi.z()}, {hi.x(), lo.y(), hi.z()},
                           {hi.x(), hi.y(), hi.z()}, {lo.x(), hi.y(), hi.z()}};
        quad(p[0], p[3], p[2], p[1], material);  // -z
        quad(p[4], p[5], p[6], p[7], material);  // +z
        quad(p[0], p[1], p[5], p[4], material);  // -y
        quad(p[2], p[3], p[7], p[6], material);  // +y
        quad(p[1], p[2], p[6], p[5], material);  // +x
        quad(p[3], p[0], p[4], p[7], material);  // -x
    }
    // A tube along the polyline `axis` with radius `radius(i)` at each point, `sides` facets,
    // smooth normals, open ends.
    template <class Radius>
    void tube(const std::vector<Vec3>& axis, Radius radius, int sides, int material) {
        const std::size_t rings = axis.size();
        Vec3 u = orthogonal((axis[1] - axis[0]).normalized());
        std::vector<std::uint32_t> previous;
        for (std::size_t i = 0; i < rings; ++i) {
            const Vec3 t = (axis[std::min(i + 1, rings - 1)] - axis[i > 0 ? i - 1 : 0]).normalized();
            u = (u - u.dot(t) * t).normalized();  // parallel transport keeps the facets untwisted
            const Vec3 v = t.cross(u);
            std::vector<std::uint32_t> ring;
            for (int s = 0; s < sides; ++s) {
                const double a = 2 * kPi * s / sides;
                const Vec3 n = std::cos(a) * u + std::sin(a) * v;
                ring.push_back(vertex(axis[i] + radius(i) * n, n, {double(s) / sides, double(i) / double(rings - 1)}));
            }
            if (!previous.empty())
                for (int s = 0; s < sides; ++s) {
                    const int s1 = (s + 1) % sides;
                    triangle(previous[std::size_t(s)], previous[std::size_t(s1)], ring[std::size_t(s1)], material);
                    triangle(previous[std::size_t(s)], ring[std::size_t(s1)], ring[std::size_t(s)], material);
                }
            previous = std::move(ring);
        }
    }
    // An ellipsoid with centre c, orthonormal axes (columns of R) and semi-axes r.
    void ellipsoid(const Vec3& c, const Eigen::Matrix3d& R, const Vec3& r, int material, int slices = 10,
                   int stacks = 6) {
        std::vector<std::uint32_t> grid;
        for (int i = 0; i <= stacks; ++i) {
            const double theta = kPi * i / stacks;
            for (int j = 0; j < slices; ++j) {
                const double phi = 2 * kPi * j / slices;
                const Vec3 unit(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
                const Vec3 p = c + R * unit.cwiseProduct(r);
                const Vec3 n = R * unit.cwiseQuotient(r);
                grid.push_back(vertex(p, n, {double(j) / slices, double(i) / stacks}));
            }
        }
        for (int i = 0; i < stacks; ++i)
            for (int j = 0; j < slices; ++j) {
                const int j1 = (j + 1) % slices;
                const auto a = grid[std::size_t(i * slices + j)], b = grid[std::size_t(i * slices + j1)];
                const auto c2 = grid[std::size_t((i + 1) * slices + j1)], d = grid[std::size_t((i + 1) * slices + j)];
                if (i > 0) triangle(a, d, c2, material);
                if (i + 1 < stacks) triangle(a, c2, b, material);
            }
    }

    ingest::TriangleMesh take() { return std::move(mMesh); }

private:
    ingest::TriangleMesh mMesh;
};

// Grass (Fig. 7): blades of V section narrowing to the tip, leaning and bending.
ingest::TriangleMesh grass(const PatternOptions& o) {
    Rng rng(o.seed);
    MeshBuilder mb;
    const int greens[4] = {mb.material(0.10f, 0.35f, 0.06f), mb.material(0.16f, 0.42f, 0.08f),
                           mb.material(0.22f, 0.45f, 0.10f), mb.material(0.30f, 0.50f, 0.12f)};
    const int blades = o.count > 0 ? o.count : 16;
    const double sigma = o.fluctuation >= 0 ? o.fluctuation : 0.25;
    const Vec3 mean = leanDirection(o.leanDegrees);
    constexpr int kSegments = 8;
    for (int b = 0; b < blades; ++b) {
        const Vec3 base(rng.uniform(), rng.uniform(), 0);
        const double height = rng.uniform(0.55, 0.9);
        const double width = rng.uniform(0.04, 0.07);
        const double fold = rng.uniform(0.35, 0.6);  // half-angle of the V from flat, radians
        const Vec3 dir = fluctuate(mean, sigma, rng);
        const double facingAngle = rng.uniform(0, 2 * kPi);
        const Vec3 facing0(std::cos(facingAngle), std::sin(facingAngle), 0);
        // Bends further along its own tilt as it rises (a blade droops the way it leans).
        Vec3 tilt = dir - dir.dot(Vec3::UnitZ()) * Vec3::UnitZ();
        tilt = tilt.norm() > 1e-9 ? Vec3(tilt.normalized()) : Vec3::UnitX();
        const double bend = 0.35 * sigma * rng.uniform(0.5, 1.5);
        const int material = greens[rng.index(4)];
        std::vector<Vec3> spine{base}, facing, side;
        std::vector<double> half;
        for (int k = 0; k <= kSegments; ++k) {
            const double s = double(k) / kSegments;
            const Vec3 d = (dir + bend * s * tilt).normalized();
            if (k > 0) spine.push_back(spine.back() + d * (height / kSegments));
            Vec3 f = facing0 - facing0.dot(d) * d;
            f = f.norm() > 1e-9 ? Vec3(f.normalized()) : orthogonal(d);
            facing.push_back(f);
            side.push_back(d.cross(f));
            half.push_back(0.5 * width * std::pow(1 - s, 0.8));
        }
        // Two wings folded toward the facing direction: points spine ± half·(cos·side) + half·sin·facing.
        for (int wing = -1; wing <= 1; wing += 2) {
            for (int k = 0; k < kSegments; ++k) {
                auto edge = [&](int i) {
                    return Vec3(spine[std::size_t(i)] + half[std::size_t(i)] * (wing * std::cos(fold) * side[std::size_t(i)] +
                                                                                std::sin(fold) * facing[std::size_t(i)]));
                };
                const Vec3 a = spine[std::size_t(k)], b = edge(k), c = edge(k + 1), d = spine[std::size_t(k + 1)];
                if (k + 1 < kSegments)
                    mb.quad(a, b, c, d, material);
                else {  // the tip: one triangle
                    const Vec3 n = (b - a).cross(d - a);
                    mb.triangle(mb.vertex(a, n), mb.vertex(b, n), mb.vertex(d, n), material);
                }
            }
        }
    }
    return wrapIntoUnitTile(mb.take());
}

// Bush (Figs. 5–6): a trimmed bush of flat elliptic leaves, denser toward its surface.
ingest::TriangleMesh bush(const PatternOptions& o) {
    Rng rng(o.seed);
    MeshBuilder mb;
    const int greens[4] = {mb.material(0.08f, 0.30f, 0.05f), mb.material(0.12f, 0.38f, 0.07f),
                           mb.material(0.18f, 0.42f, 0.06f), mb.material(0.10f, 0.25f, 0.08f)};
    const int leaves = o.count > 0 ? o.count : 2000;
    const Vec3 centre(0.5, 0.5, 0.5);
    constexpr double kRadius = 0.40;
    constexpr int kOutline = 8;
    for (int l = 0; l < leaves; ++l) {
        const Vec3 radial = rng.unitVector();
        const double r = kRadius * (0.55 + 0.45 * std::cbrt(rng.uniform()));
        const Vec3 c = centre + r * radial;
        const Vec3 n = (radial + 1.2 * rng.unitVector()).normalized();
        const Vec3 u = orthogonal(n), v = n.cross(u);
        const double angle = rng.uniform(0, 2 * kPi);
        const Vec3 along = std::cos(angle) * u + std::sin(angle) * v, across = n.cross(along);
        const double length = 0.03 * rng.uniform(0.8, 1.2), width = 0.45 * length;
        const int material = greens[rng.index(4)];
        const auto middle = mb.vertex(c, n, {0.5, 0.5});
        std::vector<std::uint32_t> rim;
        for (int k = 0; k < kOutline; ++k) {
            const double t = 2 * kPi * k / kOutline;
            rim.push_back(mb.vertex(c + length * std::cos(t) * along + width * std::sin(t) * across, n,
                                    {0.5 + 0.5 * std::cos(t), 0.5 + 0.5 * std::sin(t)}));
        }
        for (int k = 0; k < kOutline; ++k) mb.triangle(middle, rim[std::size_t(k)], rim[std::size_t((k + 1) % kOutline)], material);
    }
    return mb.take();
}

// Fur (Figs. 8, 10): thin cylinders rising from the base, fluctuating and bending.
ingest::TriangleMesh fur(const PatternOptions& o) {
    Rng rng(o.seed);
    MeshBuilder mb;
    const int browns[3] = {mb.material(0.35f, 0.22f, 0.12f), mb.material(0.45f, 0.30f, 0.16f),
                           mb.material(0.25f, 0.15f, 0.08f)};
    const int hairs = o.count > 0 ? o.count : 300;
    const double sigma = o.fluctuation >= 0 ? o.fluctuation : 0.15;
    const Vec3 mean = leanDirection(o.leanDegrees);
    constexpr int kSegments = 6;
    for (int h = 0; h < hairs; ++h) {
        const Vec3 base(rng.uniform(), rng.uniform(), 0);
        const double length = rng.uniform(0.6, 0.85), radius = rng.uniform(0.004, 0.007);
        const Vec3 dir = fluctuate(mean, sigma, rng);
        const Vec3 droop = fluctuate(Vec3(dir.x(), dir.y(), 0).norm() > 1e-6 ? Vec3(dir.x(), dir.y(), 0).normalized()
                                                                              : Vec3::UnitX(),
                                     0.3, rng);
        const double bend = 0.4 * rng.uniform();
        std::vector<Vec3> axis{base};
        for (int k = 1; k <= kSegments; ++k) {
            const double s = double(k) / kSegments;
            axis.push_back(axis.back() + (dir + bend * s * droop).normalized() * (length / kSegments));
        }
        const int material = browns[rng.index(3)];
        mb.tube(axis, [&](std::size_t i) { return radius * (1 - 0.6 * double(i) / kSegments); }, 6, material);
    }
    return wrapIntoUnitTile(mb.take());
}

// Brushed aluminium (Fig. 1): elongated ellipsoids ("cylinders") along concentric rings that
// turn progressively into spheres toward the rim, or along radial spokes.
ingest::TriangleMesh brushed(const PatternOptions& o) {
    Rng rng(o.seed);
    MeshBuilder mb;
    const int metal = mb.material(0.85f, 0.86f, 0.88f);
    const bool radial = o.variant == "radial";
    if (!o.variant.empty() && o.variant != "radial" && o.variant != "concentric")
        throw std::invalid_argument("brushed: --variant must be concentric or radial");
    const Vec3 centre(0.5, 0.5, 0.5);
    constexpr double kMinor = 0.012;
    const double zLayers[2] = {0.46, 0.54};
    if (!radial) {
        const int rings = o.count > 0 ? o.count : 9;
        for (int k = 1; k <= rings; ++k) {
            const double r = 0.45 * k / rings;
            const double elongation = 1 + 5.0 * (1 - double(k - 1) / std::max(1, rings - 1));  // 6 … 1
            const double major = kMinor * elongation;
            const int count = std::max(3, int(2 * kPi * r / (2.2 * major)));
            for (double z : zLayers) {
                const double phase = rng.uniform(0, 2 * kPi);
                for (int i = 0; i < count; ++i) {
                    const double a = phase + 2 * kPi * i / count;
                    const Vec3 outward(std::cos(a), std::sin(a), 0), tangent(-std::sin(a), std::cos(a), 0);
                    Eigen::Matrix3d R;
                    R.col(0) = tangent;
                    R.col(1) = outward;
                    R.col(2) = Vec3::UnitZ();
                    mb.ellipsoid(Vec3(centre.x(), centre.y(), z) + r * outward, R, Vec3(major, kMinor, kMinor), metal);
                }
            }
        }
    } else {
        const int spokes = o.count > 0 ? o.count : 24;
        const double major = 5 * kMinor;
        for (double z : zLayers) {
            const double phase = rng.uniform(0, 2 * kPi);
            for (int s = 0; s < spokes; ++s) {
                const double a = phase + 2 * kPi * s / spokes;
                const Vec3 outward(std::cos(a), std::sin(a), 0), tangent(-std::sin(a), std::cos(a), 0);
                Eigen::Matrix3d R;
                R.col(0) = outward;
                R.col(1) = tangent;
                R.col(2) = Vec3::UnitZ();
                for (double r = 0.08; r + major <= 0.46; r += 2.2 * major)
                    mb.ellipsoid(Vec3(centre.x(), centre.y(), z) + (r + major) * outward, R, Vec3(major, kMinor, kMinor),
                                 metal);
            }
        }
    }
    return mb.take();
}

// Topiary (Fig. 5: "buissons taillés … avec divers types de primitives locales", the texel in a
// frame whose shadow falls on the ground): a bush trimmed to a shape and made of one kind of
// element — a ball of flat leaves (variant "leaves", the default), a block of needles ("needles")
// or a cone of beads ("beads") — inside twelve bars along the cube's edges.
ingest::TriangleMesh topiary(const PatternOptions& o) {
    const std::string variant = o.variant.empty() ? "leaves" : o.variant;
    if (variant != "leaves" && variant != "needles" && variant != "beads")
        throw std::invalid_argument("topiary: --variant must be leaves, needles or beads");
    Rng rng(o.seed);
    MeshBuilder mb;
    const int green = mb.material(0.12f, 0.36f, 0.07f), frame = mb.material(0.55f, 0.55f, 0.57f);
    const auto inside = [&](const Vec3& p) {
        if (variant == "leaves") return (p - Vec3(0.5, 0.5, 0.45)).norm() < 0.36;
        if (variant == "needles")
            return (p.array() > Eigen::Array3d(0.22, 0.22, 0.08)).all() && (p.array() < Eigen::Array3d(0.78, 0.78, 0.64)).all();
        const double t = (p.z() - 0.08) / 0.8;  // the cone: 0 at its base, 1 at its tip
        return t > 0 && t < 1 && std::hypot(p.x() - 0.5, p.y() - 0.5) < 0.34 * (1 - t);
    };
    const int elements = o.count > 0 ? o.count : variant == "beads" ? 1500 : 2000;
    for (int placed = 0, tries = 0; placed < elements && tries < 100 * elements; ++tries) {
        const Vec3 p(rng.uniform(), rng.uniform(), rng.uniform());
        if (!inside(p)) continue;
        ++placed;
        const Vec3 n = rng.unitVector(), u = orthogonal(n), w = n.cross(u);
        if (variant == "leaves") {  // a square leaf 0.05 across
            constexpr double r = 0.025;
            mb.quad(p - r * u - r * w, p + r * u - r * w, p + r * u + r * w, p - r * u + r * w, green);
        } else if (variant == "needles") {  // 0.1 long, 0.006 across
            mb.tube({p - 0.05 * n, p + 0.05 * n}, [](std::size_t) { return 0.003; }, 3, green);
        } else {  // a bead of radius 0.02
            Eigen::Matrix3d axes;
            axes << u, w, n;
            mb.ellipsoid(p, axes, Vec3::Constant(0.02), green, 6, 4);
        }
    }
    // The frame: bars 0.02 thick along the twelve edges of [0.01, 0.99]² × [0, 0.98].
    constexpr double lo = 0.01, hi = 0.99, top = 0.98, t = 0.02;
    for (const double a : {lo, hi - t}) {
        for (const double b : {lo, hi - t}) mb.box(Vec3(a, b, 0), Vec3(a + t, b + t, top), frame);  // uprights
        for (const double z : {0.0, top - t}) {
            mb.box(Vec3(lo, a, z), Vec3(hi, a + t, z + t), frame);  // along x
            mb.box(Vec3(a, lo, z), Vec3(a + t, hi, z + t), frame);  // along y
        }
    }
    return mb.take();
}

// Building elements (Fig. 11): walls, slabs, columns, and rods and plates thinner than a voxel
// at 128³ (1/128 ≈ 0.0078).
ingest::TriangleMesh blocks(const PatternOptions& o) {
    Rng rng(o.seed);
    MeshBuilder mb;
    const int concrete = mb.material(0.55f, 0.55f, 0.52f), brick = mb.material(0.55f, 0.25f, 0.18f),
              steel = mb.material(0.20f, 0.22f, 0.25f), glass = mb.material(0.35f, 0.45f, 0.55f);
    const int elements = o.count > 0 ? o.count : 24;
    auto place = [&](const Vec3& size) {
        Vec3 lo;
        for (int a = 0; a < 3; ++a) lo[a] = rng.uniform(0.02, std::max(0.021, 0.98 - size[a]));
        return lo;
    };
    for (int e = 0; e < elements; ++e) {
        const int kind = rng.index(5);
        const int axis = rng.index(2);  // walls and plates stand along x or y
        Vec3 size;
        int material = concrete;
        switch (kind) {
            case 0:  // wall
                size = axis == 0 ? Vec3(rng.uniform(0.2, 0.5), rng.uniform(0.03, 0.06), rng.uniform(0.2, 0.5))
                                 : Vec3(rng.uniform(0.03, 0.06), rng.uniform(0.2, 0.5), rng.uniform(0.2, 0.5));
                material = brick;
                break;
            case 1:  // slab
                size = Vec3(rng.uniform(0.2, 0.5), rng.uniform(0.2, 0.5), rng.uniform(0.02, 0.04));
                break;
            case 2: {  // column: an octagonal tube with caps left open
                const double r = rng.uniform(0.015, 0.035), h = rng.uniform(0.3, 0.7);
                const Vec3 lo = place(Vec3(2 * r, 2 * r, h));
                mb.tube({lo + Vec3(r, r, 0), lo + Vec3(r, r, h)}, [&](std::size_t) { return r; }, 8, concrete);
                continue;
            }
            case 3:  // rod thinner than a voxel
                size = Vec3(0.004, 0.004, rng.uniform(0.3, 0.8));
                if (rng.uniform() < 0.5) std::swap(size[axis], size[2]);
                material = steel;
                break;
            default:  // thin plate (glazing)
                size = axis == 0 ? Vec3(rng.uniform(0.15, 0.4), 0.003, rng.uniform(0.15, 0.4))
                                 : Vec3(0.003, rng.uniform(0.15, 0.4), rng.uniform(0.15, 0.4));
                material = glass;
                break;
        }
        const Vec3 lo = place(size);
        mb.box(lo, lo + size, material);
    }
    return mb.take();
}

// A polygon vertex with the attributes that are interpolated along a cut.
struct AttributedVertex {
    Vec3 p;
    Vec3 n;
    Vec2 uv;
};
using AttributedPolygon = std::vector<AttributedVertex>;

void splitAttributed(const AttributedPolygon& poly, int axis, double c, AttributedPolygon& below,
                     AttributedPolygon& above) {
    below.clear();
    above.clear();
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % poly.size()];
        const double da = a.p[axis] - c, db = b.p[axis] - c;
        if (da <= 0) below.push_back(a);
        if (da >= 0) above.push_back(a);
        if ((da < 0 && db > 0) || (da > 0 && db < 0)) {
            const double t = da / (da - db);
            AttributedVertex x{a.p + t * (b.p - a.p), (a.n + t * (b.n - a.n)).normalized(), a.uv + t * (b.uv - a.uv)};
            x.p[axis] = c;
            below.push_back(x);
            above.push_back(x);
        }
    }
}

double minCoord(const AttributedPolygon& poly, int axis) {
    double m = INFINITY;
    for (const auto& v : poly) m = std::min(m, v.p[axis]);
    return m;
}
double maxCoord(const AttributedPolygon& poly, int axis) {
    double m = -INFINITY;
    for (const auto& v : poly) m = std::max(m, v.p[axis]);
    return m;
}

// Cuts along integer planes of `axis`; emit(cell, piece).
template <class Emit>
void peelCells(const AttributedPolygon& poly, int axis, Emit&& emit) {
    if (poly.size() < 3) return;
    AttributedPolygon rest = poly, below, above;
    for (double i = std::floor(minCoord(rest, axis));; i += 1) {
        if (maxCoord(rest, axis) < i + 1) {
            emit(i, rest);
            return;
        }
        if (minCoord(rest, axis) >= i + 1) continue;
        splitAttributed(rest, axis, i + 1, below, above);
        if (below.size() >= 3) emit(i, below);
        rest = above;
        if (rest.size() < 3) return;
    }
}

}  // namespace

ingest::TriangleMesh wrapIntoUnitTile(const ingest::TriangleMesh& mesh) {
    ingest::TriangleMesh out;
    out.materials = mesh.materials;
    out.textures = mesh.textures;
    const bool hasUv = mesh.uvs.size() == mesh.positions.size();
    const bool hasNormals = mesh.normals.size() == mesh.positions.size();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        AttributedPolygon poly;
        for (std::uint32_t i : mesh.triangles[t])
            poly.push_back({mesh.positions[i].cast<double>(), hasNormals ? Vec3(mesh.normals[i].cast<double>()) : Vec3::UnitZ(),
                            hasUv ? Vec2(mesh.uvs[i].cast<double>()) : Vec2::Zero()});
        const std::uint32_t material = mesh.triangleMaterials.empty() ? 0 : mesh.triangleMaterials[t];
        peelCells(poly, 0, [&](double cx, const AttributedPolygon& px) {
            peelCells(px, 1, [&](double cy, const AttributedPolygon& py) {
              // Below the ground or above the tile: cut away (bases of tilted blades and hairs).
              peelCells(py, 2, [&](double cz, const AttributedPolygon& piece) {
                if (cz != 0 && !(cz == 1 && maxCoord(piece, 2) == 1)) return;
                const std::uint32_t first = std::uint32_t(out.positions.size());
                for (const auto& v : piece) {
                    Vec3 p = v.p - Vec3(cx, cy, 0);
                    // Exactly on the far border after the shift: keep it inside the tile.
                    for (int a = 0; a < 3; ++a) p[a] = std::clamp(p[a], 0.0, 1.0);
                    out.positions.push_back(p.cast<float>());
                    out.normals.push_back(v.n.cast<float>());
                    if (hasUv) out.uvs.push_back(v.uv.cast<float>());
                }
                for (std::size_t k = 1; k + 1 < piece.size(); ++k) {
                    const Vec3 a = out.positions[first].cast<double>(), b = out.positions[first + k].cast<double>(),
                               c = out.positions[first + k + 1].cast<double>();
                    if ((b - a).cross(c - a).norm() < 1e-12) continue;
                    out.triangles.push_back({first, first + std::uint32_t(k), first + std::uint32_t(k + 1)});
                    out.triangleMaterials.push_back(material);
                }
              });
            });
        });
    }
    return out;
}

const std::vector<std::string>& patternNames() {
    static const std::vector<std::string> names{"grass", "bush", "fur", "brushed", "blocks", "topiary"};
    return names;
}

bool isCyclicPattern(std::string_view name) { return name == "grass" || name == "fur"; }

bool patternUses(std::string_view pattern, std::string_view option) {
    if (option == "seed" || option == "count") return true;
    if (option == "fluctuation" || option == "lean") return pattern == "grass" || pattern == "fur";
    if (option == "variant") return pattern == "brushed" || pattern == "topiary";
    return false;
}

std::string patternsUsing(std::string_view option) {
    std::vector<std::string> users;
    for (const std::string& name : patternNames())
        if (patternUses(name, option)) users.push_back(name);
    std::string text;
    for (std::size_t i = 0; i < users.size(); ++i)
        text += (i == 0 ? "" : i + 1 == users.size() ? " and " : ", ") + users[i];
    return text.empty() ? "no pattern" : text;
}

namespace {

ingest::TriangleMesh build(std::string_view name, const PatternOptions& options) {
    if (options.count < 0 || options.count > 10'000'000) throw std::invalid_argument("count out of range");
    if (!std::isfinite(options.fluctuation) || options.fluctuation > kPi)
        throw std::invalid_argument("fluctuation must be at most π radians");
    if (!std::isfinite(options.leanDegrees) || std::abs(options.leanDegrees) > 80)
        throw std::invalid_argument("lean must be within ±80 degrees");
    if (name == "grass") return grass(options);
    if (name == "bush") return bush(options);
    if (name == "fur") return fur(options);
    if (name == "brushed") return brushed(options);
    if (name == "blocks") return blocks(options);
    if (name == "topiary") return topiary(options);
    throw std::invalid_argument("unknown pattern '" + std::string(name) + "' (grass, bush, fur, brushed, blocks, topiary)");
}

}  // namespace

std::uint64_t estimatePatternTriangles(std::string_view name, const PatternOptions& options) {
    constexpr int kSample = 64;
    if (options.count <= kSample) return build(name, options).triangles.size();
    PatternOptions sample = options;
    sample.count = kSample;
    return build(name, sample).triangles.size() * std::uint64_t(options.count) / kSample;
}

ingest::TriangleMesh makePattern(std::string_view name, const PatternOptions& options) {
    if (options.count > 64) {
        const std::uint64_t triangles = estimatePatternTriangles(name, options);
        if (triangles > kMaxPatternTriangles)
            throw std::invalid_argument("a count of " + std::to_string(options.count) + " makes about " +
                                        std::to_string(triangles) + " triangles, more than the " +
                                        std::to_string(kMaxPatternTriangles) + " vtex ingests");
    }
    return build(name, options);
}

}  // namespace vtex::sampler
