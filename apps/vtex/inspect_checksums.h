#pragma once
// What `vtex inspect` says about the container of a .vtl or .vto file: the checksum of each
// section, shared by both inspectors.

#include <vtex/octree/volume.h>

#include <nlohmann/json.hpp>

#include <ostream>

namespace vtex::cli {

/// {"valid", "version", "problem", "sections": [{"tag", "bytes", "checksum"}]}.
nlohmann::json checksumsJson(const octree::FileCheck& check);
/// One line: "checksums:  HEAD (64 B) ok  LV00 (44 B) MISMATCH  -- <problem>".
void printChecksums(const octree::FileCheck& check, std::ostream& out);

}  // namespace vtex::cli
