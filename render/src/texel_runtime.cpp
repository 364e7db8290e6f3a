// See texel_runtime.h.
#include "texel_runtime.h"

#include <vtex/core/error.h>
#include <vtex/octree/chord_transmittance.h>

#include "footprint.h"

#include <cmath>

namespace vtex::render::detail {
namespace {

// The range of levels at which the volume lets through what the source mesh does, within
// `tolerance` (absolute transmittance, mean over random chords of the whole texel): from the
// coarsest level finer, the first level within the tolerance and the finer ones as long as each
// stays within it. Coarser than that, a voxel spreads clustered leaves over its whole volume and
// is too opaque; finer, a voxel stands for a piece of one opaque surface that the exponential
// medium lets light through (and shadows itself). The measurement stops at the first level past
// the run, so that a render does not read a lazily opened texel's finest levels (the bulk of its
// file) only to measure them. When no level is within the tolerance, the level of least error
// alone.
struct FaithfulLevels {
    int coarsest = 0, finest = 0;
};
FaithfulLevels faithfulLevels(const octree::Octree& tree, const octree::ChordVisibility& visible, double tau,
                              double tolerance) {
    int coarsest = -1;
    const auto chords = octree::measureChordTransmittance(
        tree, visible, tau, 4096, 1, [&](std::size_t level, const octree::ChordTransmittance& c) {
            const bool within = std::abs(c.error()) <= tolerance;
            if (within && coarsest < 0) coarsest = int(level);
            return coarsest >= 0 && !within;
        });
    if (coarsest >= 0) {
        int finest = coarsest;
        while (std::size_t(finest + 1) < chords.size() && std::abs(chords[std::size_t(finest + 1)].error()) <= tolerance) ++finest;
        return {coarsest, finest};
    }
    std::size_t best = 0;
    for (std::size_t l = 1; l < chords.size(); ++l)
        if (std::abs(chords[l].error()) < std::abs(chords[best].error())) best = l;
    return {int(best), int(best)};
}

}  // namespace

std::vector<TexelRuntime> loadTexels(const Scene& scene, const RenderOptions& options) {
    std::vector<TexelRuntime> texels(scene.texels.size());
    for (const std::size_t index : usedTexels(scene)) {
        TexelRuntime& t = texels.at(index);
        if (t.volume) continue;
        const TexelDef& def = scene.texels[index];
        auto tree = loadTexelVolume(scene, index);
        tree->loadLevels(0);
        if (tree->levels.empty() || tree->levels[0].empty())
            throw InputError(def.volume, "octree has no root");
        t.tau = def.tau;
        t.material = def.material;
        // With a source, the levels the volume is faithful at are measured (one pass of chords):
        // shadows keep to them, and the hybrid traces the mesh past the finest of them.
        if (def.sourceData || !def.source.empty()) {
            t.sourceMesh = loadTexelSource(scene, index);
            auto source = std::make_unique<const SourceBvh>(*t.sourceMesh, tree->info.source);
            const octree::ChordVisibility visible = [&](const Vec3& a, const Vec3& b) { return !source->occluded(a, b, 0); };
            const FaithfulLevels faithful = faithfulLevels(*tree, visible, def.tau, options.hybridTolerance);
            t.coarsestShadowLevel = faithful.coarsest;
            // Measured before the fit, the faithful levels keep saying where the volume's
            // chords differ from the mesh's per chord, which a scale per level does not change.
            // 16 384 chords: a mean of them has a standard error ≤ 0.5/√16384 = 0.004; on a texel
            // of clustered discs a fit then lets through what the mesh does within 0.003 on other
            // chords (ShellChords.AFittedLevelLetsThroughWhatTheMeshDoesOnOtherChords).
            // With the hybrid on, a level finer than the mesh level's next is never marched.
            constexpr int kShellChords = 16384;
            const std::uint32_t finest = options.hybrid ? std::uint32_t(faithful.finest + 1) : 30u;
            if (options.fitLevels)
                for (const octree::ShellChordFit& fit : octree::fitShellChords(*tree, visible, def.tau, kShellChords, 1, finest))
                    t.levelScale.push_back(fit.scale);
            if (options.hybrid) {
                t.meshLevel = faithful.finest;
                t.source = std::move(source);
            } else {
                t.sourceMesh.reset();
            }
        }
        t.volume = std::make_unique<const MarchVolume>(std::move(tree));
    }
    return texels;
}

}  // namespace vtex::render::detail
