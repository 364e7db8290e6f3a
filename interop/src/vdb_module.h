#pragma once
// The boundary between `vtex` and vtex_vdb.so, the module that holds every use of OpenVDB.
//
// Why a module: libopenvdb.so is 57 MB, and merely loading it (its relocations) adds ~29 MiB of
// resident memory to a process — measured: `vtex --version` 10.7 MiB without it, 39.5 MiB with it
// linked — which every vtex command would pay and which broke the memory estimates' test. So
// `vtex export` loads it with dlopen when it writes a .vdb, and no other command ever maps it.
//
// The module and the program come from one build (same compiler, same headers): C++ types cross
// the boundary by reference; exceptions do not (each side has its own copy of vtex::core), so the
// entry point catches everything and hands back the kind and the message.

#include <vtex/interop/vdb.h>

#include <string>
#include <vector>

namespace vtex::interop::detail {

struct VdbModuleResult {
    enum Kind { Done = 0, Io = 1, Input = 2, Other = 3 };
    int kind = Done;
    std::string message;   ///< what(): for Io, "<file>: <problem>"
    std::string file;      ///< Input, Io: the file named
    std::string problem;   ///< Input: the problem; Io: the message without the file
    std::string location;  ///< Input: the location
    std::vector<VdbLevelSummary> summary;
};

using VdbModuleEntry = void (*)(const octree::Octree&, const VdbExportOptions&, const std::filesystem::path&,
                                VdbModuleResult&);
using VdbModuleStamp = const char* (*)();

inline constexpr const char* kVdbModuleFile = "vtex_vdb.so";
inline constexpr const char* kVdbModuleEntryName = "vtexInteropWriteVdb";
inline constexpr const char* kVdbModuleStampName = "vtexInteropVdbStamp";

/// What the program and the module must agree on before a reference crosses: the version and
/// the layout of the types passed.
inline std::string vdbModuleStamp() {
    return std::string("vtex-vdb 1 ") + std::to_string(sizeof(octree::Octree)) + " " +
           std::to_string(sizeof(octree::OctreeNode)) + " " + std::to_string(sizeof(VdbExportOptions)) + " " +
           std::to_string(sizeof(VdbModuleResult)) + " " + std::to_string(sizeof(std::filesystem::path));
}

}  // namespace vtex::interop::detail
