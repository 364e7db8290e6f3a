// See source_visibility.h.
#include <vtex/render/source_visibility.h>

#include <vtex/octree/density_profile.h>
#include <vtex/render/renderer.h>

#include "source_bvh.h"

#include <cmath>

namespace vtex::render {

SourceVisibility::SourceVisibility(const ingest::TriangleMesh& mesh, const octree::VolumeInfo& volume)
    : mBvh(std::make_unique<detail::SourceBvh>(mesh, volume)) {}

SourceVisibility::~SourceVisibility() = default;

bool SourceVisibility::visible(const Vec3& a, const Vec3& b) const { return !mBvh->occluded(a, b, 0); }

std::optional<double> SourceVisibility::firstHit(const Vec3& a, const Vec3& b) const {
    if (const auto hit = mBvh->intersect(a, b, 0)) return hit->s;
    return std::nullopt;
}

FaithfulLevels faithfulLevels(const std::vector<octree::ChordTransmittance>& chords, double tolerance) {
    int coarsest = -1;
    for (std::size_t l = 0; l < chords.size() && coarsest < 0; ++l)
        if (std::abs(chords[l].error()) <= tolerance) coarsest = int(l);
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

SourceFidelity measureSourceFidelity(const octree::Octree& tree, const ingest::TriangleMesh& source) {
    const SourceVisibility visibility(source, tree.info.source);
    const auto visible = [&](const Vec3& a, const Vec3& b) { return visibility.visible(a, b); };
    SourceFidelity out{octree::measureChordTransmittance(tree, visible), octree::measureBeamTransmittance(tree, visible), {}, {}, 0};
    const octree::DensityProfile profile(tree);
    while (profile.profiles(out.profiledLevels)) ++out.profiledLevels;
    const FaithfulLevels faithful = marchedLevels(faithfulLevels(out.chords, RenderOptions{}.hybridTolerance));
    for (const octree::ShellChordFit& fit :
         octree::fitShellChords(tree, visible, 1, kLevelFitChords, 1, std::uint32_t(faithful.finest)))
        out.fitScale.push_back(fit.scale);
    out.fitted = octree::measureChordTransmittance(tree, visible, out.fitScale);
    return out;
}

}  // namespace vtex::render
