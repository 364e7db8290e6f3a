// How `vtex inspect --source` and `vtex build --source` show each level's fidelity to the
// texel's source mesh (render::measureSourceFidelity, issue 13's measure).
#pragma once

#include <vtex/render/source_visibility.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <ostream>

namespace vtex::cli {

/// Level `l`'s chord and beam figures; null when nothing was measured (no source).
nlohmann::json fidelityJson(const render::SourceFidelity& m, std::uint32_t l);
/// The per-level table, after a line naming the source; nothing when nothing was measured.
void printFidelity(const render::SourceFidelity& m, const std::filesystem::path& source, std::ostream& out);

}  // namespace vtex::cli
