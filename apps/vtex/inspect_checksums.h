#pragma once
// What `vtex inspect` says about the container of a .vtl or .vto file: the checksum of each
// section, shared by both inspectors.

#include <vtex/octree/volume.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <ostream>
#include <string>
#include <string_view>

namespace vtex::cli {

/// {"valid", "version", "problem", "sections": [{"tag", "bytes", "checksum"}]}.
nlohmann::json checksumsJson(const octree::FileCheck& check);
/// One line: "checksums:  HEAD (64 B) ok  LV00 (44 B) MISMATCH  -- <problem>".
void printChecksums(const octree::FileCheck& check, std::ostream& out);

/// A .vtl or .vto file's bytes and its container's check (magic, version, checksums).
struct CheckedFile {
    std::string bytes;
    octree::FileCheck check;
};
/// Reads `file` and checks its container; a damaged one is reported at once (its checksums, as
/// one JSON line when `json`, else as text), before the parse that will refuse it names why.
CheckedFile readCheckedFile(const std::filesystem::path& file, std::string_view magic, std::uint32_t version, bool json,
                            std::ostream& out);

}  // namespace vtex::cli
