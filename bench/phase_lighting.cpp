// How a texel's leaves are lit against the angle between the view and the light, through its
// source mesh and through its levels (docs/error-vs-time.md, "The bias under other lights": the
// bush field's lit leaves go from a few percent too dark to a few percent too bright as the phase
// angle grows). For shell chords (cosine-weighted views through the tiled texel, as the level fit
// draws them) and, per phase angle α, a light at α from the view (its azimuth about the view drawn
// uniformly, above the horizon): the mesh's Lambert radiance at the first surface the chord meets
// (albedo 1, lit when its ray to the top meets nothing, the face turned to the camera), and the
// volume's at camera level c, Σ T·α·t_l·R_d front to back, R_d the fast kernel's diffuse factor of
// each voxel's ellipsoid and t_l its shadow at the shadow level with the voxel's own share taken
// off, as the renderer lights it. Prints, per α and camera level, the two means' ratio.
// With VIEW_ZENITH (degrees) every chord looks down at that angle instead of cosine-weighted, its
// azimuth uniform (VIEW_AZIMUTH "random"), or within ±7° of VIEW_AZIMUTH (the direction from the
// texel to the eye, as a camera over a field sees it); with a LIGHT too (its direction of travel, as in scene.toml), one
// row for that light instead of the phase angles.
//   usage: vtex_phase_lighting TEXEL.vto SOURCE_MESH [SHADOW_LEVEL] [CHORDS]
//                              [VIEW_ZENITH [VIEW_AZIMUTH [LX LY LZ]]]
#include <vtex/ingest/ingest.h>
#include <vtex/octree/chord_medium.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/primitive/reflectance_kernel.h>
#include <vtex/render/renderer.h>
#include <vtex/render/source_visibility.h>
#include <vtex/render/texel_march.h>

#include "../octree/src/chord_sampling.h"
#include "../render/src/source_bvh.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace {

using Vec3 = Eigen::Vector3d;
using vtex::octree::detail::Segments;

// A unit vector at angle `alpha` from v, at azimuth phi about it.
Vec3 around(const Vec3& v, double alpha, double phi) {
    const Vec3 a = std::abs(v.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX();
    const Vec3 e1 = v.cross(a).normalized(), e2 = v.cross(e1);
    return (std::cos(alpha) * v + std::sin(alpha) * (std::cos(phi) * e1 + std::sin(phi) * e2)).normalized();
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s TEXEL.vto SOURCE_MESH [SHADOW_LEVEL] [CHORDS] [VIEW_ZENITH [VIEW_AZIMUTH [LX LY LZ]]]\n", argv[0]);
        return 2;
    }
    try {
        using namespace vtex;
        const int shadowLevel = argc > 3 ? std::atoi(argv[3]) : 4;
        const int chords = argc > 4 ? std::atoi(argv[4]) : 8192;
        constexpr double kDegree = std::numbers::pi / 180;
        const double zenith = argc > 5 ? std::atof(argv[5]) * kDegree : -1;
        // "random" (or none): the chords' azimuths uniform.
        const double azimuth = argc > 6 && std::string(argv[6]) != "random" ? std::atof(argv[6]) * kDegree
                                                                            : std::numeric_limits<double>::quiet_NaN();
        std::optional<Vec3> fixedLight;  // toward the light
        if (argc > 9) fixedLight = -Vec3(std::atof(argv[7]), std::atof(argv[8]), std::atof(argv[9])).normalized();
        if ((argc > 5 && !(zenith >= 0 && zenith < std::numbers::pi / 2)) || (fixedLight && !(fixedLight->z() > 0))) {
            std::fprintf(stderr, "the view's zenith must lie in [0, 90) degrees, the light come from above\n");
            return 2;
        }
        const auto tree = octree::openVto(argv[1]);
        tree->loadLevels(30);
        const ingest::TriangleMesh mesh = ingest::loadMesh(argv[2]);
        const render::detail::SourceBvh bvh(mesh, tree->info.source);
        const octree::SourceMeasures measures =
            render::measureSource(*tree, mesh, 1.0, render::RenderOptions{}.hybridTolerance);
        const std::vector<double>& scales = measures.levelScales;
        const octree::ChordMedium medium(*tree);
        const std::vector<double> phases =
            fixedLight ? std::vector<double>{0} : std::vector<double>{30, 45, 57, 68, 78, 87, 100, 115, 130};
        const int cameraLevels[] = {3, 4, 5};
        const double own = std::size_t(shadowLevel) < measures.ownShares.size() ? measures.ownShares[std::size_t(shadowLevel)] : 0;
        // Sums per phase: the mesh's radiance, and per camera level the volume's.
        std::vector<double> meshSum(phases.size(), 0.0), litSum(phases.size(), 0.0);
        std::vector<std::vector<double>> volumeSum(3, std::vector<double>(phases.size(), 0.0));
        std::vector<double> count(phases.size(), 0.0);
        for (int j = 0; j < chords; ++j) {
            octree::detail::ChordRng rng{octree::detail::mix64(0x5eedull ^ octree::detail::mix64(std::uint64_t(j)))};
            Segments chord;
            if (zenith >= 0) {
                // The chord runs away from the eye: its azimuth is the view's plus a half turn.
                const double phi = std::isnan(azimuth) ? 2 * std::numbers::pi * rng.next()
                                                       : azimuth + std::numbers::pi + 14 * kDegree * (rng.next() - 0.5);
                const Vec3 a(rng.next(), rng.next(), 1.0);
                const Vec3 down(std::sin(zenith) * std::cos(phi), std::sin(zenith) * std::sin(phi), -std::cos(zenith));
                chord = octree::detail::tiledSegments(a, down / std::cos(zenith));
            } else {
                chord = octree::detail::randomShellChord(rng);
            }
            const Vec3 dir = (chord.front().second - chord.front().first).normalized();
            const Vec3 view = -dir;
            // The mesh's first surface along the chord.
            std::optional<render::detail::SourceHit> hit;
            Vec3 hitPoint = Vec3::Zero();
            for (const auto& [a, b] : chord)
                if ((hit = bvh.intersect(a, b, 0.0))) {
                    hitPoint = a + hit->s * (b - a);
                    break;
                }
            for (std::size_t k = 0; k < phases.size(); ++k) {
                const double alpha = phases[k] * std::numbers::pi / 180;
                Vec3 light = fixedLight.value_or(Vec3::UnitZ());
                for (int tries = 0; !fixedLight && (tries == 0 || (light.z() < 0.1 && tries < 64)); ++tries)
                    light = around(view, alpha, 2 * std::numbers::pi * rng.next());
                if (!fixedLight && light.z() < 0.1) continue;  // a drawn light this low: another chord
                count[k] += 1;
                if (hit) {
                    Vec3 n = hit->normal;
                    if (n.dot(view) < 0) n = -n;
                    const double cosine = std::max(0.0, n.dot(light));
                    bool lit = cosine > 0;
                    if (lit) {
                        const Vec3 start = hitPoint + render::detail::kSelfIntersectionGap * light;
                        for (const auto& [c, d] : octree::detail::toTheTop(start, light))
                            if (bvh.occluded(c, d, 0.0)) {
                                lit = false;
                                break;
                            }
                    }
                    meshSum[k] += lit ? cosine / std::numbers::pi : 0.0;
                    litSum[k] += lit;
                }
                const primitive::ReflectanceKernel kernel(light, view, 20, 16, false);
                for (int ci = 0; ci < 3; ++ci) {
                    const int c = cameraLevels[ci];
                    double transmittance = 1, radiance = 0;
                    for (const auto& [a, b] : chord) {
                        const Vec3 w = (b - a).normalized();
                        octree::DensityProfile::Line line(medium.profile(), c, a, w);
                        octree::forEachVoxelOnSegment(*tree, std::uint32_t(c), a, b,
                                                      [&](const octree::OctreeNode& node, double t0, double t1) {
                            const render::GridVoxel v = render::gridVoxel(node.data);
                            const double sigma = scales[std::size_t(c)] * v.extinction(1.0, w) * line.mean(t0, t1);
                            const double opacity = 1 - std::exp(-sigma * (t1 - t0));
                            if (!(opacity > 0) || transmittance < 1e-4) return;
                            const Vec3 p = a + 0.5 * (t0 + t1) * w;
                            const double shadow = std::exp(-scales[std::size_t(shadowLevel)] *
                                                           octree::detail::shadowDepth(medium, std::uint32_t(shadowLevel), p, light, own));
                            radiance += transmittance * opacity * shadow * kernel(v.s).diffuse;
                            transmittance *= 1 - opacity;
                        });
                    }
                    volumeSum[std::size_t(ci)][k] += radiance;
                }
            }
        }
        std::printf("shadow level %d (own share %.3f), %d chords; mean radiance (albedo 1, irradiance 1)\n",
                    shadowLevel, own, chords);
        std::printf("%s   mesh     lit     volume/mesh − 1 at camera level 3, 4, 5\n", fixedLight ? "light" : "phase");
        for (std::size_t k = 0; k < phases.size(); ++k) {
            const double m = meshSum[k] / count[k];
            fixedLight ? std::printf("given") : std::printf("%5.0f", phases[k]);
            std::printf("  %.5f  %.3f", m, litSum[k] / count[k]);
            for (int ci = 0; ci < 3; ++ci) std::printf("  %+7.3f", volumeSum[std::size_t(ci)][k] / count[k] / m - 1);
            std::printf("\n");
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 3;
    }
}
