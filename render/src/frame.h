// What the texel renderer and the reference renderer share, so that their images differ only
// by what is inside the cells: the base faces and cells of a scene behind one Embree BVH, the
// camera's rays, Phong shading of opaque surfaces with the same lights and shadow rule, the
// tiled parallel loop over pixels and the statistics.
#pragma once

#include <vtex/core/progress.h>
#include <vtex/render/image.h>
#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

#include "tracer.h"

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace vtex::render::detail {

/// The faces of one placing of a scene surface (SurfaceDef::placing): a texel per face comes
/// as one of these per material or group.
struct SurfaceRuntime {
    Material material;
    int texel = -1;
    TexelPlacing placing;  ///< its height, placement, repeat or sub-rectangle
    double height = 0;
    bool under = false;
};

/// The base faces of a scene: plain patches, and cells over the faces of textured surfaces.
struct SceneGeometry {
    std::vector<SurfaceRuntime> surfaces;  ///< Prim::surface indexes these
    std::unique_ptr<Tracer> tracer;
    std::uint64_t faces = 0;
    std::uint64_t cells = 0;
};

/// The largest coordinate a scene may have (camera, lights, base-mesh corners and the tops of
/// their shells), in world units. Embree 3 asserts on a ray component beyond ±1.84e18
/// (FLT_LARGE), and the patch and cell tests run in double precision: at 1e12 a unit-sized
/// feature keeps ~1e-4 of absolute precision, further out the geometry is no longer what the
/// scene says. Scenes past it are refused (vtex::InputError naming the key).
inline constexpr double kMaxSceneCoordinate = 1e12;

/// Loads the base meshes and builds the BVH. With `cellsAsFloors`, a textured face becomes the
/// plain patch of its cell's floor (w = 0) instead of a cell: for renderers that put the texel's
/// content into the BVH themselves. Throws vtex::InputError naming the mesh.
SceneGeometry buildSceneGeometry(const Scene& scene, bool cellsAsFloors = false);

/// The image size a render makes (the options', else the camera's). Throws vtex::InputError.
std::pair<int, int> imageSize(const Scene& scene, int width, int height);

/// The full image a render's pixels belong to, and the rows of it the render makes
/// (ImageOptions::rowBegin): camera rays and sample positions come from the full image.
struct ImageFrame {
    int width = 0, height = 0;
    int rowBegin = 0, rowEnd = 0;
    int rows() const { return rowEnd - rowBegin; }
};
/// imageSize and imageRows of `options`. Throws as they do.
ImageFrame imageFrame(const Scene& scene, const ImageOptions& options);

/// The image and the scene's files, as both renderers' estimates count them (renderer.h,
/// estimateRenderMemory, states the factors).
std::uint64_t imageAndSceneMemory(const Scene& scene, const ImageOptions& options);

/// Adds what `tree` (the texel's volume, once the render is done) read of its file, and the
/// file's size, to stats.vtoBytesRead and stats.vtoFileBytes (nothing for an in-memory octree).
void countVtoBytes(const TexelDef& texel, const octree::Octree& tree, RenderStats& stats);

/// Pinhole camera rays through image coordinates (px, py) ∈ [0,1]², (0,0) the top left.
class CameraRays {
public:
    CameraRays(const Camera& camera, int width, int height);
    const Vec3& origin() const { return mOrigin; }
    Vec3 direction(double px, double py) const {
        return (mForward + (2 * px - 1) * mTanHalf * mAspect * mRight + (1 - 2 * py) * mTanHalf * mUp).normalized();
    }

private:
    Vec3 mOrigin, mForward, mRight, mUp;
    double mTanHalf, mAspect;
};

struct Counters {
    std::uint64_t primary = 0, shadow = 0, segments = 0, voxels = 0, reflectance = 0;
    std::uint64_t clamped = 0;  ///< pixel channels beyond float's range (or NaN), clamped when stored
    double mesh = 0;  ///< the hybrid's mesh shares of camera-ray segments, summed
    std::vector<double> histogram;
    void add(const Counters& o) {
        mesh += o.mesh;
        clamped += o.clamped;
        primary += o.primary;
        shadow += o.shadow;
        segments += o.segments;
        voxels += o.voxels;
        reflectance += o.reflectance;
        if (histogram.size() < o.histogram.size()) histogram.resize(o.histogram.size(), 0.0);
        for (std::size_t i = 0; i < o.histogram.size(); ++i) histogram[i] += o.histogram[i];
    }
};

/// A render's warnings: the scene's, then one if pixel channels were clamped when stored
/// (storedRadiance), with their count over all tiles.
inline std::vector<std::string> renderWarnings(const Scene& scene, const std::vector<Counters>& tiles) {
    std::vector<std::string> warnings = scene.warnings;
    std::uint64_t clamped = 0;
    for (const Counters& c : tiles) clamped += c.clamped;
    if (clamped)
        warnings.push_back(std::to_string(clamped) +
                           " pixel channels overflowed (or were NaN) and were clamped to float's range: "
                           "check the lights' colours and the materials");
    return warnings;
}

/// The statistics every render reports, from the counters summed over the tiles.
RenderStats summarize(const std::vector<Counters>& tileCounters, const SceneGeometry& geometry, int threads,
                      const ImageFrame& frame, int spp, double wallSeconds, double loadSeconds);

/// Tiled reference coordinates of cell coordinates r of a textured face (its CellMap: the
/// repeat or sub-rectangle, and the face's perturbation).
inline Vec3 tile(const Vec3& r, const Prim& prim) { return prim.map.toReference(r); }

/// The Jacobian at cell coordinates r of the map from tiled reference space to the world: the
/// cell's, times the inverse of the face's CellMap.
Mat3 tiledJacobian(const Prim& prim, const Vec3& r);
/// tiledJacobian(prim, r).inverse(), kept by an affine cell's Prim.
Mat3 tiledJacobianInverse(const Prim& prim, const Vec3& r);

/// World length per unit of tiled reference space around cell coordinates r (footprint.h).
double localScale(const Prim& prim, const Vec3& r);

/// A hit on a texel's source mesh at tiled reference coordinates `rt` as both renderers shade
/// it: its cell coordinates, world point, unit world normal (the triangle's reference normal
/// through the inverse transpose of the tiled map's Jacobian; −d where that is undefined) and
/// the local scale for lifting shadow rays off it.
struct SourcePoint {
    Vec3 cell, world, normal;
    double scale = 1;
};
SourcePoint sourcePoint(const Prim& prim, const Vec3& rt, const Vec3& referenceNormal, const Vec3& d);

inline Vec3 bilerp(const std::array<Vec3, 4>& p, double u, double v) {
    const Vec3 a = p[0] + u * (p[1] - p[0]);
    const Vec3 b = p[2] + u * (p[3] - p[2]);
    return a + v * (b - a);
}

/// The unit geometric normal of a bilinear patch at (u, v), finite even at a collapsed corner.
Vec3 geometricNormal(const std::array<Vec3, 4>& p, double u, double v, const std::array<Vec3, 4>& n);
/// The interpolated corner normal, turned to the side of `ng`; `ng` where it is undefined.
Vec3 shadingNormal(const std::array<Vec3, 4>& n, double u, double v, const Vec3& ng);
/// The largest distance between two corners of a patch.
double patchSize(const std::array<Vec3, 4>& p);

/// An offset along the normal that lifts a surface point clear of the rounding of its own
/// intersection (pbrt-v4's OffsetRayOrigin idea, with a bound relative to the coordinates and
/// to the local feature size rather than a propagated error).
inline double offsetDistance(const Vec3& x, double scale) { return 1e-9 * x.cwiseAbs().maxCoeff() + 1e-6 * scale; }

/// Direction toward the light, distance to it (∞ for directional) and irradiance at x; false
/// where it is undefined (x on a point light).
inline bool lightAt(const Light& light, const Vec3& x, Vec3& l, double& distance, Color& e) {
    if (light.type == LightType::Directional) {
        l = -light.direction;
        distance = std::numeric_limits<double>::infinity();
        e = light.color;
        return true;
    }
    const Vec3 delta = light.position - x;
    distance = delta.norm();
    if (!(distance > 0) || !std::isfinite(distance)) return false;
    l = delta / distance;
    e = light.color / (distance * distance);
    return e.allFinite();
}

/// Energy-normalised Phong (DESIGN.md, "Radiometry") of an opaque two-sided surface: the
/// normals are turned toward the viewer. `albedo` scales the diffuse and ambient colours (a
/// texel's base colour; 1 for base faces). `shadow(origin, l, distance)` is the transmittance
/// toward a light from the lifted origin; `scale` is the local feature size for that lift.
template <class Shadow>
Color shadePhong(const std::vector<Light>& lights, const Vec3& x, Vec3 n, Vec3 ng, const Vec3& view,
                 const Material& m, const Color& albedo, double scale, Shadow&& shadow) {
    if (ng.dot(view) < 0) {
        ng = -ng;
        n = -n;
    }
    if (n.dot(view) < 0) n = ng;  // a shading normal past the silhouette
    Color out = m.ambient.cwiseProduct(albedo);
    const Vec3 origin = x + offsetDistance(x, scale) * ng;
    for (const Light& light : lights) {
        Vec3 l;
        double distance;
        Color e;
        if (!lightAt(light, x, l, distance, e)) continue;
        const double cosTheta = n.dot(l);
        if (cosTheta <= 0 || ng.dot(l) <= 0) continue;
        const double transmittance = shadow(origin, l, distance);
        if (transmittance <= 0) continue;
        const Vec3 mirror = 2 * n.dot(l) * n - l;
        const double cosAlpha = std::max(0.0, mirror.dot(view));
        const Color f = m.diffuse.cwiseProduct(albedo) / std::numbers::pi +
                        m.specular * ((m.shininess + 2) / (2 * std::numbers::pi) * std::pow(cosAlpha, m.shininess));
        out += transmittance * cosTheta * e.cwiseProduct(f);
    }
    return out;
}

// The cell coordinates where the ray enters at hit.t: the face parameters when it crossed a
// face there, the caller's hint when it starts inside the hinted cell, otherwise the inverse
// trilinear map of the world point.
inline std::optional<Vec3> entryCoords(const Prim& prim, const Hit& hit, const Vec3& o, const Vec3& d, int hintPrim,
                                       const Vec3& hintR) {
    const CellSpan& span = hit.span;
    // The cell's size (28 corner distances) only when the entry is not already within the
    // tolerance's first term, as it nearly always is (hit.t is the span's own tIn).
    const double slack = 1e-9 * std::max(1.0, std::abs(span.tOut));
    if (span.faceIn >= 0 && (hit.t - span.tIn <= slack || hit.t - span.tIn <= slack + 1e-12 * prim.cell.size()))
        return span.rIn;
    if (span.faceIn < 0 && hit.prim == hintPrim) return hintR;
    const Vec3 guess = span.faceIn >= 0
                           ? Vec3(span.rIn + (span.rOut - span.rIn) * std::clamp((hit.t - span.tIn) / (span.tOut - span.tIn), 0.0, 1.0))
                           : Vec3(0.5, 0.5, 0.5);
    return prim.cell.inverse(o + hit.t * d, guess, 1e-7, 1e-3);
}

/// Follows a shadow ray from o along the unit direction l up to tMax through the base faces and
/// cells: an opaque face or a cell's floor blocks it (0); in each cell it crosses, the straight
/// reference-space segment between the cell coordinates where it enters and leaves is handed to
/// `segment(prim, surface, rIn, rOut, startsAtHint, transmittanceSoFar)`, whose transmittance
/// multiplies in. `startsAtHint`: the ray starts inside cell `hintPrim` at `hintR`, where a
/// caller's surface point lies. Below `cutoff` the answer is 0. `tStart`: the ray starts there
/// (what lies before was accounted for by the caller).
template <class Segment>
double walkShadowRay(const Tracer& tracer, const std::vector<SurfaceRuntime>& surfaces, const Vec3& o, const Vec3& l,
                     double tMax, int hintPrim, const Vec3& hintR, double cutoff, Segment&& segment, double tStart = 0) {
    double transmittance = 1;
    double tNear = tStart;
    SpanCache cache;
    for (int step = 0; step < 4096; ++step) {
        const auto hit = tracer.trace(o, l, tNear, tMax, &cache);
        if (!hit) break;
        std::optional<Prim> scratch;
        const Prim& prim = tracer.prims().at(std::size_t(hit->prim), scratch);
        if (!prim.textured) return 0;
        const CellSpan& span = hit->span;
        if (span.faceIn == 0 && hit->t <= span.tIn) return 0;
        const SurfaceRuntime& surface = surfaces[std::size_t(prim.surface)];
        const double tOut = std::min(span.tOut, tMax);
        if (const auto rIn = entryCoords(prim, *hit, o, l, hintPrim, hintR)) {
            const Vec3 rOut =
                tOut < span.tOut ? prim.cell.inverse(o + tOut * l, span.rOut).value_or(span.rOut) : span.rOut;
            const bool startsAtHint = span.faceIn < 0 && hit->prim == hintPrim;
            transmittance *= segment(prim, surface, *rIn, rOut, startsAtHint, transmittance);
            if (transmittance <= cutoff) return 0;
        }
        if (tOut < span.tOut) break;
        if (span.faceOut == 0) return 0;  // leaves through the base surface
        tNear = span.tOut;
    }
    return transmittance;
}

/// What one pixel's samples added up to.
struct PixelValue {
    Color radiance = Color::Zero();
    double alpha = 0;
    double depth = 0;    ///< AOV; 0 where nothing was hit
    double level = -1;   ///< AOV; −1 where no texel was seen
};

/// A radiance as the image stores it: radiance that overflows float (a light of colour 1e308)
/// is clamped to the largest float and NaN to 0, each counted, so that no image holds inf or
/// NaN (the renderers then warn; docs/render.md, "Output").
inline float storedRadiance(double radiance, Counters& counters) {
    constexpr double kLargest = double(std::numeric_limits<float>::max());
    if (std::isnan(radiance)) {
        ++counters.clamped;
        return 0.0f;
    }
    if (std::abs(radiance) > kLargest) {
        ++counters.clamped;
        return float(std::copysign(kLargest, radiance));
    }
    return float(radiance);
}

/// Renders the rows [frame.rowBegin, frame.rowEnd) of the full image with `pixel(x, y, counters)`
/// (y the full image's row) into `image` (those rows alone, image row 0 = frame.rowBegin), in
/// 16×16 tiles on the current arena's TBB workers (withThreads), with progress per tile. A pixel's value depends on its
/// own (x, y) alone, not on the thread that computes it nor on which other pixels are rendered:
/// row ranges rendered apart stack into the whole render exactly (tests/render/row_range_test.cpp).
template <class PixelFunction>
void renderTiles(Image& image, const ImageFrame& frame, Progress& progress, std::vector<Counters>& tileCounters,
                 PixelFunction&& pixel) {
    constexpr int kTile = 16;
    const int width = image.width, rows = image.height;
    const int tilesX = (width + kTile - 1) / kTile, tilesY = (rows + kTile - 1) / kTile;
    const int tiles = tilesX * tilesY;
    tileCounters.assign(std::size_t(tiles), Counters{});
    progress.start("render", std::uint64_t(tiles));
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
        for (int tileIndex = range.begin(); tileIndex != range.end(); ++tileIndex) {
            if (progress.wasInterrupted()) return;
            Counters& counters = tileCounters[std::size_t(tileIndex)];
            const int x0 = (tileIndex % tilesX) * kTile, y0 = (tileIndex / tilesX) * kTile;
            for (int y = y0; y < std::min(y0 + kTile, rows); ++y) {
                for (int x = x0; x < std::min(x0 + kTile, width); ++x) {
                    const PixelValue value = pixel(x, frame.rowBegin + y, counters);
                    const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
                    for (int c = 0; c < 3; ++c) image.rgba[4 * i + std::size_t(c)] = storedRadiance(value.radiance[c], counters);
                    image.rgba[4 * i + 3] = float(value.alpha);
                    if (image.hasAovs()) {
                        image.depth[i] = float(value.depth);
                        image.level[i] = float(value.level);
                    }
                }
            }
            progress.advance(1);
        }
    });
    progress.finish();
}

inline int resolveThreads(int requested) {
    return requested > 0 ? requested : tbb::this_task_arena::max_concurrency();
}

/// Runs f, a whole render (what its load measures, in parallel, and its tiles), in an arena of
/// `threads` (ImageOptions::threads; 0: the caller's arena's concurrency), so that the option
/// bounds every parallel loop of the render and not only the tiles': `vtex render --threads 1`
/// (two renders side by side on two cores, say) took every core while the texels' chord
/// measures ran at load.
template <class F>
auto withThreads(int threads, F&& f) {
    tbb::task_arena arena(resolveThreads(threads));
    return arena.execute(std::forward<F>(f));
}

}  // namespace vtex::render::detail
