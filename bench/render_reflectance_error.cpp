// The fast micro-primitive reflectance (SGGX visible-normal quadrature) against the paper's
// numerical integration: error and time per evaluation, on random ellipsoids from spheres to
// discs and needles, random light and view directions. Prints a table (docs/render.md).
#include <vtex/primitive/reflectance_kernel.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

using namespace vtex::primitive;

int main() {
    std::mt19937 rng(1);
    std::normal_distribution<double> n;
    std::uniform_real_distribution<double> logRatio(-4, 0);
    struct Case {
        SggxMatrix s;
        Eigen::Vector3d l, v;
    };
    std::vector<Case> cases;
    for (int k = 0; k < 400; ++k) {
        const Eigen::Matrix3d r = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
        // σ spans 4 decades: discs (one σ large) and needles (one σ small) included.
        const Eigen::Vector3d sigma(std::pow(10.0, logRatio(rng)), std::pow(10.0, logRatio(rng)), 1.0);
        const Eigen::Matrix3d s = r * sigma.cwiseAbs2().asDiagonal() * r.transpose();
        cases.push_back({{s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(0, 2), s(1, 2)},
                         Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized(),
                         Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized()});
    }
    const double shininess = 20;
    std::vector<ReflectanceFactors> reference;
    const auto t0 = std::chrono::steady_clock::now();
    for (const Case& c : cases) reference.push_back(reflectanceReference(c.s, c.l, c.v, shininess, 64));
    const double refTime = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / cases.size();
    const auto t1 = std::chrono::steady_clock::now();
    for (const Case& c : cases) (void)reflectanceReference(c.s, c.l, c.v, shininess, 24);
    const double ref24Time = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count() / cases.size();
    double meanDiffuse = 0, meanSpecular = 0;
    for (const auto& r : reference) {
        meanDiffuse += r.diffuse / cases.size();
        meanSpecular += r.specular / cases.size();
    }
    std::printf("reference (64 per axis): %.1f us/eval; (24 per axis, the renderer's default): %.1f us/eval\n",
                refTime * 1e6, ref24Time * 1e6);
    std::printf("mean diffuse factor %.4f, mean specular factor %.4f (shininess %.0f)\n", meanDiffuse, meanSpecular, shininess);
    std::printf("%8s %12s %14s %14s %14s\n", "samples", "us/eval", "diffuse MAE/mean", "specular MAE/mean", "diffuse max abs");
    for (int samples : {8, 16, 32, 64}) {
        double dErr = 0, sErr = 0, dMax = 0;
        const auto start = std::chrono::steady_clock::now();
        double sink = 0;
        for (int rep = 0; rep < 50; ++rep)
            for (const Case& c : cases) sink += reflectanceFast(c.s, c.l, c.v, shininess, samples).diffuse;
        const double time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / (50.0 * cases.size());
        for (std::size_t i = 0; i < cases.size(); ++i) {
            const auto f = reflectanceFast(cases[i].s, cases[i].l, cases[i].v, shininess, samples);
            dErr += std::abs(f.diffuse - reference[i].diffuse);
            sErr += std::abs(f.specular - reference[i].specular);
            dMax = std::max(dMax, std::abs(f.diffuse - reference[i].diffuse));
        }
        std::printf("%8d %12.3f %14.4f %14.4f %14.4f%s\n", samples, time * 1e6, dErr / cases.size() / meanDiffuse,
                    sErr / cases.size() / meanSpecular, dMax, sink < 0 ? "!" : "");
    }
    return 0;
}
