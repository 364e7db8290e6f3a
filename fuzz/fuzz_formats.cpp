// libFuzzer target for vtex's own inputs: .vtl and .vto files and scene.toml. The first byte
// picks the reader and whether the container's checksums are resealed first. Resealing lets
// mutations reach the content checks behind the XXH3 guards (an unsealed mutation almost
// always stops at "checksum mismatch"); the unsealed modes test the guards themselves. An
// accepted file must serialise to bytes that parse to the same thing.
#include "container.h"

#include <vtex/core/error.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/render/scene.h>

#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

namespace {

using namespace vtex::octree;

void storeU64(std::string& bytes, std::size_t at, std::uint64_t v) {
    detail::ByteWriter w;
    w.u64(v);
    bytes.replace(at, 8, w.str());
}

// Rewrites the payload checksums of the sections that lie inside the file, then the table's
// guard (docs/formats.md, "Container").
void reseal(std::string& bytes) {
    if (bytes.size() < detail::kHeaderSize) return;
    detail::ByteReader header(std::string_view(bytes).substr(12));
    const std::uint32_t count = header.u32();
    if (count > detail::kMaxSections) return;
    const std::size_t tableEnd = detail::kHeaderSize + detail::kTableEntrySize * count;
    if (tableEnd > bytes.size()) return;
    for (std::size_t s = 0; s < count; ++s) {
        const std::size_t entry = detail::kHeaderSize + detail::kTableEntrySize * s;
        detail::ByteReader place(std::string_view(bytes).substr(entry + 8));
        const std::uint64_t offset = place.u64(), size = place.u64();
        if (offset <= bytes.size() && size <= bytes.size() - offset)
            storeU64(bytes, entry + 24, detail::checksum(std::string_view(bytes).substr(offset, size)));
    }
    storeU64(bytes, 16, detail::tableChecksum(bytes, tableEnd));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
    const int mode = data[0] % 5;
    if (mode == 0 || mode == 2) reseal(bytes);
    try {
        switch (mode) {
            case 0:
            case 1: {
                const SparseVolume volume = parseVtl(bytes, "fuzz.vtl");
                if (!(parseVtl(serializeVtl(volume), "again.vtl") == volume)) std::abort();
                break;
            }
            case 2:
            case 3: {
                const std::string canonical = serializeVto(parseVto(bytes, "fuzz.vto"));
                if (serializeVto(parseVto(canonical, "again.vto")) != canonical) std::abort();
                break;
            }
            default: vtex::render::parseScene(bytes, "fuzz/scene.toml"); break;
        }
    } catch (const vtex::InputError&) {
        // Refused cleanly: the expected outcome for most inputs.
    }
    return 0;
}
