// Debian's libxxhash, compiled inline into this translation unit (as octree/src/container.cpp
// does), so nothing extra is linked or exported.
#define XXH_INLINE_ALL
#include <xxhash.h>

#include "content_hash.h"

#include <vtex/core/error.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <vector>

namespace vtex::pipelines {
namespace {

std::string hex(const XXH128_hash_t& h) {
    char text[33];
    std::snprintf(text, sizeof text, "%016llx%016llx", (unsigned long long)h.high64, (unsigned long long)h.low64);
    return text;
}

}  // namespace

std::string hashBytes(std::string_view bytes) { return hex(XXH3_128bits(bytes.data(), bytes.size())); }

std::string hashFile(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file, "cannot read (missing file?)");
    std::unique_ptr<XXH3_state_t, decltype(&XXH3_freeState)> state(XXH3_createState(), &XXH3_freeState);
    XXH3_128bits_reset(state.get());
    std::vector<char> buffer(1 << 20);
    while (in) {
        in.read(buffer.data(), std::streamsize(buffer.size()));
        XXH3_128bits_update(state.get(), buffer.data(), std::size_t(in.gcount()));
    }
    if (in.bad()) throw InputError(file, "read error");
    return hex(XXH3_128bits_digest(state.get()));
}

}  // namespace vtex::pipelines
