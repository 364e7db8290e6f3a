// How the floor under a texel is seen and lit at once, through its source mesh and through its
// levels: the camera's and the light's paths to a floor point cross the same leaves, and a volume
// of one density per voxel takes them as independent below the voxel's size (docs/error-vs-time.md,
// "A lit voxel's own leaf" and "Light-specific calibration of the levels": the bush field's far
// view sees its ground lit 11 % too often). For uniform points of the floor of the texel tiled in
// x and y, with the view direction V (floor to eye) and the light direction L (floor to light):
// the mesh's P(seen), P(lit), P(seen and lit); per camera level c the volume's E[t_c], and with
// the shadow level's t_l (the levels' factors as a render's load fits them, render::measureSource:
// the levels it marches) E[t_c t_l] and the
// correlation coefficient r_c that would make E[t_c t_l + r √(t_c(1−t_c) t_l(1−t_l))] the mesh's
// P(seen and lit).
//   usage: vtex_floor_correlation TEXEL.vto SOURCE_MESH VX VY VZ LX LY LZ [SHADOW_LEVEL] [POINTS]
#include <vtex/ingest/ingest.h>
#include <vtex/octree/chord_medium.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/render/renderer.h>
#include <vtex/render/source_visibility.h>

#include "../octree/src/chord_sampling.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

int main(int argc, char** argv) {
    if (argc < 9) {
        std::fprintf(stderr, "usage: %s TEXEL.vto SOURCE_MESH VX VY VZ LX LY LZ [SHADOW_LEVEL] [POINTS]\n", argv[0]);
        return 2;
    }
    try {
        using namespace vtex;
        using Vec3 = Eigen::Vector3d;
        const Vec3 view = Vec3(std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5])).normalized();
        const Vec3 light = Vec3(std::atof(argv[6]), std::atof(argv[7]), std::atof(argv[8])).normalized();
        const int shadowLevel = argc > 9 ? std::atoi(argv[9]) : 4;
        const int points = argc > 10 ? std::atoi(argv[10]) : 16384;
        if (!(view.z() > 0) || !(light.z() > 0) || points <= 0) {
            std::fprintf(stderr, "the directions must point up, the points be positive\n");
            return 2;
        }
        const auto tree = octree::openVto(argv[1]);
        tree->loadLevels(30);
        const ingest::TriangleMesh mesh = ingest::loadMesh(argv[2]);
        const render::SourceVisibility source(mesh, tree->info.source);
        const octree::ChordVisibility visible = [&](const Vec3& a, const Vec3& b) { return source.visible(a, b); };
        const std::vector<double> scales =
            render::measureSource(*tree, mesh, 1.0, render::RenderOptions{}.hybridTolerance).levelScales;
        const octree::ChordMedium medium(*tree);
        const int levels = int(scales.size());
        if (shadowLevel < 0 || shadowLevel >= int(scales.size())) {
            std::fprintf(stderr, "no fitted level %d\n", shadowLevel);
            return 2;
        }
        const auto up = [](const Vec3& p, const Vec3& d) { return octree::detail::tiledSegments(p, d / d.z()); };
        const auto seen = [&](const octree::detail::Segments& s) {
            for (const auto& [a, b] : s)
                if (!visible(a, b)) return false;
            return true;
        };
        double meshC = 0, meshL = 0, meshBoth = 0;
        std::vector<double> tc(std::size_t(levels), 0), both(std::size_t(levels), 0), spread(std::size_t(levels), 0);
        double tlSum = 0;
        octree::detail::ChordRng rng{0x5eedull};
        for (int i = 0; i < points; ++i) {
            const Vec3 p(rng.next(), rng.next(), 1e-6);
            const auto camera = up(p, view), sun = up(p, light);
            const bool c = seen(camera), l = seen(sun);
            meshC += c;
            meshL += l;
            meshBoth += c && l;
            const double tl = std::exp(-scales[std::size_t(shadowLevel)] * octree::detail::chordDepth(medium, std::uint32_t(shadowLevel), sun));
            tlSum += tl;
            for (int level = 0; level < levels; ++level) {
                const double t = std::exp(-scales[std::size_t(level)] * octree::detail::chordDepth(medium, std::uint32_t(level), camera));
                tc[std::size_t(level)] += t;
                both[std::size_t(level)] += t * tl;
                spread[std::size_t(level)] += std::sqrt(t * (1 - t) * tl * (1 - tl));
            }
        }
        const double n = points;
        std::printf("mesh: seen %.4f, lit %.4f, seen and lit %.4f (independent: %.4f)\n", meshC / n, meshL / n,
                    meshBoth / n, meshC * meshL / (n * n));
        std::printf("volume, shadow level %d: lit %.4f\n", shadowLevel, tlSum / n);
        std::printf("camera level  seen    seen and lit  spread   r\n");
        for (int level = 0; level < levels; ++level) {
            const std::size_t k = std::size_t(level);
            std::printf("%12d  %.4f  %.4f        %.4f   %+.4f\n", level, tc[k] / n, both[k] / n, spread[k] / n,
                        spread[k] > 0 ? (meshBoth - both[k]) / spread[k] : 0.0);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 3;
    }
}
