// One ray span through a texel cell, marched at one octree level (docs/render.md, "Inside a
// texel"): extinction τρÂ(ω), front-to-back compositing, the voxels' Phong reflectance of the
// ellipsoid lit through shadow queries. The level blend and the mesh/volume hybrid around it
// are the integrator's (renderer.cpp); the shadows are ShadowQueries'.
#pragma once

#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>
#include <vtex/primitive/reflectance_kernel.h>

#include "frame.h"
#include "per_light.h"
#include "shadow_queries.h"
#include "texel_runtime.h"

#include <array>
#include <optional>

namespace vtex::render::detail {

struct SpanResult {
    Color radiance = Color::Zero();
    double transmittance = 1;
};

/// What a span's marches share, whatever their level: the segment in tiled reference space,
/// the lights as seen from it (a directional light's direction, irradiance, reference-space
/// direction and reflectance kernel are constant along the span), and the shadow queries the
/// first march took, which a second march of a blend may reuse.
struct SpanContext {
    static constexpr int kTrackCapacity = 32;
    /// The shadow queries of the first (coarse) march of a blend, by light: where along the span
    /// they were taken and what they found.
    struct ShadowTrack {
        int count = 0;
        std::array<double, kTrackCapacity> s, t;
    };
    struct Light {
        bool directional = false;
        bool usable = false;   ///< directional: lr is finite
        int latticeSlot = -1;  ///< directional, usable, and the cell has a transmittance lattice
        Vec3 lw = Vec3::Zero(), lr = Vec3::Zero();
        Color e = Color::Zero();
        std::optional<primitive::ReflectanceKernel> kernel;  ///< directional, usable, fast shading
    };

    /// `scale`: localScale at the span's middle, which the caller took to choose the levels.
    SpanContext(const Scene& scene, const RenderOptions& options, const ShadowQueries& shadows, const Prim& prim,
                const SurfaceRuntime& surface, const TexelRuntime& texel, const Vec3& rIn, const Vec3& rOut,
                double tIn, double tOut, double scale, double startTransmittance, int coarseLevel);

    /// The light direction lw (world) in unit tiled reference space; false where undefined.
    bool referenceLight(const Vec3& lw, Vec3& lr) const;

    const Prim& prim;
    const SurfaceRuntime& surface;
    const TexelRuntime& texel;
    Vec3 p0, p1, dir;      ///< tiled reference space; dir unit
    double length = 0;     ///< 0: an empty span, not marched
    double tIn, tOut;      ///< along the camera ray
    double scale = 1;      ///< world length per reference unit at the span's middle
    double startT = 1;     ///< the path's transmittance where the span starts
    Mat3 jtInv;            ///< world → tiled reference directions at the span's middle
    /// A second march takes a recorded shadow query within this distance (one coarse voxel).
    double shareDistance = 1;
    /// The shadow queries' level along the whole span, once a march has chosen it (the span's
    /// other march takes it too): −1 where it changes along the span (chosen per query), −2 not
    /// chosen yet (SpanMarcher::constantShadowLevel).
    int shadowLevel = -2;
    PerLight<Light> lights;
    PerLight<ShadowTrack> tracks;
};

/// Where a voxel of a march is shaded: its middle, s along the span, as cell coordinates and,
/// made on first use (point lights and exact shadow rays need it), as a world point.
class VoxelPoint {
public:
    VoxelPoint(const SpanContext& span, double s) : s(s), mSpan(span) {}
    Vec3 cell() const { return mSpan.prim.map.toCell(mSpan.p0 + s * mSpan.dir); }
    const Vec3& world() {
        if (!mHaveWorld) mWorld = mSpan.prim.cell.map(cell());
        mHaveWorld = true;
        return mWorld;
    }
    const double s;

private:
    const SpanContext& mSpan;
    Vec3 mWorld = Vec3::Zero();
    bool mHaveWorld = false;
};

class SpanMarcher {
public:
    SpanMarcher(const Scene& scene, const RenderOptions& options, const ShadowQueries& shadows, double coneSpread)
        : mScene(scene), mOptions(options), mShadows(shadows), mConeSpread(coneSpread) {}

    /// The span's march at `level`, its colour and transmittance weighted by nothing (the blend
    /// weight only enters the reflectance-reuse budget). `record`: keep this march's shadow
    /// queries in the context for a second march; otherwise reuse recorded ones within
    /// SpanContext::shareDistance (RenderOptions::approximations.shareShadowRays).
    SpanResult march(SpanContext& span, int level, bool record, double blendWeight, Counters& counters) const;

private:
    /// Light i's transmittance at `point`: a query the span's first march recorded within
    /// SpanContext::shareDistance (unless this march records; `reuseAt` resumes the scan of the
    /// track), otherwise a new query (ShadowQueries), recorded when `record`.
    double shadowQuery(SpanContext& span, std::size_t i, const Vec3& lw, double distance, VoxelPoint& point,
                       bool record, int& reuseAt, Counters& counters) const;
    /// The Phong reflectance factors (material m) of the ellipsoid S lit along lr (unit, tiled
    /// reference space) and seen along `view`: the light's kernel where the span made one,
    /// otherwise the shading mode's method.
    primitive::ReflectanceFactors reflectance(const SpanContext::Light& light, const Material& m,
                                              const primitive::SggxMatrix& s, const Vec3& lr, const Vec3& view) const;
    /// The shadow queries' cone width (world units) at s along the span.
    double shadowWidth(const SpanContext& span, double s) const;
    /// SpanContext::shadowLevel, chosen on first use: the level is chosen once per span instead of
    /// per query (a logarithm each) when the whole span takes the same one.
    int constantShadowLevel(SpanContext& span) const;

    const Scene& mScene;
    const RenderOptions& mOptions;
    const ShadowQueries& mShadows;
    double mConeSpread;
};

}  // namespace vtex::render::detail
