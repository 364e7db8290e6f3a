// The fast micro-primitive reflectance (see reflectance_kernel.h): the SGGX visible-normal
// distribution through the closed-form sampler of Heitz et al. 2015 (Listing 3) on a fixed lattice.
#include <vtex/primitive/reflectance_kernel.h>

#include "band_specular.h"
#include "fibre_specular.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vtex::primitive {

using Eigen::Vector3d;

// Fixed points on the unit disc: a Fibonacci lattice, radius √((i+½)/n) for equal areas. Kept
// in single precision for the 4-wide loop below (n is a multiple of 4).
struct ReflectanceKernel::Lattice {
    alignas(16) std::array<float, 64> x{}, y{}, z{};  ///< z: the point lifted onto the hemisphere
    int n = 0;
    explicit Lattice(int count) : n(count) {
        const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
        for (int i = 0; i < n; ++i) {
            const double r = std::sqrt((i + 0.5) / n);
            const double px = r * std::cos(golden * i), py = r * std::sin(golden * i);
            x[std::size_t(i)] = float(px);
            y[std::size_t(i)] = float(py);
            z[std::size_t(i)] = float(std::sqrt(std::max(0.0, 1 - px * px - py * py)));
        }
    }
    double diffuseScale = 1 / (n * std::numbers::pi);  ///< Σ (N·l)⁺ / n over π
};

namespace {

// The lobe's fixed points (strategy B of the specular term, reflectance_kernel.h): mirror
// directions r around v drawn from the normalised Phong lobe (n+1)/2π cosⁿα by its inverse
// cumulative distribution, cos α = ξ^{1/(n+1)} at ξ = (k+½)/K, azimuth on the golden angle.
// They depend on the shininess alone; a thread keeps the last shininess's, since a scene's
// texels rarely have more than one and the powers are the costliest part of a kernel's setup.
struct LobeLattice {
    static constexpr int kCount = ReflectanceKernel::kLobeSamples;
    double shininess = -1;
    /// r = (sin α cos φ, sin α sin φ, cos α) and cosⁿα, in single precision for setUpLobe's 4-wide loop
    alignas(16) std::array<float, kCount> x{}, y{}, z{}, cosPower{};
    double fibreGate = 0;  ///< detail::kernelFibreEigenRatioGate(n): a pow, so kept with the lobe's points
    double bandGate = 0;   ///< detail::bandEigenRatioGate(n)
    static const LobeLattice& forShininess(double n) {
        thread_local LobeLattice cached;
        if (cached.shininess != n) {
            const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
            for (std::size_t k = 0; k < std::size_t(kCount); ++k) {
                const double xi = (double(k) + 0.5) / kCount;
                const double cosAlpha = std::pow(xi, 1 / (n + 1));
                const double sinAlpha = std::sqrt(std::max(0.0, 1 - cosAlpha * cosAlpha));
                cached.x[k] = float(sinAlpha * std::cos(golden * double(k)));
                cached.y[k] = float(sinAlpha * std::sin(golden * double(k)));
                cached.z[k] = float(cosAlpha);
                cached.cosPower[k] = float(std::pow(xi, n / (n + 1)));  // cosⁿα
            }
            cached.fibreGate = detail::kernelFibreEigenRatioGate(n);
            cached.bandGate = detail::bandEigenRatioGate(n);
            cached.shininess = n;
        }
        return cached;
    }
};

// The shininess as a whole number in [0, 1024], for which xⁿ is taken by repeated squaring
// (exact to a few ulps, ~6 multiplies instead of a libm pow); −1 otherwise. (std::floor is a
// libm call on SSE2: the round trip through int is the same test for n in range.)
int wholePower(double n) { return n >= 0 && n <= 1024 && double(int(n)) == n ? int(n) : -1; }

// pow(1e-6, 1/n) for whole n ≤ 64 (n = 0 unused), beyond which n is clamped to 64: a lower
// cut-off only keeps more terms.
const std::array<double, 65> kCosCutoffs = [] {
    std::array<double, 65> c{};
    for (int n = 1; n <= 64; ++n) c[std::size_t(n)] = std::pow(1e-6, 1.0 / n);
    return c;
}();

}  // namespace

// The kernel's set-up and evaluation are compiled for AVX2 as well and chosen at load time where
// the processor has it (as in ellipsoid.cpp): the same SSE2 intrinsics in VEX encoding, whose
// three-operand instructions save the register copies and spills that 16 two-operand registers
// force on the lattice's and the fibre's loops. Every lane rounds as in the SSE2 build, in the
// same order ("avx2" enables no FMA instruction to contract into): both give the same bits.
// `flatten` inlines the member functions each calls into the clone. GCC only: Clang 14 (the fuzz
// build's compiler) cannot combine target_clones with flatten, and builds the SSE2 code alone.
#if defined(__x86_64__) && defined(__has_attribute) && !defined(__clang__)
#if __has_attribute(target_clones) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define VTEX_KERNEL_CLONES __attribute__((target_clones("avx2", "default"), flatten))
#endif
#endif
#ifndef VTEX_KERNEL_CLONES
#define VTEX_KERNEL_CLONES
#endif
struct ReflectanceKernel::Clones {
    static void setUp(ReflectanceKernel& k, const Vector3d& wk, const Vector3d& wj, const Vector3d& wi);
    static void setUpLobe(ReflectanceKernel& k);
    static ReflectanceFactors evaluate(const ReflectanceKernel& k, const SggxMatrix& s);
    /// detail::bandSpecular in the kernel's frame: a call of its own (not flattened into
    /// evaluate, whose common path it would crowd), in its own clones.
    static double band(const ReflectanceKernel& k, const Eigen::Matrix3d& s);
};

ReflectanceFactors ReflectanceKernel::operator()(const SggxMatrix& s) const { return Clones::evaluate(*this, s); }

double ReflectanceKernel::power(double c) const {
    if (mWholePower < 0) return std::pow(c, mShininess);
    double result = 1;
    for (int e = mWholePower; e > 0; e >>= 1) {
        if (e & 1) result *= c;
        c *= c;
    }
    return result;
}

ReflectanceKernel::ReflectanceKernel(const Vector3d& light, const Vector3d& view, double shininess, int samples,
                                     bool specular)
    : mShininess(shininess), mWholePower(wholePower(shininess)), mSpecular(specular) {
    // One guard for the four lattices (a call to reflectanceFast builds a kernel each time).
    static const std::array<Lattice, 4> lattices{Lattice(8), Lattice(16), Lattice(32), Lattice(64)};
    mLattice = &lattices[samples <= 8 ? 0 : samples <= 16 ? 1 : samples <= 32 ? 2 : 3];
    // Orthonormal basis (wk, wj, wi) with wi = view (Frisvad/Duff's branchless construction).
    const double sign = std::copysign(1.0, view.z());
    const double a = -1.0 / (sign + view.z());
    const double b = view.x() * view.y() * a;
    const Vector3d wk(1 + sign * view.x() * view.x() * a, sign * b, -sign * view.x());
    const Vector3d wj(b, sign + view.y() * view.y() * a, -view.y());
    Clones::setUp(*this, wk, wj, view);
    mLight = Eigen::Vector3f(float(light.dot(wk)), float(light.dot(wj)), float(light.dot(view)));
    // cosⁿα below 1e-6 of its peak is dropped: pow is the costliest step of the loop.
    mCosCutoff = float(shininess <= 0        ? 0.0
                       : mWholePower >= 0    ? kCosCutoffs[std::size_t(std::min(mWholePower, 64))]
                                             : std::pow(1e-6, 1 / shininess));
    mDiffuseScale = mLattice->diffuseScale;
    mSpecularScale = (shininess + 2) / (2 * std::numbers::pi) / mLattice->n;
    if (specular && shininess >= 0) Clones::setUpLobe(*this);
}

// pᵀSq over S's entries for the six pairs (p, q) of basis vectors: the diagonal entries once,
// the off-diagonal ones for both halves.
inline void ReflectanceKernel::setUpProjection(const Vector3d& wk, const Vector3d& wj, const Vector3d& wi) {
#if defined(__SSE2__)
    // Two outputs at a time, the same products as the scalar loop below: P and Q hold, for one
    // coordinate c, the pairs' c components, outputs (kk, jj, ii, kj, ki, ji) in order.
    struct Six {
        __m128d o01, o23, o45;
    };
    const auto p = [&](int c) { return Six{_mm_set_pd(wj[c], wk[c]), _mm_set_pd(wk[c], wi[c]), _mm_set_pd(wj[c], wk[c])}; };
    const auto q = [&](int c) { return Six{_mm_set_pd(wj[c], wk[c]), _mm_set_pd(wj[c], wi[c]), _mm_set1_pd(wi[c])}; };
    const Six px = p(0), py = p(1), pz = p(2), qx = q(0), qy = q(1), qz = q(2);
    const auto store = [this](std::size_t row, __m128d o01, __m128d o23, __m128d o45) {
        _mm_store_pd(&mProjection[6 * row], o01);
        _mm_store_pd(&mProjection[6 * row + 2], o23);
        _mm_store_pd(&mProjection[6 * row + 4], o45);
    };
    const auto square = [&](std::size_t row, const Six& a, const Six& b) {
        store(row, _mm_mul_pd(a.o01, b.o01), _mm_mul_pd(a.o23, b.o23), _mm_mul_pd(a.o45, b.o45));
    };
    const auto mixed = [&](std::size_t row, const Six& pa, const Six& qb, const Six& pb, const Six& qa) {
        store(row, _mm_add_pd(_mm_mul_pd(pa.o01, qb.o01), _mm_mul_pd(pb.o01, qa.o01)),
              _mm_add_pd(_mm_mul_pd(pa.o23, qb.o23), _mm_mul_pd(pb.o23, qa.o23)),
              _mm_add_pd(_mm_mul_pd(pa.o45, qb.o45), _mm_mul_pd(pb.o45, qa.o45)));
    };
    square(0, px, qx);
    square(1, py, qy);
    square(2, pz, qz);
    mixed(3, px, qy, py, qx);
    mixed(4, px, qz, pz, qx);
    mixed(5, py, qz, pz, qy);
#else
    const std::array<std::pair<const Vector3d&, const Vector3d&>, 6> outputs{
        {{wk, wk}, {wj, wj}, {wi, wi}, {wk, wj}, {wk, wi}, {wj, wi}}};
    for (std::size_t o = 0; o < 6; ++o) {
        const auto& [p, q] = outputs[o];
        mProjection[o] = p.x() * q.x();
        mProjection[6 + o] = p.y() * q.y();
        mProjection[12 + o] = p.z() * q.z();
        mProjection[18 + o] = p.x() * q.y() + p.y() * q.x();
        mProjection[24 + o] = p.x() * q.z() + p.z() * q.x();
        mProjection[30 + o] = p.y() * q.z() + p.z() * q.y();
    }
#endif
}

// Strategy B: the half vector between l and each of the lobe's mirror directions r (in the
// kernel's frame, where v = (0, 0, 1)); those facing away from v see nothing: their term is 0
// (and their normal v, which keeps the weights' arithmetic finite).
inline void ReflectanceKernel::setUpLobe() {
    const LobeLattice& lobe = LobeLattice::forShininess(mShininess);
    const float lx = mLight.x(), ly = mLight.y(), lz = mLight.z();
#if defined(__SSE2__)
    // Four points at a time in single precision, as the light (mLight) already is: this runs
    // once per kernel, but reflectanceFast builds one per call.
    const __m128 vlx = _mm_set1_ps(lx), vly = _mm_set1_ps(ly), vlz = _mm_set1_ps(lz);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1), tiny = _mm_set1_ps(1e-24f);
    for (std::size_t k = 0; k < std::size_t(kLobeSamples); k += 4) {
        const __m128 x = _mm_add_ps(vlx, _mm_load_ps(&lobe.x[k])), y = _mm_add_ps(vly, _mm_load_ps(&lobe.y[k]));
        const __m128 z = _mm_add_ps(vlz, _mm_load_ps(&lobe.z[k]));
        const __m128 length2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)), _mm_mul_ps(z, z));
        const __m128 faces = _mm_and_ps(_mm_cmpgt_ps(length2, tiny), _mm_cmpgt_ps(z, zero));
        const __m128 inverse = _mm_and_ps(faces, _mm_div_ps(one, _mm_sqrt_ps(_mm_max_ps(length2, tiny))));
        _mm_store_ps(&mLobeX[k], _mm_mul_ps(x, inverse));
        _mm_store_ps(&mLobeY[k], _mm_mul_ps(y, inverse));
        _mm_store_ps(&mLobeZ[k], _mm_or_ps(_mm_and_ps(faces, _mm_mul_ps(z, inverse)), _mm_andnot_ps(faces, one)));
        const __m128 nl = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(x, vlx), _mm_mul_ps(y, vly)), _mm_mul_ps(z, vlz)), inverse);
        _mm_store_ps(&mLobeTerm[k], _mm_mul_ps(nl, _mm_load_ps(&lobe.cosPower[k])));
        const int mask = _mm_movemask_ps(faces);  // popcount is a libgcc call without SSE4.2
        mLobeCount += (mask & 1) + (mask >> 1 & 1) + (mask >> 2 & 1) + (mask >> 3);
    }
#else
    for (std::size_t k = 0; k < std::size_t(kLobeSamples); ++k) {
        const float x = lx + lobe.x[k], y = ly + lobe.y[k], z = lz + lobe.z[k];
        const float length2 = x * x + y * y + z * z;
        const bool faces = length2 > 1e-24f && z > 0;
        const float inverse = faces ? 1 / std::sqrt(length2) : 0;
        mLobeX[k] = x * inverse;
        mLobeY[k] = y * inverse;
        mLobeZ[k] = faces ? z * inverse : 1;
        mLobeTerm[k] = (x * lx + y * ly + z * lz) * inverse * lobe.cosPower[k];
        mLobeCount += faces;
    }
#endif
    mLobeRatio = double(kLobeSamples) / mLattice->n * 2 * (mShininess + 1);
    mFibreGate = lobe.fibreGate;
    mBandGate = lobe.bandGate;
}

// Strategy B's sum: each half vector's pre-image q = C⁻¹N (back substitution), at which A's
// density is (q_z/|q|)/π and B's is (n+1)/2π cosⁿα 4(N·l) · |det C| |q|³; term / (1 + ratio)
// with ratio = K term |det C| |q|⁴ / q_z, written with one division. Four points at a time in
// single precision: |q|⁴ reaches 1e16 on needles at the axis-ratio floor, well inside float's
// range (3e38), and a lane that overflows is dropped (its weight there is B's alone, ≈ 0).
inline double ReflectanceKernel::lobeSum(double mkx, double mjx, double mjy, const Vector3d& Mi, double detC) const {
#if defined(__SSE2__)
    const __m128 ik = _mm_set1_ps(float(1 / mkx)), ij = _mm_set1_ps(float(1 / mjy)), ii = _mm_set1_ps(float(1 / Mi.z()));
    const __m128 mix = _mm_set1_ps(float(Mi.x())), miy = _mm_set1_ps(float(Mi.y())), jx = _mm_set1_ps(float(mjx));
    const __m128 f = _mm_set1_ps(float(mLobeRatio * detC)), infinity = _mm_set1_ps(std::numeric_limits<float>::infinity());
    const __m128 absMask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    __m128 sum = _mm_setzero_ps();
    for (std::size_t k = 0; k < std::size_t(kLobeSamples); k += 4) {
        const __m128 qz = _mm_mul_ps(_mm_load_ps(&mLobeZ[k]), ii);
        const __m128 qy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(&mLobeY[k]), _mm_mul_ps(miy, qz)), ij);
        const __m128 qx = _mm_mul_ps(_mm_sub_ps(_mm_sub_ps(_mm_load_ps(&mLobeX[k]), _mm_mul_ps(jx, qy)), _mm_mul_ps(mix, qz)), ik);
        const __m128 q2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(qx, qx), _mm_mul_ps(qy, qy)), _mm_mul_ps(qz, qz));
        const __m128 term = _mm_load_ps(&mLobeTerm[k]);
        const __m128 c = _mm_div_ps(_mm_mul_ps(term, qz), _mm_add_ps(qz, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(f, q2), q2), term)));
        // Overflow on a degenerate S counts nothing (an ordered, finite contribution only).
        sum = _mm_add_ps(sum, _mm_and_ps(_mm_cmplt_ps(_mm_and_ps(c, absMask), infinity), c));
    }
    alignas(16) float parts[4];
    _mm_store_ps(parts, sum);
    return double(parts[0]) + double(parts[1]) + double(parts[2]) + double(parts[3]);
#else
    const double inverseK = 1 / mkx, inverseJ = 1 / mjy, inverseI = 1 / Mi.z();
    const double factor = mLobeRatio * detC;
    double sum = 0;
    for (std::size_t k = 0; k < std::size_t(kLobeSamples); ++k) {
        const double qz = mLobeZ[k] * inverseI;
        const double qy = (mLobeY[k] - Mi.y() * qz) * inverseJ;
        const double qx = (mLobeX[k] - mjx * qy - Mi.x() * qz) * inverseK;
        const double q2 = qx * qx + qy * qy + qz * qz, term = mLobeTerm[k];
        const double contribution = term * qz / (qz + factor * q2 * q2 * term);
        if (std::isfinite(contribution)) sum += contribution;
    }
    return sum;
#endif
}

inline ReflectanceFactors ReflectanceKernel::evaluate(const SggxMatrix& s) const {
    const double entries[6] = {s.xx, s.yy, s.zz, s.xy, s.xz, s.yz};
    alignas(16) double t[6] = {};
#if defined(__SSE2__)
    // Two outputs per instruction: the compiler leaves this product scalar.
    __m128d t01 = _mm_setzero_pd(), t23 = t01, t45 = t01;
    for (std::size_t e = 0; e < 6; ++e) {
        const __m128d se = _mm_set1_pd(entries[e]);
        const double* c = &mProjection[6 * e];
        t01 = _mm_add_pd(t01, _mm_mul_pd(se, _mm_load_pd(c)));
        t23 = _mm_add_pd(t23, _mm_mul_pd(se, _mm_load_pd(c + 2)));
        t45 = _mm_add_pd(t45, _mm_mul_pd(se, _mm_load_pd(c + 4)));
    }
    _mm_store_pd(t, t01);
    _mm_store_pd(t + 2, t23);
    _mm_store_pd(t + 4, t45);
#else
    for (std::size_t e = 0; e < 6; ++e)
        for (std::size_t o = 0; o < 6; ++o) t[o] += mProjection[6 * e + o] * entries[e];
#endif
    const double Skk = t[0], Sjj = t[1], Sii = t[2], Skj = t[3], Ski = t[4], Sji = t[5];
    if (!(Sii > 0)) return {};
    // Heitz et al.'s Listing 3 with its square roots and divisions shared: blockDet (their tmp²)
    // is the determinant of the (j,i) block; S is floored away from singular by the ellipsoid's
    // axis-ratio floor, but float storage can round it to 0: keep it positive.
    const double rawBlockDet = Sjj * Sii - Sji * Sji;
    const double blockDet = std::max(rawBlockDet, 1e-30 * Sii * Sii);
    const double cross = Skj * Sii - Ski * Sji;
    const double det = Skk * rawBlockDet - Skj * cross + Ski * (Skj * Sji - Sjj * Ski);
    const double r = 1 / std::sqrt(Sii * blockDet);
    const double invSqrtSii = std::sqrt(blockDet) * r;
    const Vector3d Mk(std::sqrt(std::abs(det) * Sii) * r, 0, 0);
    const Vector3d Mj(cross * r, blockDet * r, 0);
    const Vector3d Mi(invSqrtSii * Ski, invSqrtSii * Sji, invSqrtSii * Sii);
    // The VNDF sampler's map m = C u, C = [Mk Mj Mi] upper triangular: |det C| / |C u|³ is the
    // density of normals per unit of u, which the balance weights need (reflectance_kernel.h).
    const double detC = Mk.x() * Mj.y() * Mi.z();
    const double scale = Mi.z();  // = √Sii: folded into the float terms to keep them O(1)
    std::optional<double> fibre;
    // A needle much thinner than the lobe: neither strategy finds the short arc where the lobe
    // crosses its circle of normals; the fibre limit integrates along that circle. A thicker one
    // against a narrow lobe (from kBandShininess): the band rule integrates over the band of its
    // normals (src/band_specular.h). The gates are tested first with the invariants above (adj S's
    // diagonal: rawBlockDet and two more minors); the band's only where it has a window.
    const double trace = Skk + Sjj + Sii, trAdj = rawBlockDet + (Skk * Sii - Ski * Ski) + (Skk * Sjj - Skj * Skj);
    const auto sFrame = [&] { return (Eigen::Matrix3d() << Skk, Skj, Ski, Skj, Sjj, Sji, Ski, Sji, Sii).finished(); };
    if (mSpecular && detail::takesFibreLimit(trace, trAdj, det, mFibreGate)) {
        const Eigen::Matrix3d s3 = sFrame();
        fibre = detail::needleSpecular(s3, detail::adjugate(s3), mLight.cast<double>(), Vector3d(0, 0, 1), mCosCutoff,
                                       {mWholePower, mShininess});
    } else if (mSpecular && mBandGate > 0 && detail::takesFibreLimit(trace, trAdj, det, mBandGate)) {
        const Eigen::Matrix3d s3 = sFrame();
        if (detail::bandTakes(s3, mBandGate)) fibre = Clones::band(*this, s3);
    }
    const bool mis = mSpecular && !fibre && mLobeCount > 0 && detC > 0;
    const double lobeRatio = mis ? mLobeRatio * detC / (scale * scale * scale) : 0;
    const auto [diffuse, latticeSpecular] = latticeSums(Mk, Mj, Mi, scale, lobeRatio, mSpecular && !fibre);
    if (!mSpecular) return {diffuse * mDiffuseScale, 0};
    if (fibre) return {diffuse * mDiffuseScale, *fibre};
    double specular = latticeSpecular;
    if (mis) specular += lobeSum(Mk.x(), Mj.x(), Mj.y(), Mi, detC);
    return {diffuse * mDiffuseScale, specular * mSpecularScale};
}

// Strategy A's sums over the lattice: Σ (N·l)⁺ and Σ (N·l)⁺cosⁿα / (1 + ratio), the second with
// B's balance weight (ratio = K_B p_B / K_A p_A; lobeRatio 0 without B).
inline std::pair<double, double> ReflectanceKernel::latticeSums(const Vector3d& Mk, const Vector3d& Mj, const Vector3d& Mi,
                                                         double scale, double lobeRatio, bool wantSpecular) const {
    const Lattice& points = *mLattice;
    // m = u·Mk + v·Mj + w·Mi with Mk = (·,0,0), Mj = (·,·,0): written out. The sum runs in
    // single precision, four lattice points at a time (SSE2, part of every x86-64): its
    // rounding (~1e-7 relative) is far below the quadrature's own error.
#if defined(__SSE2__)
    const __m128 mkx = _mm_set1_ps(float(Mk.x())), mjx = _mm_set1_ps(float(Mj.x())), mjy = _mm_set1_ps(float(Mj.y()));
    const __m128 mix = _mm_set1_ps(float(Mi.x())), miy = _mm_set1_ps(float(Mi.y())), miz = _mm_set1_ps(float(Mi.z()));
    const __m128 lx = _mm_set1_ps(mLight.x()), ly = _mm_set1_ps(mLight.y()), lz = _mm_set1_ps(mLight.z());
    const __m128 lvv = lz, cut = _mm_set1_ps(mCosCutoff);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f), two = _mm_set1_ps(2.0f);
    const __m128 scaleV = _mm_set1_ps(float(scale)), ratioV = _mm_set1_ps(float(lobeRatio));
    __m128 diffuseSum = zero, specularSum = zero;
    for (int n = 0; n < points.n; n += 4) {
        const __m128 u = _mm_load_ps(&points.x[std::size_t(n)]);
        const __m128 v = _mm_load_ps(&points.y[std::size_t(n)]);
        const __m128 w = _mm_load_ps(&points.z[std::size_t(n)]);
        const __m128 mx = _mm_add_ps(_mm_add_ps(_mm_mul_ps(u, mkx), _mm_mul_ps(v, mjx)), _mm_mul_ps(w, mix));
        const __m128 my = _mm_add_ps(_mm_mul_ps(v, mjy), _mm_mul_ps(w, miy));
        const __m128 mz = _mm_mul_ps(w, miz);
        const __m128 ml = _mm_add_ps(_mm_add_ps(_mm_mul_ps(mx, lx), _mm_mul_ps(my, ly)), _mm_mul_ps(mz, lz));
        const __m128 len2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(mx, mx), _mm_mul_ps(my, my)), _mm_mul_ps(mz, mz));
        // Facets in their own shadow (N·l ≤ 0) and degenerate m count nothing.
        const __m128 lit = _mm_and_ps(_mm_cmpgt_ps(ml, zero), _mm_cmpgt_ps(len2, zero));
        const __m128 invLen = _mm_div_ps(one, _mm_sqrt_ps(_mm_max_ps(len2, _mm_set1_ps(1e-30f))));
        const __m128 nl = _mm_mul_ps(ml, invLen);
        diffuseSum = _mm_add_ps(diffuseSum, _mm_and_ps(lit, nl));
        if (!wantSpecular) continue;
        // cos α between v and the mirror of l about N: (2(N·l)N − l)·v.
        const __m128 cosAlpha = _mm_sub_ps(_mm_mul_ps(_mm_mul_ps(two, nl), _mm_mul_ps(mz, invLen)), lvv);
        const __m128 specular = _mm_and_ps(lit, _mm_cmpgt_ps(cosAlpha, cut));
        // Most groups of a call have no point in the lobe.
        if (_mm_movemask_ps(specular) == 0) continue;
        // libm's pow (a non-whole n) only where it counts: it costs more than the rest of the call.
        const __m128 p = detail::powerLanes(cosAlpha, specular, {mWholePower, mShininess});
        const __m128 term = _mm_mul_ps(nl, p);
        const __m128 s = _mm_mul_ps(invLen, scaleV);
        // term / (1 + ratio), ratio = K term (s|m|⁻¹)³ / w: term·w / (w + K term s³), one division.
        const __m128 weighted = _mm_mul_ps(_mm_mul_ps(ratioV, term), _mm_mul_ps(s, _mm_mul_ps(s, s)));
        specularSum = _mm_add_ps(specularSum, _mm_and_ps(specular, _mm_div_ps(_mm_mul_ps(term, w), _mm_add_ps(w, weighted))));
    }
    alignas(16) float sums[8];
    _mm_store_ps(sums, diffuseSum);
    _mm_store_ps(sums + 4, specularSum);
    return {double(sums[0]) + double(sums[1]) + double(sums[2]) + double(sums[3]),
            double(sums[4]) + double(sums[5]) + double(sums[6]) + double(sums[7])};
#else
    const Vector3d l = mLight.cast<double>();
    double diffuse = 0, specular = 0;
    for (int n = 0; n < points.n; ++n) {
        const double u = points.x[std::size_t(n)], v = points.y[std::size_t(n)];
        const double w = points.z[std::size_t(n)];
        const double mx = u * Mk.x() + v * Mj.x() + w * Mi.x();
        const double my = v * Mj.y() + w * Mi.y();
        const double mz = w * Mi.z();
        const double ml = mx * l.x() + my * l.y() + mz * l.z();
        if (!(ml > 0)) continue;  // facet in its own shadow (or a degenerate m)
        const double len2 = mx * mx + my * my + mz * mz;
        if (!(len2 > 0)) continue;
        const double invLen = 1 / std::sqrt(len2);
        const double nl = ml * invLen;
        diffuse += nl;
        if (!wantSpecular) continue;
        // cos α between v and the mirror of l about N: (2(N·l)N − l)·v.
        const double cosAlpha = 2 * nl * (mz * invLen) - l.z();
        if (!(cosAlpha > mCosCutoff)) continue;
        const double term = nl * power(cosAlpha), s = invLen * scale;
        specular += term / (1 + lobeRatio * term * s * s * s / w);
    }
    return {diffuse, specular};
#endif
}

ReflectanceFactors reflectanceFast(const SggxMatrix& s, const Vector3d& light, const Vector3d& view, double shininess, int samples,
                                   bool specular) {
    return ReflectanceKernel(light, view, shininess, samples, specular)(s);
}

VTEX_KERNEL_CLONES void ReflectanceKernel::Clones::setUp(ReflectanceKernel& k, const Vector3d& wk, const Vector3d& wj,
                                                         const Vector3d& wi) {
    k.setUpProjection(wk, wj, wi);
}
VTEX_KERNEL_CLONES void ReflectanceKernel::Clones::setUpLobe(ReflectanceKernel& k) { k.setUpLobe(); }
VTEX_KERNEL_CLONES ReflectanceFactors ReflectanceKernel::Clones::evaluate(const ReflectanceKernel& k, const SggxMatrix& s) {
    return k.evaluate(s);
}
#if defined(__GNUC__)
__attribute__((noinline))
#endif
VTEX_KERNEL_CLONES double ReflectanceKernel::Clones::band(const ReflectanceKernel& k, const Eigen::Matrix3d& s) {
    // The cut-off pow(1e-6, 1/n) = e^{−x}, x = ln(10⁶)/n, unclamped (mCosCutoff clamps n to 64: the
    // band rule's many nodes gain from the tighter one): 1 − x + x²/2 − x³/6 ≤ e^{−x}, within
    // 3e-4 of it from n = 50; a lower cut-off only keeps more terms.
    const double x = 13.815510557964274 / k.mShininess, cutoff = 1 - x * (1 - x / 2 * (1 - x / 3));
    return detail::bandSpecular(s, detail::adjugate(s), k.mLight.cast<double>(), Vector3d(0, 0, 1), cutoff,
                                {k.mWholePower, k.mShininess});
}
#undef VTEX_KERNEL_CLONES

}  // namespace vtex::primitive
