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

CheckedFile readCheckedFile(const std::filesystem::path& file, std::string_view magic, std::uint32_t version, bool json,
                            std::ostream& out) {
    CheckedFile f{octree::readFileBytes(file), {}};
    f.check = octree::checkFile(f.bytes, magic, version);
    if (!f.check.problem.empty()) {
        if (json) out << nlohmann::json{{"file", file.string()}, {"checksums", checksumsJson(f.check)}}.dump() << '\n';
        else printChecksums(f.check, out);
    }
    return f;
}

void printChecksums(const octree::FileCheck& check, std::ostream& out) {
    out << "checksums:";
    for (const auto& s : check.sections) out << "  " << s.tag << " (" << s.size << " B) " << (s.checksumOk ? "ok" : "MISMATCH");
    out << (check.problem.empty() ? "" : "  -- " + check.problem) << '\n';
}

}  // namespace vtex::cli
