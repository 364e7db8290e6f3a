// How often what a camera sees of a texel is lit, through its source mesh and through its levels
// (octree::measureLitFractions, as the renderer measures it at load; docs/render.md, "Shadows at
// the level that lights what is seen" and the hybrid's "Moved coarser where a finer level lights
// too little"): the faithful levels by chords, the levels' fitted factors, then the lit fraction's
// error per camera level (rows) and shadow level (columns), with the renderer's seeds and chord
// counts, so the figures are those behind a render's `shadow_levels` and `mesh_levels`.
//   usage: vtex_lit_fractions TEXEL.vto SOURCE_MESH [TAU]
#include <vtex/ingest/ingest.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/render/renderer.h>
#include <vtex/render/source_visibility.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s TEXEL.vto SOURCE_MESH [TAU]\n", argv[0]);
        return 2;
    }
    try {
        using namespace vtex;
        const double tau = argc > 3 ? std::atof(argv[3]) : 1.0;
        const auto tree = octree::openVto(argv[1]);
        tree->loadLevels(30);
        const ingest::TriangleMesh mesh = ingest::loadMesh(argv[2]);
        const render::SourceVisibility source(mesh, tree->info.source);
        const octree::ChordVisibility visible = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return source.visible(a, b); };
        const octree::ChordFirstHit hit = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return source.firstHit(a, b); };
        const auto chords = octree::measureChordTransmittance(*tree, visible, tau, render::kLoadChords, 1);
        const render::FaithfulLevels faithful = render::faithfulLevels(chords, render::RenderOptions{}.hybridTolerance);
        std::printf("faithful levels %d-%d (chord errors:", faithful.coarsest, faithful.finest);
        for (const auto& c : chords) std::printf(" %+.3f", c.error());
        std::printf(")\nfitted factors:");
        std::vector<double> scales;
        for (const auto& fit : octree::fitShellChords(*tree, visible, tau, render::kLevelFitChords, 1)) {
            scales.push_back(fit.scale);
            std::printf(" %.3f", fit.scale);
        }
        const std::size_t finest = std::size_t(std::max(faithful.finest, faithful.coarsest)) + 1;
        const octree::LitFractions lit =
            octree::measureLitFractions(*tree, hit, visible, tau, scales, finest, render::kLoadChords, 1);
        std::printf("\nmesh lit fraction %.4f (standard error %.4f, %zu chords see the mesh)\n", lit.mesh,
                    lit.meshStandardError(), lit.seen);
        std::printf("lit fraction error, volume − mesh: rows camera level, columns shadow level\n       ");
        for (std::size_t l = 0; l < lit.volume.front().size(); ++l) std::printf(" %7zu", l);
        for (std::size_t c = 0; c < lit.volume.size(); ++c) {
            std::printf("\n  %3zu: ", c);
            for (std::size_t l = 0; l < lit.volume[c].size(); ++l)
                std::isnan(lit.volume[c][l]) ? std::printf("       -") : std::printf(" %+7.3f", lit.error(c, l));
        }
        std::printf("\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 3;
    }
}
