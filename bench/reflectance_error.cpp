// Error against run time of the paper's reflectance method (apparent-ellipse sampling,
// Neyret 1994 §3.2) as its grid grows, against a high-sample reference computed by the
// independent method (quadrature over normals, 1024 rings = 2.1 M normals). Prints a
// Markdown table; usage: vtex_reflectance_error [cases=200] [seed=1].
#include <vtex/primitive/reflectance.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

using namespace vtex::primitive;

namespace {

struct Case {
    Ellipsoid ellipsoid;
    Vec3 light, view;
    double shininess;
    double diffuse, specular;  // reference
};

double percentile(std::vector<double> values, double p) {
    std::sort(values.begin(), values.end());
    return values[std::min(values.size() - 1, std::size_t(p * double(values.size())))];
}

}  // namespace

int main(int argc, char** argv) {
    const int caseCount = argc > 1 ? std::atoi(argv[1]) : 200;
    const unsigned seed = argc > 2 ? unsigned(std::atoi(argv[2])) : 1u;
    std::mt19937 rng(seed);
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> logAxis(std::log(0.01), 0.0), shininess(1, 50);
    auto direction = [&] { return Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized(); };

    // Shapes from discs and needles (1:100) to spheres; only configurations where the
    // primitive is lit and visible enough to matter (reference diffuse ≥ 0.01).
    std::vector<Case> cases;
    while (int(cases.size()) < caseCount) {
        const Mat3 R = Eigen::Quaterniond(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized().toRotationMatrix();
        const Ellipsoid e = Ellipsoid::fromAxes(R, Vec3(std::exp(logAxis(rng)), std::exp(logAxis(rng)), 1.0));
        Case c{e, direction(), direction(), shininess(rng), 0, 0};
        const auto reference = phongReflectanceNormalQuadrature(e, c.light, c.view, c.shininess, 1024);
        if (reference.diffuse < 0.01) continue;
        c.diffuse = reference.diffuse;
        c.specular = reference.specular;
        cases.push_back(c);
    }

    std::printf("| grid cells per axis | facets (≈) | time per evaluation (µs) | median rel. error diffuse | "
                "90th pct diffuse | median rel. error specular | 90th pct specular |\n");
    std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int n : {4, 8, 16, 32, 64, 128, 256}) {
        std::vector<double> diffuseErrors, specularErrors;
        double sink = 0;
        const auto start = std::chrono::steady_clock::now();
        for (const Case& c : cases) {
            const auto r = phongReflectanceApparentEllipse(c.ellipsoid, c.light, c.view, c.shininess, n);
            sink += r.diffuse;
            diffuseErrors.push_back(std::abs(r.diffuse - c.diffuse) / c.diffuse);
            specularErrors.push_back(std::abs(r.specular - c.specular) / std::max(c.specular, 1e-3));
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("| %d | %d | %.2f | %.2e | %.2e | %.2e | %.2e |\n", n, int(std::lround(n * n * 3.14159 / 4)),
                    1e6 * seconds / double(cases.size()), percentile(diffuseErrors, 0.5),
                    percentile(diffuseErrors, 0.9), percentile(specularErrors, 0.5),
                    percentile(specularErrors, 0.9));
        if (sink < 0) std::printf("impossible\n");
    }
    return 0;
}
