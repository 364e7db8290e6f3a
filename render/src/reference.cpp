// The explicit-geometry reference renderer (DESIGN.md, "The reference renderer").
//
// It shares with the texel renderer everything outside the cells (frame.h: the base faces and
// cells behind one BVH, the camera, Phong of opaque surfaces, the lights and the shadow rule),
// so that the two images differ only by what a cell holds: here the source mesh's triangles,
// opaque and two-sided, with the texel's material.
#include <vtex/render/reference.h>

#include <vtex/core/error.h>
#include <vtex/core/memory_budget.h>

#include "deformed_mesh.h"
#include "footprint.h"
#include "frame.h"
#include "source_bvh.h"
#include "tracer.h"

#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <memory>

namespace vtex::render {
namespace {

using detail::Counters;
using detail::Hit;
using detail::Prim;
using detail::SurfaceRuntime;
using detail::tile;


/// Uniform pseudo-random numbers for the reference renderer's jittered samples: a pure
/// function of (pixel, sample, dimension), so images do not depend on the thread count.
double hashUniform(std::uint64_t pixel, std::uint64_t sample, std::uint64_t dimension) {
    std::uint64_t x = pixel * 0x9E3779B97F4A7C15ull ^ (sample + 0x632BE59BD9B4E019ull) * 0xD1B54A32D192ED03ull ^
                      (dimension + 1) * 0x94D049BB133111EBull;
    x ^= x >> 30;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 27;
    x *= 0x94D049BB133111EBull;
    x ^= x >> 31;
    return double(x >> 11) * 0x1.0p-53;
}

struct SourceRuntime {
    std::shared_ptr<const ingest::TriangleMesh> mesh;
    std::unique_ptr<detail::SourceBvh> bvh;
    Material material;
};

struct Sample {
    Color radiance = Color::Zero();
    bool hit = false;
    double depth = 0;
};

class ReferenceIntegrator {
public:
    ReferenceIntegrator(const Scene& scene, const detail::Tracer& tracer, const std::vector<SurfaceRuntime>& surfaces,
                        const std::vector<SourceRuntime>& sources, const detail::DeformedMesh* deformed)
        : mLights(scene.lights), mTracer(tracer), mSurfaces(surfaces), mSources(sources), mDeformed(deformed) {}

    Sample radiance(const Vec3& o, const Vec3& d, Counters& counters) const {
        ++counters.primary;
        return mDeformed ? radianceDeformed(o, d, counters) : radianceEmbedded(o, d, counters);
    }

private:
    static Sample opaque(double t, const Color& radiance) { return {radiance, true, t}; }

    Sample radianceEmbedded(const Vec3& o, const Vec3& d, Counters& counters) const {
        double tNear = 0;
        detail::SpanCache cache;
        for (int step = 0; step < 4096; ++step) {
            const auto hit = mTracer.trace(o, d, tNear, std::numeric_limits<double>::infinity(), &cache);
            if (!hit) break;
            std::optional<Prim> scratch;
            const Prim& prim = mTracer.prims().at(std::size_t(hit->prim), scratch);
            const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
            if (!prim.textured) return opaque(hit->t, shadePlain(prim, surface, hit->u, hit->v, d, counters));
            const CellSpan& span = hit->span;
            if (span.faceIn == 0 && hit->t <= span.tIn)
                return opaque(hit->t, shadeFloor(prim, surface, span.rIn, d, counters));
            if (const auto rIn = detail::entryCoords(prim, *hit, o, d, -1, Vec3::Zero())) {
                ++counters.segments;
                const Vec3 p0 = tile(*rIn, prim), p1 = tile(span.rOut, prim);
                const SourceRuntime& source = mSources[std::size_t(surface.texel)];
                if (const auto h = source.bvh->intersect(p0, p1, 0)) {
                    const double t = hit->t + h->s * (span.tOut - hit->t);
                    return opaque(t, shadeSource(prim, surface, p0 + h->s * (p1 - p0), *h, d, counters));
                }
            }
            if (span.faceOut == 0) return opaque(span.tOut, shadeFloor(prim, surface, span.rOut, d, counters));
            tNear = span.tOut;
        }
        return {};
    }

    Sample radianceDeformed(const Vec3& o, const Vec3& d, Counters& counters) const {
        const auto plain = mTracer.trace(o, d, 0);
        const auto triangle = mDeformed->intersect(o, d, 0, plain ? plain->t : std::numeric_limits<double>::infinity());
        if (triangle) {
            const Vec3 x = o + triangle->t * d;
            const SourceRuntime& source = mSources[std::size_t(triangle->texel)];
            const double scale = x.cwiseAbs().maxCoeff();  // lifts past the float rounding of the triangle
            return opaque(triangle->t,
                          detail::shadePhong(mLights, x, triangle->normal, triangle->normal, -d, source.material,
                                             triangle->albedo, scale, [&](const Vec3& origin, const Vec3& l, double distance) {
                                                 return visibilityDeformed(origin, l, distance, counters);
                                             }));
        }
        if (!plain) return {};
        const Prim& prim = mTracer.prims()[std::size_t(plain->prim)];
        return opaque(plain->t, shadePlain(prim, mSurfaces[std::size_t(prim.surface)], plain->u, plain->v, d, counters));
    }

    // 1 when nothing opaque lies between o and the light (distance tMax along l), else 0.
    double visibility(const Vec3& o, const Vec3& l, double tMax, int hintPrim, const Vec3& hintR, Counters& counters) const {
        if (mDeformed) return visibilityDeformed(o, l, tMax, counters);
        ++counters.shadow;
        return detail::walkShadowRay(
            mTracer, mSurfaces, o, l, tMax, hintPrim, hintR, 0,
            [&](const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, bool startsAtHint, double) {
                return mSources[std::size_t(surface.texel)].bvh->occludedLeaving(tile(rIn, prim), tile(rOut, prim),
                                                                                 startsAtHint)
                           ? 0.0
                           : 1.0;
            });
    }

    double visibilityDeformed(const Vec3& o, const Vec3& l, double tMax, Counters& counters) const {
        ++counters.shadow;
        if (mTracer.trace(o, l, 0, tMax)) return 0;
        return mDeformed->occluded(o, l, 0, tMax) ? 0 : 1;
    }

    Color shadePlain(const Prim& prim, const SurfaceRuntime& surface, double u, double v, const Vec3& d,
                     Counters& counters) const {
        const Vec3 x = detail::bilerp(prim.p, u, v);
        const Vec3 ng = detail::geometricNormal(prim.p, u, v, prim.n);
        const Vec3 n = detail::shadingNormal(prim.n, u, v, ng);
        return shadeOpaque(x, n, ng, -d, surface.material, detail::patchSize(prim.p), counters);
    }

    // The cell's floor (w = 0): the base surface with the face's material, as the texel
    // renderer draws it.
    Color shadeFloor(const Prim& prim, const SurfaceRuntime& surface, const Vec3& r, const Vec3& d, Counters& counters) const {
        const Vec3 x = prim.cell.map(Vec3(r.x(), r.y(), 0));
        const auto bottom = prim.cell.faceCorners(0);
        const Vec3 ng = detail::geometricNormal(bottom, r.x(), r.y(), prim.n);
        const Vec3 n = detail::shadingNormal(prim.n, r.x(), r.y(), ng);
        return shadeOpaque(x, n, ng, -d, surface.material, std::min(surface.height, detail::patchSize(prim.p)), counters);
    }

    Color shadeOpaque(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& view, const Material& m, double scale,
                      Counters& counters) const {
        return detail::shadePhong(mLights, x, n, ng, view, m, Color::Ones(), scale,
                                  [&](const Vec3& origin, const Vec3& l, double distance) {
                                      return visibility(origin, l, distance, -1, Vec3::Zero(), counters);
                                  });
    }

    // A source triangle hit at tiled reference coordinates `rt`: its normal goes to the world
    // through the inverse transpose of the tiled map's Jacobian there.
    Color shadeSource(const Prim& prim, const SurfaceRuntime& surface, const Vec3& rt, const detail::SourceHit& hit,
                      const Vec3& d, Counters& counters) const {
        const detail::SourcePoint p = detail::sourcePoint(prim, rt, hit.normal, d);
        const int primIndex = prim.index;
        const SourceRuntime& source = mSources[std::size_t(surface.texel)];
        return detail::shadePhong(mLights, p.world, p.normal, p.normal, -d, source.material, hit.albedo, p.scale,
                                  [&](const Vec3& origin, const Vec3& l, double distance) {
                                      return visibility(origin, l, distance, primIndex, p.cell, counters);
                                  });
    }


    const std::vector<Light>& mLights;
    const detail::Tracer& mTracer;
    const std::vector<SurfaceRuntime>& mSurfaces;
    const std::vector<SourceRuntime>& mSources;
    const detail::DeformedMesh* mDeformed;
};

}  // namespace

std::uint64_t estimateReferenceMemory(const Scene& scene, const ReferenceOptions& options) {
    return detail::imageAndSceneMemory(scene, options);
}

namespace {

// renderReference in the arena of withThreads.
RenderResult renderReferenceInArena(const Scene& scene, const ReferenceOptions& options, Progress& progress) {
    const auto loadStart = std::chrono::steady_clock::now();
    const detail::ImageFrame frame = detail::imageFrame(scene, options);
    const int width = frame.width, height = frame.height;
    const int strata = std::max(1, int(std::ceil(std::sqrt(double(std::max(options.spp, 1))))));
    checkMemoryEstimate(scene.file, "rendering " + std::to_string(width) + "x" + std::to_string(frame.rows()),
                        estimateReferenceMemory(scene, options), options.maxMemoryBytes);
    const bool deformedMode = options.mode == ReferenceMode::Deformed;
    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene, deformedMode);

    // The source meshes of the texels some surface uses, each loaded once.
    std::vector<SourceRuntime> sources(scene.texels.size());
    std::vector<const detail::SourceBvh*> bvhs(scene.texels.size(), nullptr);
    std::uint64_t sourceTriangles = 0;
    RenderStats vtoBytes;  // only its .vto counts
    for (const std::size_t t : usedTexels(scene)) {
        const TexelDef& def = scene.texels.at(t);
        if (!def.sourceData && def.source.empty())
            throw InputError(scene.file, "texel '" + def.name + "' has no source mesh (vtex reference draws it)", "texel.source");
        SourceRuntime& runtime = sources[t];
        runtime.mesh = loadTexelSource(scene, t);
        // Where the sampler put the mesh in the unit cube is recorded in the volume.
        const auto volume = loadTexelVolume(scene, t);
        runtime.bvh = std::make_unique<detail::SourceBvh>(*runtime.mesh, volume->info.source);
        detail::countVtoBytes(def, *volume, vtoBytes);
        runtime.material = def.material;
        bvhs[t] = runtime.bvh.get();
        sourceTriangles += runtime.mesh->triangles.size();
    }
    std::unique_ptr<detail::DeformedMesh> deformed;
    if (deformedMode)
        deformed = std::make_unique<detail::DeformedMesh>(geometry.tracer->prims(), geometry.surfaces, bvhs, options.tolerance,
                                                          options.maxMemoryBytes, scene.file);

    const detail::CameraRays camera(scene.camera, width, height);
    const ReferenceIntegrator integrator(scene, *geometry.tracer, geometry.surfaces, sources, deformed.get());
    const auto renderStart = std::chrono::steady_clock::now();
    const double loadSeconds = std::chrono::duration<double>(renderStart - loadStart).count();

    Image image(width, frame.rows(), options.aovs);
    const int threads = detail::resolveThreads(options.threads);
    std::vector<Counters> tileCounters;
    const int samples = strata * strata;
    detail::renderTiles(image, frame, progress, tileCounters, [&](int x, int y, Counters& counters) {
        detail::PixelValue value;
        double depth = 0;
        int depthCount = 0;
        const std::uint64_t pixel = std::uint64_t(y) * std::uint64_t(width) + std::uint64_t(x);
        for (int k = 0; k < samples; ++k) {
            const int sx = k % strata, sy = k / strata;
            const double px = (x + (sx + hashUniform(pixel, std::uint64_t(k), 0)) / strata) / width;
            const double py = (y + (sy + hashUniform(pixel, std::uint64_t(k), 1)) / strata) / height;
            const Sample s = integrator.radiance(camera.origin(), camera.direction(px, py), counters);
            value.radiance += s.radiance;
            if (s.hit) {
                value.alpha += 1;
                depth += s.depth;
                ++depthCount;
            }
        }
        value.radiance /= double(samples);
        value.alpha /= double(samples);
        value.depth = depthCount ? depth / depthCount : 0.0;
        return value;
    });

    const double wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - renderStart).count();
    RenderResult result;
    result.stats = detail::summarize(tileCounters, geometry, threads, frame, samples, wallSeconds, loadSeconds);
    result.stats.renderer = deformedMode ? "reference-deformed" : "reference-embedded";
    result.stats.referenceTriangles = deformedMode ? deformed->triangleCount() : sourceTriangles;
    result.stats.vtoBytesRead = vtoBytes.vtoBytesRead;
    result.stats.vtoFileBytes = vtoBytes.vtoFileBytes;
    result.image = std::move(image);
    result.warnings = detail::renderWarnings(scene, tileCounters);
    return result;
}

}  // namespace

RenderResult renderReference(const Scene& scene, const ReferenceOptions& options, Progress& progress) {
    return detail::withThreads(options.threads, [&] { return renderReferenceInArena(scene, options, progress); });
}

}  // namespace vtex::render
