// libFuzzer target for the ingest entry points. The first byte picks the reader (GLB, glTF
// JSON, OBJ, OFF, PLY or STL); the rest is the file. Nothing external can be
// read (no folder is given), textures are capped small, and every mesh that is accepted must
// survive the rest of the pipeline: repair, .glb encoding, and ingesting that .glb again.
#include "detail.h"

#include <vtex/core/error.h>

#include <cstdint>
#include <cstdlib>
#include <string_view>

using namespace vtex::ingest;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    IngestOptions options;
    options.maxTriangles = 200000;
    options.maxFileBytes = 1 << 20;
    options.maxTextureDimension = 1024;
    options.maxTexturePixels = 1 << 18;
    const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
    const std::filesystem::path file = "fuzz-input";
    try {
        detail::RawMesh raw;
        switch (data[0] % 6) {
            case 0: raw = detail::readGltf(bytes, true, file, {}, options); break;
            case 1: raw = detail::readGltf(bytes, false, file, {}, options); break;
            case 2: raw = detail::readObj(bytes, file, {}, options); break;
            case 3: raw = detail::readOffPlyStl(bytes, "off", file, options); break;
            case 4: raw = detail::readOffPlyStl(bytes, "ply", file, options); break;
            default: raw = detail::readOffPlyStl(bytes, "stl", file, options); break;
        }
        IngestReport report;
        const TriangleMesh mesh = detail::repairMesh(std::move(raw), file, options, report);
        // Oracle: the canonical output of an accepted input is itself accepted, unchanged in size.
        const std::string glb = encodeMeshGlb(mesh);
        IngestReport again;
        const TriangleMesh back = detail::repairMesh(detail::readGltf(glb, true, file, {}, options), file, options, again);
        if (back.triangles.size() != mesh.triangles.size()) std::abort();
    } catch (const vtex::InputError&) {
        // Refused cleanly: the expected outcome for most inputs.
    }
    return 0;
}
