// See frame.h.
#include "frame.h"

#include <vtex/core/error.h>

#include "footprint.h"

#include <Eigen/LU>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>

namespace vtex::render {

std::pair<int, int> imageRows(const ImageOptions& options, int height) {
    if (options.rowBegin == 0 && options.rowEnd == 0) return {0, height};
    if (options.rowBegin < 0 || options.rowBegin >= options.rowEnd || options.rowEnd > height)
        throw std::invalid_argument("rows " + std::to_string(options.rowBegin) + ":" + std::to_string(options.rowEnd) +
                                    " are not a range within the image's " + std::to_string(height) +
                                    " rows (0 <= begin < end <= height)");
    return {options.rowBegin, options.rowEnd};
}

}  // namespace vtex::render

namespace vtex::render::detail {

namespace {

bool inRange(const Vec3& p) { return p.allFinite() && p.cwiseAbs().maxCoeff() <= kMaxSceneCoordinate; }

// The camera and the lights within kMaxSceneCoordinate (scene files are checked here too, for
// scenes built in memory).
void checkSceneRange(const Scene& scene) {
    static_assert(kMaxSceneCoordinate == 1e12, "the messages say 1e12");
    const std::string limit = " beyond ±1e12 (the renderers' exact range)";
    if (!inRange(scene.camera.position)) throw InputError(scene.file, "a coordinate" + limit, "camera.position");
    if (!inRange(scene.camera.lookAt)) throw InputError(scene.file, "a coordinate" + limit, "camera.look_at");
    for (std::size_t i = 0; i < scene.lights.size(); ++i)
        if (scene.lights[i].type == LightType::Point && !inRange(scene.lights[i].position))
            throw InputError(scene.file, "a coordinate" + limit, "light[" + std::to_string(i) + "].position");
}

// A shift, or a sub-rectangle beyond the unit square, shows a texel's pattern cut inside each
// face unless the texel is cyclic (docs/render.md, "Per-face perturbation"): refused, naming the
// key.
void checkTiling(const Scene& scene, std::size_t si, std::size_t k) {
    const SurfaceDef& def = scene.surfaces[si];
    const TexelPlacing placing = def.placing(k);
    if (!placing.texel) return;
    const auto& r = placing.subrect;
    const bool outside = r && ((*r)[0] < 0 || (*r)[1] < 0 || (*r)[2] > 1 || (*r)[3] > 1);
    if ((!placing.perturb.shift && !outside) || texelIsCyclic(scene, *placing.texel)) return;
    const std::string surface = "surface[" + std::to_string(si) + "]";
    const std::string key = k == 0 ? surface : surface + ".texels." + def.texels[k - 1].name;
    const std::string texel = "texel '" + scene.texels[*placing.texel].name + "' is not cyclic";
    if (placing.perturb.shift)
        throw InputError(scene.file, texel + " (a shift would cut its pattern inside each face)", key + ".perturb.shift");
    throw InputError(scene.file, texel + ": the sub-rectangle must lie within [0, 1]²", key + ".subrect");
}

}  // namespace

SceneGeometry buildSceneGeometry(const Scene& scene, bool cellsAsFloors) {
    checkSceneRange(scene);
    SceneGeometry geometry;
    PrimTable prims;
    for (std::size_t si = 0; si < scene.surfaces.size(); ++si) {
        const SurfaceDef& def = scene.surfaces[si];
        // One runtime surface per placing (SurfaceDef::placing): the faces of each material or
        // group named in `texels`, and the others.
        const std::size_t first = geometry.surfaces.size();
        for (std::size_t k = 0; k < def.placingCount(); ++k) {
            const TexelPlacing placing = def.placing(k);
            if (placing.texel && *placing.texel >= scene.texels.size())
                throw InputError(scene.file, "texel index out of range", "surface.texel");
            checkTiling(scene, si, k);
            SurfaceRuntime s;
            s.material = def.material;
            s.texel = placing.texel ? int(*placing.texel) : -1;
            s.placing = placing;
            s.height = placing.height;
            s.under = placing.placement == Placement::Under;
            geometry.surfaces.push_back(s);
        }
        const auto mesh = loadSurfaceMesh(scene, si);
        for (std::size_t k = first; k < geometry.surfaces.size(); ++k) {
            const SurfaceRuntime& s = geometry.surfaces[k];
            const bool textured = s.texel >= 0;
            prims.addSurface({mesh, textured && !cellsAsFloors, textured && cellsAsFloors, s.height, s.under, s.placing});
        }
        const std::vector<std::uint32_t> placings = facePlacings(scene, si, *mesh);
        for (std::size_t f = 0; f < mesh->quads.size(); ++f) {
            const int surface = int(first + placings[f]);
            const SurfaceRuntime& s = geometry.surfaces[std::size_t(surface)];
            std::array<Vec3, 4> p, n;
            if (!baseFaceCorners(*mesh, f, p, n))
                throw InputError(def.mesh, "face " + std::to_string(f) + " has an invalid corner");
            for (const Vec3& corner : p)  // the shell's top is within `height` of its corners
                if (!inRange(corner) || !(corner.cwiseAbs().maxCoeff() + std::abs(s.height) <= kMaxSceneCoordinate))
                    throw InputError(def.mesh, "face " + std::to_string(f) + " has a corner (or its shell) beyond ±1e12, "
                                     "the renderers' exact range");
            if (s.texel >= 0) ++geometry.cells;
            prims.add(surface, std::uint32_t(f));
        }
    }
    geometry.faces = prims.size();
    prims.keepBuilt(std::size_t(32) << 20);  // ~60 000 faces; larger meshes rebuild on demand
    geometry.tracer = std::make_unique<Tracer>(std::move(prims));
    return geometry;
}

Mat3 tiledJacobian(const Prim& prim, const Vec3& r) { return prim.cell.jacobian(r) * prim.map.linearInverse(); }

Mat3 tiledJacobianInverse(const Prim& prim, const Vec3& r) {
    return prim.affine ? prim.affineJacobianInverse : Mat3(tiledJacobian(prim, r).inverse());
}

double localScale(const Prim& prim, const Vec3& r) {
    return prim.affine ? prim.affineScale : localScale(prim.cell, r, prim.map);
}

SourcePoint sourcePoint(const Prim& prim, const Vec3& rt, const Vec3& referenceNormal, const Vec3& d) {
    SourcePoint p;
    p.cell = prim.map.toCell(rt);
    p.world = prim.cell.map(p.cell);
    const Vec3 n = tiledJacobianInverse(prim, p.cell).transpose() * referenceNormal;
    const double length = n.norm();
    p.normal = length > 0 && std::isfinite(length) ? Vec3(n / length) : Vec3(-d);
    p.scale = localScale(prim, p.cell);
    return p;
}

std::pair<int, int> imageSize(const Scene& scene, int width, int height) {
    const int w = width > 0 ? width : scene.camera.width;
    const int h = height > 0 ? height : scene.camera.height;
    if (w <= 0 || h <= 0 || w > 16384 || h > 16384) throw InputError(scene.file, "image size must be in [1, 16384]");
    return {w, h};
}

ImageFrame imageFrame(const Scene& scene, const ImageOptions& options) {
    ImageFrame frame;
    std::tie(frame.width, frame.height) = imageSize(scene, options.width, options.height);
    std::tie(frame.rowBegin, frame.rowEnd) = imageRows(options, frame.height);
    return frame;
}

CameraRays::CameraRays(const Camera& camera, int width, int height)
    : mOrigin(camera.position),
      mForward((camera.lookAt - camera.position).normalized()),
      mRight(mForward.cross(camera.up).normalized()),
      mUp(mRight.cross(mForward)),
      mTanHalf(std::tan(camera.fovY * std::numbers::pi / 360)),
      mAspect(double(width) / double(height)) {}

RenderStats summarize(const std::vector<Counters>& tileCounters, const SceneGeometry& geometry, int threads,
                      const ImageFrame& frame, int spp, double wallSeconds, double loadSeconds) {
    Counters total;
    for (const Counters& c : tileCounters) total.add(c);
    RenderStats st;
    st.wallSeconds = wallSeconds;
    st.loadSeconds = loadSeconds;
    st.threads = threads;
    st.width = frame.width;
    st.height = frame.height;
    st.rowBegin = frame.rowBegin;
    st.rowEnd = frame.rowEnd;
    st.spp = spp;
    st.faces = geometry.faces;
    st.cells = geometry.cells;
    st.primaryRays = total.primary;
    st.shadowRays = total.shadow;
    st.cellSegments = total.segments;
    st.voxelsVisited = total.voxels;
    st.reflectanceEvaluations = total.reflectance;
    st.levelHistogram = total.histogram;
    st.meshSegments = total.mesh;
    return st;
}

Vec3 geometricNormal(const std::array<Vec3, 4>& p, double u, double v, const std::array<Vec3, 4>& n) {
    const Vec3 du = (1 - v) * (p[1] - p[0]) + v * (p[3] - p[2]);
    const Vec3 dv = (1 - u) * (p[2] - p[0]) + u * (p[3] - p[1]);
    Vec3 ng = du.cross(dv);
    // At a triangle's collapsed corner the cross product vanishes: use the other corners'.
    if (!(ng.squaredNorm() > 0) || !ng.allFinite()) ng = (p[1] - p[0]).cross(p[3] - p[0]);
    if (!(ng.squaredNorm() > 0) || !ng.allFinite()) ng = bilerp(n, u, v);
    const double len = ng.norm();
    return len > 0 && std::isfinite(len) ? Vec3(ng / len) : Vec3(0, 0, 1);
}

Vec3 shadingNormal(const std::array<Vec3, 4>& n, double u, double v, const Vec3& ng) {
    Vec3 s = bilerp(n, u, v);
    const double len = s.norm();
    if (!(len > 0) || !std::isfinite(len)) return ng;
    s /= len;
    return s.dot(ng) < 0 ? Vec3(-s) : s;
}

double patchSize(const std::array<Vec3, 4>& p) {
    double size = 0;
    for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) size = std::max(size, (p[i] - p[j]).norm());
    return size;
}

}  // namespace vtex::render::detail

namespace vtex::render::detail {
namespace {

// The size of a file the scene will load (0 for one given in memory or missing: the loader
// names a missing file itself). Read with stat, never opened here.
double fileBytes(const std::filesystem::path& file) {
    std::error_code ec;
    if (file.empty()) return 0;
    const auto size = std::filesystem::file_size(file, ec);
    return ec ? 0.0 : double(size);
}

}  // namespace

void countVtoBytes(const TexelDef& texel, const octree::Octree& tree, RenderStats& stats) {
    if (texel.octree) return;
    stats.vtoBytesRead += tree.bytesRead();
    stats.vtoFileBytes += std::uint64_t(fileBytes(texel.volume));
}

std::uint64_t imageAndSceneMemory(const Scene& scene, const ImageOptions& options) {
    // The factors are stated and measured in renderer.h (estimateRenderMemory).
    const int w = options.width > 0 ? options.width : scene.camera.width;
    // A row range holds only its rows (ImageOptions::rowBegin).
    const int h = options.rowEnd > options.rowBegin ? options.rowEnd - options.rowBegin
                  : options.height > 0              ? options.height
                                                    : scene.camera.height;
    double bytes = double(std::max(w, 0)) * double(std::max(h, 0)) * (options.aovs ? 30.0 : 22.0) + double(16 << 20);
    std::vector<bool> used(scene.texels.size(), false);
    for (const SurfaceDef& s : scene.surfaces) {
        if (!s.meshData) bytes += 10 * fileBytes(s.mesh);
    }
    for (const std::size_t t : usedTexels(scene))
        if (t < used.size()) used[t] = true;
    for (std::size_t t = 0; t < scene.texels.size(); ++t) {
        if (!used[t]) continue;
        if (!scene.texels[t].octree) bytes += 3 * fileBytes(scene.texels[t].volume);
        if (!scene.texels[t].sourceData) bytes += 3 * fileBytes(scene.texels[t].source);
    }
    return std::uint64_t(std::min(bytes, 1.8e19));
}

}  // namespace vtex::render::detail
