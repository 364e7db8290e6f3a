// See texel_runtime.h.
#include "texel_runtime.h"

#include <vtex/core/error.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/render/source_visibility.h>

#include "footprint.h"

#include <cmath>

namespace vtex::render::detail {
namespace {

// The faithful levels (render::faithfulLevels), measured from the coarsest level finer and
// stopping at the first level past the run, so that a render does not read a lazily opened
// texel's finest levels (the bulk of its file) only to measure them.
FaithfulLevels measureFaithfulLevels(const octree::Octree& tree, const octree::ChordVisibility& visible, double tau,
                                     double tolerance) {
    int coarsest = -1;
    const auto chords = octree::measureChordTransmittance(
        tree, visible, tau, 4096, 1, [&](std::size_t level, const octree::ChordTransmittance& c) {
            const bool within = std::abs(c.error()) <= tolerance;
            if (within && coarsest < 0) coarsest = int(level);
            return coarsest >= 0 && !within;
        });
    return faithfulLevels(chords, tolerance);
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
            const FaithfulLevels faithful = measureFaithfulLevels(*tree, visible, def.tau, options.hybridTolerance);
            t.coarsestShadowLevel = faithful.coarsest;
            // Measured before the fit, the faithful levels keep saying where the volume's
            // chords differ from the mesh's per chord, which a scale per level does not change.
            // kLevelFitChords: on a texel of clustered discs a fit then lets through what the mesh
            // does within 0.003 on other chords (ShellChords.AFittedLevelLetsThroughWhatTheMeshDoesOnOtherChords).
            // With the hybrid on, a level finer than the mesh level's next is never marched.
            const std::uint32_t finest = options.hybrid ? std::uint32_t(faithful.finest + 1) : 30u;
            if (options.fitLevels)
                for (const octree::ShellChordFit& fit : octree::fitShellChords(*tree, visible, def.tau, kLevelFitChords, 1, finest))
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
