// Small in-memory scenes for the render tests: base meshes, octrees built through the octree
// stage's own builder, and a helper to render them.
#pragma once

#include <vtex/octree/octree.h>
#include <vtex/octree/voxel.h>
#include <vtex/render/renderer.h>
#include <vtex/render/texel_march.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace vtex::render::test {

/// One quad (or a grid of n×n quads) over [x0,x1]×[y0,y1] at z, normals +z.
inline std::shared_ptr<ingest::QuadMesh> gridMesh(double x0, double y0, double x1, double y1, double z, int n = 1) {
    auto mesh = std::make_shared<ingest::QuadMesh>();
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            mesh->positions.emplace_back(float(x0 + (x1 - x0) * i / n), float(y0 + (y1 - y0) * j / n), float(z));
            mesh->normals.emplace_back(0.f, 0.f, 1.f);
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = std::uint32_t(j * (n + 1) + i);
            mesh->quads.push_back({a, a + 1, a + std::uint32_t(n) + 2, a + std::uint32_t(n) + 1});
        }
    return mesh;
}

/// A quad mesh from four explicit corners (counter-clockwise) and one normal each.
inline std::shared_ptr<ingest::QuadMesh> quadMesh(const std::array<Eigen::Vector3f, 4>& p,
                                                  const std::array<Eigen::Vector3f, 4>& n) {
    auto mesh = std::make_shared<ingest::QuadMesh>();
    for (int i = 0; i < 4; ++i) {
        mesh->positions.push_back(p[std::size_t(i)]);
        mesh->normals.push_back(n[std::size_t(i)]);
    }
    mesh->quads.push_back({0, 1, 2, 3});
    return mesh;
}

/// An octree of 2^L voxels per side whose voxel (x,y,z) holds `voxel(x,y,z)` (density 0 =
/// empty), built without compression so that every level is stored.
inline std::shared_ptr<const octree::Octree> makeOctree(
    int levels, const std::function<std::optional<octree::VoxelData>(int, int, int)>& voxel, bool compress = false) {
    octree::SparseVolume volume;
    volume.info.levels = std::uint32_t(levels);
    const int n = 1 << levels;
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const auto data = voxel(x, y, z);
                if (!data || data->density == 0) continue;
                octree::VolumeBlock block;
                block.key = octree::mortonEncode(std::uint32_t(x), std::uint32_t(y), std::uint32_t(z));
                block.level = std::uint8_t(levels);
                block.data = *data;
                volume.blocks.push_back(block);
            }
    volume.sortBlocks();
    octree::BuildOptions options;
    options.compress = compress;
    NullProgress progress;
    return std::make_shared<const octree::Octree>(octree::buildOctree(volume, options, progress));
}

inline octree::VoxelData sphereVoxel(float density, std::array<float, 3> albedo = {0.8f, 0.8f, 0.8f}) {
    octree::VoxelData v;
    v.density = density;
    octree::packIsotropic(v);
    v.albedo = albedo;
    return v;
}

/// A scene with one camera and one directional light from above, no surfaces yet.
inline Scene baseScene(Eigen::Vector3d eye, Eigen::Vector3d target, double fov = 30, int size = 64) {
    Scene scene;
    scene.camera.position = eye;
    scene.camera.lookAt = target;
    scene.camera.up = Eigen::Vector3d(0, 0, 1);
    if (std::abs((target - eye).normalized().z()) > 0.99) scene.camera.up = Eigen::Vector3d(0, 1, 0);
    scene.camera.fovY = fov;
    scene.camera.width = size;
    scene.camera.height = size;
    Light light;
    light.direction = Eigen::Vector3d(-0.3, 0.2, -1).normalized();
    light.color = Color(3, 3, 3);
    scene.lights.push_back(light);
    return scene;
}

inline std::size_t addTexel(Scene& scene, std::shared_ptr<const octree::Octree> tree, double tau = 1) {
    TexelDef t;
    // Not `"t" + std::to_string(…)` nor an assignment from a literal: GCC 12 warns falsely
    // (-Wrestrict) on both once they are inlined here.
    t.name = std::to_string(scene.texels.size()).insert(0, 1, 't');
    t.octree = std::move(tree);
    t.tau = tau;
    scene.texels.push_back(t);
    return scene.texels.size() - 1;
}

inline void addSurface(Scene& scene, std::shared_ptr<const ingest::QuadMesh> mesh, std::optional<std::size_t> texel,
                       double height = 1, std::array<double, 2> repeat = {1, 1}) {
    SurfaceDef s;
    s.meshData = std::move(mesh);
    s.texel = texel;
    s.height = height;
    s.repeat = repeat;
    scene.surfaces.push_back(s);
}

/// Adds a surface of `mesh` carrying a texel, `height` high, to a scene.
using TexelFace = std::function<void(Scene&, std::shared_ptr<ingest::QuadMesh>, double height)>;

/// The robustness tests' extreme scenes, `size` pixels square: a grazing camera, shells 1e-6 and
/// 1e3 times as high as the face, a collapsed edge, a twisted patch, coordinates near 1e6,
/// lights in the face's plane and inside the shell. `texelFace` puts the texel on.
inline std::vector<std::pair<std::string, std::function<Scene()>>> extremeScenes(const TexelFace& texelFace, int size) {
    return {
        {"grazing camera", [=] {
             Scene s = baseScene(Eigen::Vector3d(-3, 0.5, 0), Eigen::Vector3d(1, 0.5, 0), 30, size);
             texelFace(s, gridMesh(0, 0, 1, 1, 0), 0.3);
             addSurface(s, gridMesh(1, 0, 2, 1, 0), std::nullopt);
             return s;
         }},
        {"shell 1e-6 of the face", [=] {
             Scene s = baseScene(Eigen::Vector3d(0.5, -2, 1.5), Eigen::Vector3d(0.5, 0.5, 0), 40, size);
             texelFace(s, gridMesh(0, 0, 1, 1, 0), 1e-6);
             return s;
         }},
        {"shell 1e3 of the face", [=] {
             // Close enough that the 1-unit-wide, 1000-unit-high shell fills part of the view.
             Scene s = baseScene(Eigen::Vector3d(0.5, -3, 500), Eigen::Vector3d(0.5, 0.5, 500), 40, size);
             texelFace(s, gridMesh(0, 0, 1, 1, 0), 1e3);
             return s;
         }},
        {"collapsed edge", [=] {
             Scene s = baseScene(Eigen::Vector3d(0.5, -2, 1.5), Eigen::Vector3d(0.5, 0.5, 0), 40, size);
             auto m = quadMesh({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0.5f, 1, 0),
                                Eigen::Vector3f(0.5f, 1, 0)},
                               {Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(0, 0, 1), Eigen::Vector3f(0, 0, 1),
                                Eigen::Vector3f(0, 0, 1)});
             m->quads[0] = {0, 1, 2, 2};
             texelFace(s, m, 0.3);
             addSurface(s, m, std::nullopt);
             return s;
         }},
        {"twisted patch", [=] {
             // Opposite edges 80° apart: (1, 0, ±tan 40°).
             Scene s = baseScene(Eigen::Vector3d(0.5, -2, 1.5), Eigen::Vector3d(0.5, 0.5, 0), 40, size);
             auto m = quadMesh({Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0.8391f), Eigen::Vector3f(1, 1, 0),
                                Eigen::Vector3f(0, 1, 0.8391f)},
                               {Eigen::Vector3f(0.7f, 0, 0.7f), Eigen::Vector3f(0, 0.7f, 0.7f),
                                Eigen::Vector3f(-0.7f, 0, 0.7f), Eigen::Vector3f(0, -0.7f, 0.7f)});
             texelFace(s, m, 0.6);
             return s;
         }},
        {"coordinates near 1e6", [=] {
             const Eigen::Vector3d c(1e6, 1e6, 1e6);
             Scene s = baseScene(c + Eigen::Vector3d(0.5, -2, 1.5), c + Eigen::Vector3d(0.5, 0.5, 0), 40, size);
             texelFace(s, gridMesh(1e6, 1e6, 1e6 + 1, 1e6 + 1, 1e6, 2), 0.3);
             return s;
         }},
        {"lights in the face's plane and inside the shell", [=] {
             Scene s = baseScene(Eigen::Vector3d(0.5, -2, 1.5), Eigen::Vector3d(0.5, 0.5, 0), 40, size);
             s.lights[0].direction = Eigen::Vector3d(1, 0, 0);
             Light point;
             point.type = LightType::Point;
             point.position = Eigen::Vector3d(0.5, 0.5, 0);
             s.lights.push_back(point);
             Light inside = point;
             inside.position = Eigen::Vector3d(0.5, 0.5, 0.15);
             s.lights.push_back(inside);
             texelFace(s, gridMesh(0, 0, 1, 1, 0), 0.3);
             addSurface(s, gridMesh(1, 0, 2, 1, 0), std::nullopt);
             return s;
         }},
    };
}

// The largest difference of one colour channel between two images of the same size.
inline double maxAbsDifference(const Image& a, const Image& b) {
    double worst = 0;
    for (std::size_t i = 0; i < a.rgba.size(); ++i)
        if (i % 4 != 3) worst = std::max(worst, double(std::abs(a.rgba[i] - b.rgba[i])));
    return worst;
}

// The most radiance the Phong material m under irradiance e reflects: E·(kd·albedo/π + ks·(n+2)/2π).
inline double largestPhongRadiance(double e, const Material& m, double albedo) {
    return e * (m.diffuse.maxCoeff() * albedo / std::numbers::pi +
                m.specular.maxCoeff() * (m.shininess + 2) / (2 * std::numbers::pi));
}

inline RenderResult renderQuiet(const Scene& scene, RenderOptions options = {}) {
    NullProgress progress;
    return renderScene(scene, options, progress);
}

// Whether two images hold the same bytes: what a change that must not move the image is held to.
inline bool sameImageBytes(const Image& a, const Image& b) {
    return a.rgba.size() == b.rgba.size() && std::memcmp(a.rgba.data(), b.rgba.data(), a.rgba.size() * sizeof(float)) == 0;
}

inline bool allFinite(const Image& image) {
    for (float v : image.rgba)
        if (!std::isfinite(v)) return false;
    return true;
}

/// How a shadow table agrees with the march it stands for at `queries` random points in the
/// non-empty voxels of `grid` (where shadow queries come from: voxels that absorb): the mean of
/// table(p) over the mean of march(p), and the mean |table(p) − march(p)|. march(p) is called
/// first, so that it may leave what table(p) needs.
struct TableAgreement {
    double ratio = 0;
    double meanDifference = 0;
};
template <class Table, class March>
TableAgreement agreementInVoxels(const LevelGrid& grid, std::uint32_t seed, int queries, Table&& table, March&& march) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    double sumMarch = 0, sumTable = 0, sumDiff = 0;
    for (int n = 0; n < queries;) {
        const Eigen::Vector3d p0(u(rng), u(rng), u(rng));
        if (grid.cell(std::uint32_t(p0.x() * grid.n), std::uint32_t(p0.y() * grid.n), std::uint32_t(p0.z() * grid.n)) &
            LevelGrid::kEmpty)
            continue;
        const double m = march(p0), t = table(p0);
        sumMarch += m;
        sumTable += t;
        sumDiff += std::abs(t - m);
        ++n;
    }
    return {sumTable / sumMarch, sumDiff / queries};
}

}  // namespace vtex::render::test
