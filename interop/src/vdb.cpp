// writeVdb (vdb.h): checks the request and hands it to vtex_vdb.so, loaded on first use
// (vdb_module.h: why OpenVDB lives in a module). No OpenVDB header here.
#include "vdb_module.h"

#include <vtex/core/error.h>

#include <dlfcn.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace vtex::interop {

namespace {

#if VTEX_HAVE_OPENVDB
// Beside the program in the build tree, in <libdir>/vtex once installed (VTEX_VDB_MODULE_RELATIVE,
// the path from the installed program's folder to it).
std::vector<std::filesystem::path> moduleCandidates() {
    std::error_code error;
    const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
    if (error) return {};
    const std::filesystem::path folder = program.parent_path();
    return {folder / detail::kVdbModuleFile, folder / VTEX_VDB_MODULE_RELATIVE / detail::kVdbModuleFile};
}

// The module's entry point, loaded once and kept (never dlclose'd: OpenVDB keeps registries in
// static storage). Throws std::runtime_error naming what was tried.
detail::VdbModuleEntry loadModule() {
    static std::once_flag once;
    static detail::VdbModuleEntry entry = nullptr;
    static std::string failure;
    std::call_once(once, [] {
        // Appends, not `" " + std::string`: GCC 12 warns falsely (-Wrestrict) on that.
        std::string tried;
        auto note = [&tried](const std::filesystem::path& candidate, const std::string& why) {
            tried += ' ';
            tried += candidate.string();
            tried += " (";
            tried += why;
            tried += ')';
        };
        for (const std::filesystem::path& candidate : moduleCandidates()) {
            std::error_code error;
            if (!std::filesystem::is_regular_file(candidate, error)) {
                note(candidate, "missing");
                continue;
            }
            void* handle = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (!handle) {
                note(candidate, ::dlerror());
                continue;
            }
            const auto stamp = reinterpret_cast<detail::VdbModuleStamp>(::dlsym(handle, detail::kVdbModuleStampName));
            if (!stamp || stamp() != detail::vdbModuleStamp()) {
                note(candidate, "from another build of vtex");
                continue;
            }
            entry = reinterpret_cast<detail::VdbModuleEntry>(::dlsym(handle, detail::kVdbModuleEntryName));
            if (entry) return;
            note(candidate, "no entry point");
        }
        failure = "cannot load vtex's OpenVDB writer; tried" + tried;
    });
    if (!entry) throw std::runtime_error(failure);
    return entry;
}
#endif

}  // namespace

std::vector<VdbLevelSummary> writeVdb(const octree::Octree& octree, const VdbExportOptions& options,
                                      const std::filesystem::path& file) {
    VdbExportOptions request = options;
    if (request.levels.empty()) request.levels.push_back(octree.levelCount() - 1);
    for (std::uint32_t level : request.levels)
        if (level >= octree.levelCount())
            throw std::out_of_range("level " + std::to_string(level) + " (the octree has levels 0 to " +
                                    std::to_string(int(octree.levelCount()) - 1) + ")");
#if VTEX_HAVE_OPENVDB
    const detail::VdbModuleEntry write = loadModule();
    detail::VdbModuleResult result;
    write(octree, request, file, result);
    using Result = detail::VdbModuleResult;
    switch (result.kind) {
    case Result::Done: return std::move(result.summary);
    case Result::Input: throw InputError(result.file, result.problem, result.location);
    case Result::Io: throw IoError(result.file, result.problem);
    default: throw std::runtime_error(result.message);
    }
#else
    throw std::runtime_error(file.string() + ": vtex was built without OpenVDB (install libopenvdb-dev and "
                             "libboost-iostreams-dev, then reconfigure): no .vdb output");
#endif
}

}  // namespace vtex::interop
