// The mirror-facet closed form of the specular factor beside the fast path, both against the
// paper's method (docs/micro-primitive.md, "The mirror-facet limit of the specular term"):
// mean |error| / mean specular per shape family and shininess, for the widened S of several β.
// Not used by the renderer: a measurement of why it is not.
#include <vtex/primitive/reflectance_kernel.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

using namespace vtex::primitive;
using V = Eigen::Vector3d;
using M = Eigen::Matrix3d;

namespace {

// (n+2)/(n+1) · (h·v) D(h) / (4 A(v)) with D the SGGX density of S + β tr(S)/n · I.
double closedForm(const SggxMatrix& s, const V& l, const V& v, double n, double beta) {
    const M S = s.matrix();
    const double A = std::sqrt(std::max(v.dot(S * v), 1e-300));
    const V sum = l + v;
    if (sum.norm() < 1e-9) return 0;
    const V h = sum.normalized();
    const double hv = h.dot(v);
    if (hv <= 0) return 0;
    const M widened = S + (beta * S.trace() / n) * M::Identity();
    const double q = h.dot(widened.inverse() * h);
    const double D = 1.0 / (std::numbers::pi * std::sqrt(widened.determinant()) * q * q);
    return (n + 2) / (n + 1) * hv * D / (4 * A);
}

}  // namespace

int main() {
    std::mt19937 rng(1);
    std::normal_distribution<double> g;
    std::uniform_real_distribution<double> logRatio(-4, 0);
    struct Case {
        SggxMatrix s;
        V l, v;
        int family;
    };
    std::vector<Case> cases;
    const char* families[] = {"sphere", "random axes", "disc 1e-3", "needle 1e-3"};
    for (int family = 0; family < 4; ++family)
        for (int k = 0; k < 150; ++k) {
            const M r = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
            const V sigma = family == 0   ? V(1, 1, 1)
                            : family == 1 ? V(std::pow(10.0, logRatio(rng)), std::pow(10.0, logRatio(rng)), 1)
                            : family == 2 ? V(1e-3, 1e-3, 1)
                                          : V(1, 1, 1e-3);
            const M s = r * sigma.cwiseAbs2().asDiagonal() * r.transpose();
            const V l(g(rng), g(rng), g(rng)), v(g(rng), g(rng), g(rng));
            cases.push_back({SggxMatrix::fromUpper(s), l.normalized(), v.normalized(), family});
        }
    const double betas[] = {0.25, 0.5, 1.0, 2.0};
    std::printf("%9s %-12s %8s %7s %s\n", "shininess", "family", "mean", "fast", "closed form, beta 0.25 / 0.5 / 1 / 2");
    for (const double n : {1.0, 10.0, 100.0, 1000.0}) {
        std::vector<double> truth, fast;
        for (const Case& c : cases) {
            truth.push_back(reflectanceReference(c.s, c.l, c.v, n, 96).specular);
            fast.push_back(reflectanceFast(c.s, c.l, c.v, n).specular);
        }
        for (int family = 0; family < 4; ++family) {
            double mean = 0, fastError = 0, closedError[4] = {0, 0, 0, 0};
            for (std::size_t i = 0; i < cases.size(); ++i) {
                if (cases[i].family != family) continue;
                mean += truth[i];
                fastError += std::abs(fast[i] - truth[i]);
                for (int b = 0; b < 4; ++b)
                    closedError[b] += std::abs(closedForm(cases[i].s, cases[i].l, cases[i].v, n, betas[b]) - truth[i]);
            }
            std::printf("%9.0f %-12s %8.4f %7.3f %.3f / %.3f / %.3f / %.3f\n", n, families[family], mean / 150,
                        fastError / mean, closedError[0] / mean, closedError[1] / mean, closedError[2] / mean,
                        closedError[3] / mean);
        }
    }
}
