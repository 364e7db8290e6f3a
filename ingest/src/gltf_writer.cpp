// Writes the canonical mesh as a binary glTF 2.0 file with tinygltf (Debian ships it compiled:
// TINYGLTF_IMPLEMENTATION is never defined here).
#include "detail.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>

#include <tiny_gltf.h>

#include <cstring>
#include <limits>
#include <sstream>

namespace vtex::ingest {
namespace {

// Appends `bytes` to the buffer, 4-byte aligned, and returns the index of a new bufferView.
int appendView(tinygltf::Model& model, const void* bytes, std::size_t size, int target) {
    auto& data = model.buffers[0].data;
    while (data.size() % 4) data.push_back(0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = data.size();
    view.byteLength = size;
    view.target = target;
    const auto* begin = static_cast<const unsigned char*>(bytes);
    data.insert(data.end(), begin, begin + size);
    model.bufferViews.push_back(view);
    return int(model.bufferViews.size() - 1);
}

int appendAccessor(tinygltf::Model& model, int view, int componentType, int type,
                   std::size_t count) {
    tinygltf::Accessor accessor;
    accessor.bufferView = view;
    accessor.byteOffset = 0;
    accessor.componentType = componentType;
    accessor.type = type;
    accessor.count = count;
    model.accessors.push_back(accessor);
    return int(model.accessors.size() - 1);
}

void checkMesh(const TriangleMesh& mesh) {
    const std::size_t n = mesh.positions.size();
    if (n > std::numeric_limits<std::uint32_t>::max())
        throw std::invalid_argument("writeMeshGlb: too many vertices for 32-bit indices");
    if (!mesh.normals.empty() && mesh.normals.size() != n)
        throw std::invalid_argument("writeMeshGlb: normals must be empty or one per position");
    if (!mesh.uvs.empty() && mesh.uvs.size() != n)
        throw std::invalid_argument("writeMeshGlb: uvs must be empty or one per position");
    if (!mesh.triangleMaterials.empty() && mesh.triangleMaterials.size() != mesh.triangles.size())
        throw std::invalid_argument("writeMeshGlb: triangleMaterials must be empty or one per triangle");
    for (const auto& t : mesh.triangles)
        for (std::uint32_t v : t)
            if (v >= n) throw std::invalid_argument("writeMeshGlb: triangle index out of range");
    const std::size_t materials = std::max<std::size_t>(1, mesh.materials.size());
    for (std::uint32_t m : mesh.triangleMaterials)
        if (m >= materials) throw std::invalid_argument("writeMeshGlb: material index out of range");
    for (const auto& material : mesh.materials)
        if (material.baseColorTexture >= int(mesh.textures.size()))
            throw std::invalid_argument("writeMeshGlb: texture index out of range");
}

}  // namespace

namespace {

// The vertex attributes every primitive shares (POSITION with its bounds, NORMAL and TEXCOORD_0
// where the mesh has them), as attribute name → accessor.
std::map<std::string, int> appendVertexAttributes(tinygltf::Model& model, const TriangleMesh& mesh) {
    const std::size_t n = mesh.positions.size();
    std::map<std::string, int> attributes;
    if (n == 0) return attributes;
    std::vector<float> floats(n * 3);
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f hi = -lo;
    for (std::size_t i = 0; i < n; ++i) {
        std::memcpy(&floats[3 * i], mesh.positions[i].data(), 3 * sizeof(float));
        lo = lo.cwiseMin(mesh.positions[i]);
        hi = hi.cwiseMax(mesh.positions[i]);
    }
    int view = appendView(model, floats.data(), floats.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    int accessor = appendAccessor(model, view, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
    model.accessors[accessor].minValues = {lo.x(), lo.y(), lo.z()};
    model.accessors[accessor].maxValues = {hi.x(), hi.y(), hi.z()};
    attributes["POSITION"] = accessor;
    if (!mesh.normals.empty()) {
        for (std::size_t i = 0; i < n; ++i) std::memcpy(&floats[3 * i], mesh.normals[i].data(), 3 * sizeof(float));
        view = appendView(model, floats.data(), floats.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
        attributes["NORMAL"] = appendAccessor(model, view, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
    }
    if (!mesh.uvs.empty()) {
        floats.resize(n * 2);
        for (std::size_t i = 0; i < n; ++i) std::memcpy(&floats[2 * i], mesh.uvs[i].data(), 2 * sizeof(float));
        view = appendView(model, floats.data(), floats.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
        attributes["TEXCOORD_0"] = appendAccessor(model, view, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC2, n);
    }
    return attributes;
}

// Textures, embedded as PNG.
void appendTextures(tinygltf::Model& model, const TriangleMesh& mesh) {
    for (const Image& image : mesh.textures) {
        const std::string png = encodePng(image);
        tinygltf::Image gltfImage;
        gltfImage.bufferView = appendView(model, png.data(), png.size(), 0);
        gltfImage.mimeType = "image/png";
        model.images.push_back(gltfImage);
        tinygltf::Texture texture;
        texture.source = int(model.images.size() - 1);
        model.textures.push_back(texture);
    }
}

// Materials: base colour only; two-sided, as the design treats source triangles. A mesh without
// materials gets the default one. Returns how many were written.
std::size_t appendMaterials(tinygltf::Model& model, const TriangleMesh& mesh) {
    std::vector<Material> materials = mesh.materials;
    if (materials.empty()) materials.emplace_back();
    for (const Material& source : materials) {
        tinygltf::Material material;
        const auto& f = source.baseColorFactor;
        material.pbrMetallicRoughness.baseColorFactor = {f[0], f[1], f[2], f[3]};
        material.pbrMetallicRoughness.baseColorTexture.index = source.baseColorTexture;
        material.pbrMetallicRoughness.baseColorTexture.texCoord = 0;
        material.pbrMetallicRoughness.metallicFactor = 0.0;
        material.pbrMetallicRoughness.roughnessFactor = 1.0;
        material.doubleSided = true;
        model.materials.push_back(material);
    }
    return materials.size();
}

// The mesh: one indexed TRIANGLES primitive per material that has triangles, and whether the
// mesh is closed in extras.vtex.
tinygltf::Mesh primitives(tinygltf::Model& model, const TriangleMesh& mesh, const std::map<std::string, int>& attributes,
                          std::size_t materialCount) {
    tinygltf::Mesh gltfMesh;
    std::vector<std::vector<std::uint32_t>> indices(materialCount);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const std::uint32_t m = mesh.triangleMaterials.empty() ? 0 : mesh.triangleMaterials[t];
        indices[m].insert(indices[m].end(), mesh.triangles[t].begin(), mesh.triangles[t].end());
    }
    for (std::size_t m = 0; m < materialCount; ++m) {
        if (indices[m].empty()) continue;
        tinygltf::Primitive primitive;
        primitive.attributes = attributes;
        primitive.mode = TINYGLTF_MODE_TRIANGLES;
        primitive.material = int(m);
        const int view = appendView(model, indices[m].data(), indices[m].size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
        primitive.indices = appendAccessor(model, view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, indices[m].size());
        gltfMesh.primitives.push_back(primitive);
    }
    tinygltf::Value::Object vtexExtras;
    vtexExtras["closed"] = tinygltf::Value(mesh.closed);
    tinygltf::Value::Object extras;
    extras["vtex"] = tinygltf::Value(vtexExtras);
    gltfMesh.extras = tinygltf::Value(extras);
    return gltfMesh;
}

}  // namespace

std::string encodeMeshGlb(const TriangleMesh& mesh) {
    checkMesh(mesh);
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "vtex ingest";
    model.buffers.emplace_back();
    const std::map<std::string, int> attributes = appendVertexAttributes(model, mesh);
    appendTextures(model, mesh);
    const std::size_t materialCount = appendMaterials(model, mesh);
    model.meshes.push_back(primitives(model, mesh, attributes, materialCount));

    tinygltf::Node node;
    node.mesh = 0;
    model.nodes.push_back(node);
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;

    auto& data = model.buffers[0].data;
    while (data.size() % 4) data.push_back(0);
    if (data.empty()) model.buffers.clear();

    std::ostringstream out(std::ios::binary);
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, out, false, true))
        throw std::runtime_error("tinygltf failed to serialise the mesh");
    return std::move(out).str();
}

void writeMeshGlb(const TriangleMesh& mesh, const std::filesystem::path& file) {
    AtomicOutputFile out(file);
    writeMeshGlb(mesh, out);
    out.commit();
}

void writeMeshGlb(const TriangleMesh& mesh, AtomicOutputFile& out) {
    const std::string bytes = encodeMeshGlb(mesh);
    out.stream().write(bytes.data(), std::streamsize(bytes.size()));
}

}  // namespace vtex::ingest
