// A scene's base meshes and texel cells as one .glb (layout_glb.h), written with tinygltf
// (Debian ships it compiled: TINYGLTF_IMPLEMENTATION is never defined here).
#include <vtex/interop/layout_glb.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/render/geometry.h>

#include <tiny_gltf.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace vtex::interop {
namespace {

using render::Vec3;

// One primitive's worth of geometry: positions, triangles and (optionally) line segments.
struct Geometry {
    std::vector<float> positions;
    std::vector<std::uint32_t> triangles;
    std::vector<std::uint32_t> lines;

    std::uint32_t add(const Vec3& p) {
        for (int c = 0; c < 3; ++c) positions.push_back(float(p[c]));
        return std::uint32_t(positions.size() / 3 - 1);
    }
};

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

int appendAccessor(tinygltf::Model& model, int view, int componentType, int type, std::size_t count) {
    tinygltf::Accessor accessor;
    accessor.bufferView = view;
    accessor.componentType = componentType;
    accessor.type = type;
    accessor.count = count;
    model.accessors.push_back(accessor);
    return int(model.accessors.size() - 1);
}

int appendIndices(tinygltf::Model& model, const std::vector<std::uint32_t>& indices) {
    const int view = appendView(model, indices.data(), indices.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    return appendAccessor(model, view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, indices.size());
}

int addMaterial(tinygltf::Model& model, const std::string& name, const std::array<double, 4>& rgba) {
    tinygltf::Material material;
    material.name = name;
    material.pbrMetallicRoughness.baseColorFactor = {rgba[0], rgba[1], rgba[2], rgba[3]};
    material.pbrMetallicRoughness.metallicFactor = 0.0;
    material.pbrMetallicRoughness.roughnessFactor = 1.0;
    material.doubleSided = true;
    if (rgba[3] < 1) material.alphaMode = "BLEND";
    model.materials.push_back(material);
    return int(model.materials.size() - 1);
}

// A node with one mesh: the triangles, and the lines when there are any, sharing the positions.
int addNode(tinygltf::Model& model, const std::string& name, const Geometry& g, int material,
            tinygltf::Value extras = {}) {
    tinygltf::Mesh mesh;
    mesh.name = name;
    const std::size_t n = g.positions.size() / 3;
    if (n > 0) {
        std::vector<double> lo(3, std::numeric_limits<double>::max()), hi(3, -std::numeric_limits<double>::max());
        for (std::size_t i = 0; i < g.positions.size(); ++i) {
            lo[i % 3] = std::min(lo[i % 3], double(g.positions[i]));
            hi[i % 3] = std::max(hi[i % 3], double(g.positions[i]));
        }
        const int view = appendView(model, g.positions.data(), g.positions.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
        const int positions = appendAccessor(model, view, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, n);
        model.accessors[std::size_t(positions)].minValues = lo;
        model.accessors[std::size_t(positions)].maxValues = hi;
        for (const auto& [indices, mode] : {std::pair{&g.triangles, TINYGLTF_MODE_TRIANGLES},
                                            std::pair{&g.lines, TINYGLTF_MODE_LINE}}) {
            if (indices->empty()) continue;
            tinygltf::Primitive primitive;
            primitive.attributes["POSITION"] = positions;
            primitive.mode = mode;
            primitive.material = material;
            primitive.indices = appendIndices(model, *indices);
            mesh.primitives.push_back(primitive);
        }
    }
    tinygltf::Node node;
    node.name = name;
    if (!mesh.primitives.empty()) {
        model.meshes.push_back(mesh);
        node.mesh = int(model.meshes.size() - 1);
    }
    node.extras = std::move(extras);
    model.nodes.push_back(node);
    return int(model.nodes.size() - 1);
}

// A cell's hexahedron: its corners (index i + 2j + 4k for u = i, v = j, w = k), its six
// faces as two triangles each, its twelve edges.
void addCell(Geometry& g, const render::TrilinearCell& cell) {
    std::uint32_t v[8];
    for (int c = 0; c < 8; ++c) v[c] = g.add(cell.corners()[std::size_t(c)]);
    // Faces w=0, w=1, u=0, u=1, v=0, v=1, each as a quad a b c d around its boundary.
    const int faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}};
    for (const auto& f : faces)
        for (int t : {f[0], f[1], f[2], f[0], f[2], f[3]}) g.triangles.push_back(v[t]);
    const int edges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                              {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const auto& e : edges) g.lines.insert(g.lines.end(), {v[e[0]], v[e[1]]});
}

tinygltf::Value cellExtras(const render::Scene& scene, const render::TexelPlacing& def) {
    const render::TexelDef& texel = scene.texels[*def.texel];
    tinygltf::Value::Object vtex;
    vtex["texel"] = tinygltf::Value(texel.name);
    vtex["volume"] = tinygltf::Value(texel.volume.string());
    vtex["tau"] = tinygltf::Value(texel.tau);
    vtex["height"] = tinygltf::Value(def.height);
    vtex["placement"] = tinygltf::Value(std::string(def.placement == render::Placement::Under ? "under" : "on"));
    vtex["repeat"] =
        tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(def.repeat[0]), tinygltf::Value(def.repeat[1])});
    tinygltf::Value::Object extras;
    extras["vtex"] = tinygltf::Value(vtex);
    return tinygltf::Value(extras);
}

// One surface: its base mesh node and, when textured, a cells node per texel placing (the
// faces of each material or group its `texels` names, and the others). Returns the node indices.
std::vector<int> addSurface(tinygltf::Model& model, const render::Scene& scene, std::size_t si, int cellMaterial,
                            LayoutSummary& summary) {
    const render::SurfaceDef& def = scene.surfaces[si];
    for (std::size_t k = 0; k < def.placingCount(); ++k)
        if (const auto texel = def.placing(k).texel; texel && *texel >= scene.texels.size())
            throw InputError(scene.file, "texel index out of range", "surface[" + std::to_string(si) + "].texel");
    const auto mesh = render::loadSurfaceMesh(scene, si);
    const std::vector<std::uint32_t> placings = render::facePlacings(scene, si, *mesh);
    Geometry base;
    std::vector<Geometry> cells(def.placingCount());
    std::vector<std::uint64_t> cellCount(def.placingCount(), 0);
    for (std::size_t f = 0; f < mesh->quads.size(); ++f) {
        std::array<Vec3, 4> p, n;
        if (!ingest::patchCorners(*mesh, f, p, n))  // as the renderer places cells
            throw InputError(def.mesh, "face " + std::to_string(f) + " has an invalid corner");
        const std::uint32_t b = base.add(p[0]), c1 = base.add(p[1]), c2 = base.add(p[2]), c3 = base.add(p[3]);
        base.triangles.insert(base.triangles.end(), {b, c1, c3});
        if (!mesh->isTriangle(f)) base.triangles.insert(base.triangles.end(), {b, c3, c2});
        const render::TexelPlacing placing = def.placing(placings[f]);
        if (!placing.texel) continue;
        const render::TrilinearCell cell(p, n, placing.height, placing.placement == render::Placement::Under);
        // glTF positions are floats: a shell whose top lies beyond them would be written as inf.
        for (const Vec3& corner : cell.corners())
            if (!(corner.cwiseAbs().maxCoeff() <= double(std::numeric_limits<float>::max())))
                throw InputError(def.mesh, "face " + std::to_string(f) + ": its shell reaches beyond the float range");
        addCell(cells[placings[f]], cell);
        ++cellCount[placings[f]];
    }
    summary.faces += mesh->quads.size();
    const auto& d = def.material.diffuse;
    const int baseMaterial = addMaterial(model, "surface" + std::to_string(si), {d[0], d[1], d[2], 1});
    const std::string prefix = "surface" + std::to_string(si);
    std::vector<int> nodes{addNode(model, prefix + " " + def.mesh.filename().string(), base, baseMaterial)};
    for (std::size_t k = 0; k < def.placingCount(); ++k) {
        const render::TexelPlacing placing = def.placing(k);
        if (!placing.texel || (k > 0 && cellCount[k] == 0) || (k == 0 && cellCount[k] == 0 && !def.texels.empty()))
            continue;
        summary.cells += cellCount[k];
        const std::string group = k == 0 ? "" : " " + def.texels[k - 1].name;
        nodes.push_back(addNode(model, prefix + group + " cells " + scene.texels[*placing.texel].name, cells[k],
                                cellMaterial, cellExtras(scene, placing)));
    }
    return nodes;
}

}  // namespace

std::string encodeLayoutGlb(const render::Scene& scene, LayoutSummary* summary) {
    LayoutSummary counts;
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "vtex export";
    model.buffers.emplace_back();
    const int cellMaterial = addMaterial(model, "texel cells", {0.2, 0.7, 0.3, 0.25});
    tinygltf::Scene gltfScene;
    for (std::size_t si = 0; si < scene.surfaces.size(); ++si)
        for (int node : addSurface(model, scene, si, cellMaterial, counts)) gltfScene.nodes.push_back(node);
    counts.surfaces = scene.surfaces.size();
    model.scenes.push_back(gltfScene);
    model.defaultScene = 0;
    auto& data = model.buffers[0].data;
    while (data.size() % 4) data.push_back(0);
    if (data.empty()) model.buffers.clear();

    std::ostringstream out(std::ios::binary);
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, out, false, true))
        throw std::runtime_error("tinygltf failed to serialise the layout");
    if (summary) *summary = counts;
    return std::move(out).str();
}

LayoutSummary writeLayoutGlb(const render::Scene& scene, const std::filesystem::path& file) {
    AtomicOutputFile out(file);
    LayoutSummary summary;
    const std::string bytes = encodeLayoutGlb(scene, &summary);
    out.stream().write(bytes.data(), std::streamsize(bytes.size()));
    out.commit();
    return summary;
}

}  // namespace vtex::interop
