#include "inspect_checksums.h"

namespace vtex::cli {

nlohmann::json checksumsJson(const octree::FileCheck& check) {
    nlohmann::json sections = nlohmann::json::array();
    for (const auto& s : check.sections)
        sections.push_back({{"tag", s.tag}, {"bytes", s.size}, {"checksum", s.checksumOk ? "ok" : "mismatch"}});
    return {{"valid", check.problem.empty()},
            {"version", check.version},
            {"problem", check.problem.empty() ? nlohmann::json(nullptr) : nlohmann::json(check.problem)},
            {"sections", sections}};
}

void printChecksums(const octree::FileCheck& check, std::ostream& out) {
    out << "checksums:";
    for (const auto& s : check.sections) out << "  " << s.tag << " (" << s.size << " B) " << (s.checksumOk ? "ok" : "MISMATCH");
    out << (check.problem.empty() ? "" : "  -- " + check.problem) << '\n';
}

}  // namespace vtex::cli
