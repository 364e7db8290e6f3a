// The files a scene names, loaded in one place, so that a bad or missing one is reported with
// the scene file and the key that named it (issue 16): "forest.toml: surface[0].mesh: hill.obj:
// no such file" rather than the inner file alone. See scene.h.
#include <vtex/render/scene.h>

#include <vtex/core/error.h>
#include <vtex/ingest/ingest.h>

#include <string>

namespace vtex::render {
namespace {

// Runs `load`; an InputError it throws is rethrown naming the scene file and `key` first. A
// scene built in memory (no file) passes it on as it is.
template <class Load>
auto namingTheKey(const Scene& scene, const std::string& key, Load&& load) -> decltype(load()) {
    try {
        return load();
    } catch (const InputError& e) {
        if (scene.file.empty()) throw;
        throw InputError(scene.file, e.what(), key);
    }
}

std::string indexedKey(const char* table, std::size_t i, const char* key) {
    return std::string(table) + "[" + std::to_string(i) + "]." + key;
}

}  // namespace

std::shared_ptr<const ingest::QuadMesh> loadSurfaceMesh(const Scene& scene, std::size_t surface) {
    const SurfaceDef& def = scene.surfaces.at(surface);
    if (def.meshData) return def.meshData;
    return namingTheKey(scene, indexedKey("surface", surface, "mesh"),
                        [&] { return std::make_shared<const ingest::QuadMesh>(ingest::loadBaseMesh(def.mesh)); });
}

std::shared_ptr<const octree::Octree> loadTexelVolume(const Scene& scene, std::size_t texel) {
    const TexelDef& def = scene.texels.at(texel);
    if (def.octree) return def.octree;
    return namingTheKey(scene, indexedKey("texel", texel, "volume"),
                        [&] { return octree::openVto(def.volume); });
}

std::shared_ptr<const ingest::TriangleMesh> loadTexelSource(const Scene& scene, std::size_t texel) {
    const TexelDef& def = scene.texels.at(texel);
    if (def.sourceData) return def.sourceData;
    return namingTheKey(scene, indexedKey("texel", texel, "source"),
                        [&] { return std::make_shared<const ingest::TriangleMesh>(ingest::loadMesh(def.source)); });
}

bool texelIsCyclic(const Scene& scene, std::size_t texel) { return loadTexelVolume(scene, texel)->info.source.cyclic; }

std::vector<std::uint32_t> facePlacings(const Scene& scene, std::size_t surface, const ingest::QuadMesh& mesh) {
    const SurfaceDef& def = scene.surfaces.at(surface);
    std::vector<std::uint32_t> placings(mesh.quads.size(), 0);
    if (def.texels.empty()) return placings;
    // Per name of the mesh, the entry it selects (k + 1), 0 for none.
    std::vector<std::uint32_t> byName(mesh.names.size(), 0);
    for (std::size_t n = 0; n < mesh.names.size(); ++n)
        for (std::size_t k = 0; k < def.texels.size(); ++k)
            if (def.texels[k].name == mesh.names[n]) byName[n] = std::uint32_t(k + 1);
    std::vector<char> used(def.texels.size(), 0);
    const auto entryOf = [&](std::uint32_t name) { return name < byName.size() ? byName[name] : 0u; };
    for (std::size_t f = 0; f < placings.size() && f < mesh.faceNames.size(); ++f) {
        // The material's entry first, then the group's.
        std::uint32_t k = entryOf(mesh.faceNames[f][0]);
        if (!k) k = entryOf(mesh.faceNames[f][1]);
        placings[f] = k;
        if (k) used[k - 1] = 1;
    }
    for (std::size_t k = 0; k < def.texels.size(); ++k)
        if (!used[k])
            throw InputError(scene.file.empty() ? def.mesh : scene.file,
                             "no face of " + def.mesh.filename().string() + " has the material or group '" +
                                 def.texels[k].name + "'",
                             indexedKey("surface", surface, "texels.") + def.texels[k].name);
    return placings;
}

}  // namespace vtex::render
