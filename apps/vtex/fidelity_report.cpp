#include "fidelity_report.h"
#include "json_number.h"

#include <vtex/octree/density_profile.h>

#include <algorithm>
#include <cstdio>

namespace vtex::cli {

nlohmann::json fidelityJson(const render::SourceFidelity& m, std::uint32_t l) {
    if (m.chords.empty()) return nullptr;
    const auto& c = m.chords[l];
    const auto& b = m.beams[l];
    nlohmann::json fitted = nullptr;
    if (l < m.fitted.size())
        fitted = {{"scale", jsonNumber(m.fitScale[l])}, {"transmittance", jsonNumber(m.fitted[l].transmittance)},
                  {"error", jsonNumber(m.fitted[l].error())}};
    return {{"visibility", jsonNumber(c.visibility)},
            {"transmittance", jsonNumber(c.transmittance)},
            {"error", jsonNumber(c.error())},
            {"fitted", fitted},
            {"density_profile", int(l) < m.profiledLevels},
            {"beams", {{"mean", jsonNumber(b.mean)}, {"mean_abs", jsonNumber(b.meanAbs)}, {"p95_abs", jsonNumber(b.p95Abs)},
                       {"noise", jsonNumber(b.noise)}}}};
}

namespace {

// "level 0" or "levels 0-N": the first n levels.
std::string levelsUpTo(int n) { return n == 1 ? std::string("level 0") : "levels 0-" + std::to_string(n - 1); }

}  // namespace

void printFidelity(const render::SourceFidelity& m, const std::filesystem::path& source, std::ostream& out) {
    if (m.chords.empty()) return;
    out << "against the source " << source.string() << ": 4096 random chords of the texel; 256 beams per level "
        << "(256 parallel chords, 1 voxel across, 4 long)\n"
        << "level  missing the mesh  level's transmittance  error (> 0: lets more through)  beams: mean  |mean|  p95 "
           "(noise)  fitted: scale  error\n";
    char line[256];
    for (std::size_t l = 0; l < m.chords.size(); ++l) {
        const auto& c = m.chords[l];
        const auto& b = m.beams[l];
        std::snprintf(line, sizeof line, "%5zu %17.4f %22.4f %+10.4f %+33.4f %7.4f %7.4f (%.4f)", l, c.visibility,
                      c.transmittance, c.error(), b.mean, b.meanAbs, b.p95Abs, b.noise);
        out << line;
        if (l < m.fitted.size()) {
            std::snprintf(line, sizeof line, " %14.4f %+7.4f", m.fitScale[l], m.fitted[l].error());
            out << line;
        }
        out << '\n';
    }
    if (!m.fitted.empty())
        out << "fitted: each level's densities times the factor the renderer fits (--level-fit on), over "
            << render::kLevelFitChords << " shell chords, then the same random chords\n";
    const int profileLevel = std::min<int>(octree::DensityProfile::kProfileLevel, int(m.chords.size()) - 1);
    if (m.profiledLevels > 0)
        out << levelsUpTo(m.profiledLevels) << ": each voxel's density varies with height, in x and in y as level "
            << profileLevel << "'s layer and column means do (the density profile)\n";
}

}  // namespace vtex::cli
