// The base faces and texel cells as one Embree 3 user geometry (exact bilinear-patch tests in
// double precision behind Embree's float BVH). Embree types stay in tracer.cpp.
#pragma once

#include "prim_table.h"

#include <vtex/render/geometry.h>

#include <array>
#include <limits>
#include <new>
#include <optional>
#include <vector>

namespace vtex::render::detail {

struct Hit {
    int prim = -1;
    double t = 0;        ///< where the ray enters the primitive (≥ tNear)
    double u = 0, v = 0; ///< plain patch parameters
    CellSpan span;       ///< cells: the span entered (tIn may be < tNear when the ray starts inside)
};

/// The spans of the cells a ray has met, kept across the trace() calls of one ray (same origin
/// and direction, growing tNear): Embree offers the cells behind tNear again, and their six
/// patch tests would be repeated for nothing. A small ring buffer; one per ray (or per cell test
/// of a ray traced without one), never shared.
/// Its slots are left uninitialised until a cell's spans are written into one (write()), so that
/// a cache costs two stores to make: default-initialising their 64 CellSpans was ~980
/// instructions for every camera and shadow ray, 23 % of the bush field's far view, most of whose
/// rays meet one cell or none.
struct SpanCache {
    static constexpr int kSize = 16;
    using Spans = std::array<CellSpan, 4>;
    union Slot {
        Slot() {}  // no CellSpan constructed: see write()
        Spans spans;
    };
    std::array<int, kSize> prim;
    std::array<int, kSize> count;
    std::array<Slot, kSize> slots;
    int used = 0;
    int next = 0;

    /// Slot i's spans, begun afresh (the only way a slot's spans come to life).
    Spans& write(std::size_t i) { return *::new (&slots[i].spans) Spans; }
    /// Slot i's spans, written by write(i) for the ray's prim[i] (i < used).
    const Spans& read(std::size_t i) const { return slots[i].spans; }
};

class Tracer {
public:
    explicit Tracer(PrimTable prims);
    ~Tracer();
    Tracer(const Tracer&) = delete;
    Tracer& operator=(const Tracer&) = delete;

    /// The nearest primitive along o + t·d with t > tNear (a cell also when the ray is inside
    /// it at tNear, with its span clipped to start there), t < tFar.
    std::optional<Hit> trace(const Vec3& o, const Vec3& d, double tNear,
                             double tFar = std::numeric_limits<double>::infinity(),
                             SpanCache* cache = nullptr) const;

    const PrimTable& prims() const { return mPrims; }
    /// The bounds of every primitive (empty, lo > hi, without any).
    const Vec3& boundsLo() const { return mLo; }
    const Vec3& boundsHi() const { return mHi; }

private:
    /// Whether o + t·d can meet the primitives' bounds for some t in (tNear + a hair, tFar].
    bool mayHit(const Vec3& o, const Vec3& d, double tNear, double tFar) const;

    PrimTable mPrims;
    /// The exact (double) bounds of every primitive (a patch and a cell lie in the convex hull of
    /// their corners), and 1e-9 of their size: a ray that is inside them for less than that past
    /// tNear meets nothing Embree would report (mayHit).
    Vec3 mLo = Vec3::Constant(INFINITY), mHi = Vec3::Constant(-INFINITY);
    double mHair = 0;
    void* mDevice = nullptr;
    void* mScene = nullptr;
};

}  // namespace vtex::render::detail
