// The fast path's specular factor (ReflectanceKernel: the D_v lattice and the Phong lobe's
// points combined by multiple importance sampling) and the lattice alone (the fast path before
// issue 15's row 16), per family of shapes and shininess, against an unbiased Monte Carlo
// estimate of the same integral; the paper's method at 96 cells per axis beside it as a check
// of that truth (docs/micro-primitive.md, "The specular term of the fast path"). The fast path's
// 95th percentile comes with a bootstrap 90 % interval (the cases resampled): a family's largest
// errors are a few bright cases, so at 100 cases the percentile moves by ±0.05 between draws.
// The cases run in parallel (TBB); the figures do not depend on the thread count.
//   build/bench/vtex_specular_estimators [cases per family] [Monte Carlo samples per case] [shininesses]
// (shininesses comma-separated; default 1,10,30,60,100,300,1000)
#include <vtex/primitive/reflectance_kernel.h>

#include "bush_voxels.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <vector>

using namespace vtex::primitive;
using V = Eigen::Vector3d;
using M = Eigen::Matrix3d;

namespace {

constexpr double kPi = std::numbers::pi;

struct Frame {
    V k, j, i;
};
Frame frameAround(const V& v) {
    const double sign = std::copysign(1.0, v.z());
    const double a = -1.0 / (sign + v.z());
    const double b = v.x() * v.y() * a;
    return {V(1 + sign * v.x() * v.x() * a, sign * b, -sign * v.x()), V(b, sign + v.y() * v.y() * a, -v.y()), v};
}

// The integral ∫ D_v(N) (N·l)⁺ (n+2)/2π cosⁿα dN in plain double precision: D_v through the
// SGGX density of S, its samples through Heitz et al.'s VNDF sampler written with Eigen.
class Specular {
public:
    Specular(const M& s, const V& l, const V& v, double n)
        : mS(s), mInv(s.inverse()), mSqrtDet(std::sqrt(std::max(s.determinant(), 1e-300))),
          mArea(std::sqrt(v.dot(s * v))), mL(l), mV(v), mN(n), mFrame(frameAround(v)) {
        const M t = basis() * s * basis().transpose();
        const double sii = t(2, 2), blockDet = std::max(t(1, 1) * sii - t(1, 2) * t(1, 2), 1e-300);
        mMk = V(std::sqrt(std::abs(t.determinant()) / blockDet), 0, 0);
        mMj = V((t(0, 1) * sii - t(0, 2) * t(1, 2)) / std::sqrt(sii * blockDet), std::sqrt(blockDet / sii), 0);
        mMi = t.col(2) / std::sqrt(sii);
    }
    // A visible normal from a point of the unit disc.
    V visibleNormal(double x, double y) const {
        const V m = x * mMk + y * mMj + std::sqrt(std::max(0.0, 1 - x * x - y * y)) * mMi;
        return basis().transpose() * m.normalized();
    }
    // The half vector of l and a mirror direction drawn from the Phong lobe around v.
    V lobeNormal(double xi, double phi) const {
        const double c = std::pow(xi, 1 / (mN + 1)), s = std::sqrt(std::max(0.0, 1 - c * c));
        const V r = s * std::cos(phi) * mFrame.k + s * std::sin(phi) * mFrame.j + c * mFrame.i;
        return (mL + r).normalized();
    }
    double densityA(const V& n) const {
        const double nv = n.dot(mV), q = n.dot(mInv * n);
        return nv > 0 ? nv / (kPi * mSqrtDet * q * q * mArea) : 0;
    }
    double cosAlpha(const V& n) const { return 2 * n.dot(mL) * n.dot(mV) - mL.dot(mV); }
    double densityB(const V& n) const {
        const double nl = n.dot(mL), c = cosAlpha(n);
        return nl > 0 && c > 0 ? (mN + 1) / (2 * kPi) * std::pow(c, mN) * 4 * nl : 0;
    }
    double integrand(const V& n) const {
        const double nl = n.dot(mL), c = cosAlpha(n);
        return nl > 0 && c > 0 ? densityA(n) * nl * (mN + 2) / (2 * kPi) * std::pow(c, mN) : 0;
    }
    // Unbiased: one random sample of each strategy per round, balance heuristic.
    double monteCarlo(std::mt19937& rng, int rounds) const {
        std::uniform_real_distribution<double> u(0, 1);
        double sum = 0;
        for (int k = 0; k < rounds; ++k) {
            const double r = std::sqrt(u(rng)), phi = 2 * kPi * u(rng);
            for (const V& n : {visibleNormal(r * std::cos(phi), r * std::sin(phi)), lobeNormal(u(rng), 2 * kPi * u(rng))}) {
                const double f = integrand(n);
                if (f > 0) sum += f / (densityA(n) + densityB(n));
            }
        }
        return sum / rounds;
    }
    // The diffuse factor E_{D_v}[(N·l)⁺] / π, unbiased: visible normals drawn by the sampler.
    double diffuseMonteCarlo(std::mt19937& rng, int rounds) const {
        std::uniform_real_distribution<double> u(0, 1);
        double sum = 0;
        for (int k = 0; k < rounds; ++k) {
            const double r = std::sqrt(u(rng)), phi = 2 * kPi * u(rng);
            sum += std::max(0.0, visibleNormal(r * std::cos(phi), r * std::sin(phi)).dot(mL));
        }
        return sum / rounds / kPi;
    }
    // The 16-point D_v lattice alone: the fast path before row 16.
    double latticeOnly() const {
        const double golden = kPi * (3 - std::sqrt(5.0));
        double sum = 0;
        for (int i = 0; i < 16; ++i) {
            const double r = std::sqrt((i + 0.5) / 16);
            const V n = visibleNormal(r * std::cos(golden * i), r * std::sin(golden * i));
            const double nl = n.dot(mL), c = cosAlpha(n);
            if (nl > 0 && c > 0) sum += nl * (mN + 2) / (2 * kPi) * std::pow(c, mN);
        }
        return sum / 16;
    }

private:
    M basis() const {
        M b;
        b.row(0) = mFrame.k;
        b.row(1) = mFrame.j;
        b.row(2) = mFrame.i;
        return b;
    }
    M mS, mInv;
    double mSqrtDet, mArea;
    V mL, mV;
    double mN;
    Frame mFrame;
    V mMk, mMj, mMi;
};

double percentile95(std::vector<double> x) {
    if (x.empty()) return 0;
    std::sort(x.begin(), x.end());
    return x[std::size_t(0.95 * double(x.size() - 1))];
}

double meanOf(const std::vector<double>& x) {
    double mean = 0;
    for (const double v : x) mean += v / double(x.size());
    return mean;
}

/// Mean and 95th percentile of |x − truth| / mean(truth).
std::pair<double, double> errors(const std::vector<double>& x, const std::vector<double>& truth) {
    const double mean = meanOf(truth);
    std::vector<double> e;
    for (std::size_t i = 0; i < x.size(); ++i) e.push_back(std::abs(x[i] - truth[i]) / mean);
    return {meanOf(e), percentile95(e)};
}

/// The 5th and 95th percentiles of errors(estimate, truth)'s 95th percentile over `resamples`
/// bootstrap draws of the cases (the family's mean drawn with them).
std::pair<double, double> percentileInterval(const std::vector<double>& estimate, const std::vector<double>& truth,
                                             int resamples = 1000) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<std::size_t> any(0, truth.size() - 1);
    std::vector<double> draws, x(truth.size()), t(truth.size());
    for (int r = 0; r < resamples; ++r) {
        for (std::size_t k = 0; k < truth.size(); ++k) {
            const std::size_t i = any(rng);
            x[k] = estimate[i];
            t[k] = truth[i];
        }
        draws.push_back(errors(x, t).second);
    }
    std::sort(draws.begin(), draws.end());
    return {draws[std::size_t(0.05 * (resamples - 1))], draws[std::size_t(0.95 * (resamples - 1))]};
}

/// One family at one shininess: the cases' light and view drawn in order from `rng` and `g` (so that the
/// cases do not depend on the threads), then every estimate of every case in parallel. Diffuse:
/// the diffuse factor (no lattice-alone column: the fast path's diffuse is that lattice).
struct Estimates {
    std::vector<double> truth, lattice, fast, paper;
};
Estimates estimate(const std::vector<M>& shapes, double n, std::mt19937& rng, std::normal_distribution<double>& g, int rounds,
                   bool diffuse) {
    std::vector<V> lights, views;
    for (std::size_t k = 0; k < shapes.size(); ++k) {
        const V l(g(rng), g(rng), g(rng)), v(g(rng), g(rng), g(rng));
        lights.push_back(l.normalized());
        views.push_back(v.normalized());
    }
    const std::size_t count = shapes.size();
    Estimates e{std::vector<double>(count), std::vector<double>(count), std::vector<double>(count), std::vector<double>(count)};
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t k) {
        const V& l = lights[k];
        const V& v = views[k];
        const Specular integral(shapes[k], l, v, n);
        std::mt19937 mc(7);
        const SggxMatrix m = SggxMatrix::fromUpper(shapes[k]);
        if (diffuse) {
            e.truth[k] = integral.diffuseMonteCarlo(mc, rounds);
            e.fast[k] = reflectanceFast(m, l, v, n).diffuse;
            e.paper[k] = reflectanceReference(m, l, v, n, 96).diffuse;
            return;
        }
        e.truth[k] = integral.monteCarlo(mc, rounds);
        e.lattice[k] = integral.latticeOnly();
        e.fast[k] = reflectanceFast(m, l, v, n).specular;
        e.paper[k] = reflectanceReference(m, l, v, n, 96).specular;
    });
    return e;
}

void printRow(const char* first, const char* family, const Estimates& e, bool lattice) {
    const auto [fm, fp] = errors(e.fast, e.truth);
    const auto [pm, pp] = errors(e.paper, e.truth);
    const auto [low, high] = percentileInterval(e.fast, e.truth);
    std::printf("%9s %-14s %8.4f | ", first, family, meanOf(e.truth));
    if (lattice) {
        const auto [lm, lp] = errors(e.lattice, e.truth);
        std::printf("%6.3f / %6.3f | ", lm, lp);
    }
    std::printf("%6.3f / %6.3f [%5.3f, %5.3f] | %6.3f / %6.3f\n", fm, fp, low, high, pm, pp);
}

}  // namespace

int main(int argc, char** argv) {
    const int perFamily = argc > 1 ? std::atoi(argv[1]) : 100;
    const int rounds = argc > 2 ? std::atoi(argv[2]) : 50000;
    std::vector<double> shininesses{1, 10, 30, 60, 100, 300, 1000};
    if (argc > 3) {
        shininesses.clear();
        for (const char* p = argv[3]; *p;) {
            char* end = nullptr;
            const double n = std::strtod(p, &end);
            if (end == p || !(n >= 0) || n > 1e6) {
                std::fprintf(stderr, "vtex_specular_estimators: bad shininess list '%s'\n", argv[3]);
                return 2;
            }
            shininesses.push_back(n);
            p = *end == ',' ? end + 1 : end;
        }
    }
    std::mt19937 rng(1);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> logRatio(-4, 0);
    const char* families[] = {"sphere", "random 1…1e-4", "disc 1e-3", "needle 1e-3", "bush voxels"};
    std::vector<std::vector<M>> shapes(5);
    for (int family = 0; family < 4; ++family)
        for (int k = 0; k < perFamily; ++k) {
            const M r = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
            const V sigma = family == 0   ? V(1, 1, 1)
                            : family == 1 ? V(std::pow(10.0, logRatio(rng)), std::pow(10.0, logRatio(rng)), 1)
                            : family == 2 ? V(1e-3, 1e-3, 1)
                                          : V(1, 1, 1e-3);
            shapes[std::size_t(family)].push_back(r * sigma.cwiseAbs2().asDiagonal() * r.transpose());
        }
    shapes[4] = vtex::bench::bushVoxels(rng, perFamily);
    std::printf("mean |error| / mean and 95th percentile of |error| / mean, against Monte Carlo (%d rounds)\n", rounds);
    std::printf("%9s %-14s %8s | %-15s | %-15s %-16s | %s\n", "shininess", "family", "mean", "lattice alone", "fast path",
                "(95th: 90 % int.)", "paper 96 cells vs MC");
    for (const double n : shininesses)
        for (std::size_t family = 0; family < 5; ++family) {
            char label[32];
            std::snprintf(label, sizeof label, "%.0f", n);
            printRow(label, families[family], estimate(shapes[family], n, rng, g, rounds, false), true);
        }
    // The diffuse factor does not depend on the shininess: one row per family, drawn after the
    // specular rows (which stay the cases they were).
    std::printf("\ndiffuse factor, the same measures\n%9s %-14s %8s | %-15s %-16s | %s\n", "", "family", "mean", "fast path",
                "(95th: 90 % int.)", "paper 96 cells vs MC");
    for (std::size_t family = 0; family < 5; ++family) printRow("", families[family], estimate(shapes[family], 20, rng, g, rounds, true), false);
}
