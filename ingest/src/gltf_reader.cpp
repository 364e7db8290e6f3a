// glTF 2.0 (.gltf and .glb) through tinygltf 2.7, which checks almost nothing itself: every
// check that keeps untrusted input from reading out of bounds, allocating without limit,
// escaping the input's folder or looping forever is made here, before the data is touched.
//
// The order is: the GLB container and the JSON nesting depth (tinygltf converts `extras`
// recursively), then tinygltf's parse with our file-system callbacks (contained, regular
// files only, size-capped) and a no-op image loader (stb never decodes anything), then the
// asset version, every bufferView and accessor extent (overflow-safe), and the node graph.
#include "detail.h"
#include "gltf_accessors.h"

#include <vtex/core/input_file.h>

#include <vtex/core/error.h>

#include <tiny_gltf.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <unordered_map>

namespace vtex::ingest::detail {
namespace {

namespace fs = std::filesystem;

// --- file-system callbacks ------------------------------------------------------------------

struct FsContext {
    fs::path root;  ///< canonical input folder; empty: nothing external may be read
    std::uint64_t maxBytes = 0;
    std::vector<std::string> refused;
};

bool fsFileExists(const std::string& path, void* user) {
    auto* context = static_cast<FsContext*>(user);
    std::error_code error;
    if (!fs::exists(path, error)) return false;  // tinygltf reports it as missing
    if (context->root.empty() || !isContainedRegularFile(context->root, path)) {
        context->refused.push_back(path);
        return false;
    }
    return true;
}

// No `~` or environment expansion: a URI means what it says.
std::string fsExpandFilePath(const std::string& path, void*) { return path; }

bool fsReadWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                     void* user) {
    auto* context = static_cast<FsContext*>(user);
    if (context->root.empty() || !isContainedRegularFile(context->root, path)) {
        context->refused.push_back(path);
        if (err) *err += "refused to read '" + path + "'";
        return false;
    }
    try {
        const std::string bytes = readInputFile(path, context->maxBytes, "file");
        out->assign(bytes.begin(), bytes.end());
        return true;
    } catch (const std::exception& e) {
        if (err) *err += e.what();
        return false;
    }
}

bool fsWriteWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&,
                      void*) {
    if (err) *err += "writing is disabled while reading";
    return false;
}

// tinygltf hands every image it finds to this callback. It never decodes: it keeps the encoded
// bytes of URI images (already size-capped by fsReadWholeFile) for decodeImage(). For a
// bufferView image tinygltf passes a pointer it computed without checking the view against
// its buffer, so those bytes are not touched here; they are fetched later, after the check.
bool captureImageBytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                       const unsigned char* bytes, int size, void*) {
    image->image.clear();
    image->width = image->height = 0;
    if (image->bufferView < 0 && bytes != nullptr && size > 0) image->image.assign(bytes, bytes + size);
    return true;
}

// --- structural pre-checks ------------------------------------------------------------------

// tinygltf converts `extras` and `extensions` into its Value tree recursively: bound the
// nesting depth so that hostile JSON cannot overflow the stack. Real assets stay far below.
constexpr int kMaxJsonDepth = 64;

void checkJsonDepth(std::string_view json, const fs::path& file) {
    int depth = 0;
    bool inString = false;
    for (std::size_t i = 0; i < json.size(); ++i) {
        const char c = json[i];
        if (inString) {
            if (c == '\\') ++i;
            else if (c == '"') inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '{' || c == '[') {
            if (++depth > kMaxJsonDepth)
                throw InputError(file, "JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                                           " levels");
        } else if (c == '}' || c == ']') {
            --depth;
        }
    }
}

std::uint32_t readLe32(std::string_view bytes, std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;  // glTF is little-endian, as every platform vtex builds on
}

// The GLB container (header, JSON chunk, optional BIN chunk), checked before tinygltf sees it;
// returns the JSON chunk.
std::string_view checkGlbContainer(std::string_view bytes, const fs::path& file) {
    if (bytes.size() < 12) throw InputError(file, "truncated GLB: shorter than its 12-byte header");
    if (std::memcmp(bytes.data(), "glTF", 4) != 0)
        throw InputError(file, "not a GLB file (wrong magic)");
    const std::uint32_t version = readLe32(bytes, 4);
    if (version != 2)
        throw InputError(file, "GLB container version " + std::to_string(version) +
                                   " is not supported (2 required)");
    const std::uint64_t length = readLe32(bytes, 8);
    if (length > bytes.size())
        throw InputError(file, "truncated GLB: header claims " + std::to_string(length) +
                                   " bytes, file has " + std::to_string(bytes.size()));
    if (length < 20) throw InputError(file, "truncated GLB: no JSON chunk");
    const std::uint64_t jsonLength = readLe32(bytes, 12);
    if (readLe32(bytes, 16) != 0x4E4F534Au)
        throw InputError(file, "GLB: first chunk is not JSON");
    if (jsonLength == 0 || jsonLength > length - 20)
        throw InputError(file, "truncated GLB: JSON chunk of " + std::to_string(jsonLength) +
                                   " bytes does not fit");
    std::uint64_t at = 20 + jsonLength;
    if (at % 4) throw InputError(file, "GLB: JSON chunk not padded to 4 bytes");
    if (at < length) {
        if (length - at < 8) throw InputError(file, "truncated GLB: incomplete chunk header");
        const std::uint64_t binLength = readLe32(bytes, at);
        if (readLe32(bytes, at + 4) != 0x004E4942u)
            throw InputError(file, "GLB: second chunk is not BIN");
        if (binLength > length - at - 8)
            throw InputError(file, "truncated GLB: BIN chunk of " + std::to_string(binLength) +
                                       " bytes does not fit");
    }
    return bytes.substr(20, jsonLength);
}

Eigen::Matrix4d nodeTransform(const tinygltf::Node& node, const fs::path& file, const std::string& where) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    auto finite = [](const std::vector<double>& v) {
        for (double x : v)
            if (!std::isfinite(x)) return false;
        return true;
    };
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16 || !finite(node.matrix))
            throw InputError(file, "matrix must hold 16 finite numbers", where);
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) m(r, c) = node.matrix[std::size_t(c * 4 + r)];  // column-major
        return m;
    }
    if ((!node.translation.empty() && node.translation.size() != 3) ||
        (!node.rotation.empty() && node.rotation.size() != 4) ||
        (!node.scale.empty() && node.scale.size() != 3) || !finite(node.translation) ||
        !finite(node.rotation) || !finite(node.scale))
        throw InputError(file, "translation/rotation/scale must hold 3/4/3 finite numbers", where);
    Eigen::Affine3d t = Eigen::Affine3d::Identity();
    if (!node.translation.empty())
        t.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
    if (!node.rotation.empty()) {
        Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
        if (q.norm() < 1e-12) throw InputError(file, "rotation quaternion is zero", where);
        t.rotate(q.normalized());
    }
    if (!node.scale.empty()) t.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
    return t.matrix();
}

class GltfMeshBuilder {
public:
    GltfMeshBuilder(const tinygltf::Model& model, const fs::path& file, const IngestOptions& options,
                    RawMesh& out)
        : mModel(model), mFile(file), mOptions(options), mDecoder(model, file, options), mOut(out) {}

    void build() {
        mDecoder.checkBufferViews();

        // Roots: the default scene, scene 0, or every node that is nobody's child.
        std::vector<int> roots;
        const std::size_t nodeCount = mModel.nodes.size();
        if (!mModel.scenes.empty()) {
            int scene = mModel.defaultScene;
            if (scene < 0) scene = 0;
            if (std::size_t(scene) >= mModel.scenes.size())
                throw InputError(mFile, "default scene " + std::to_string(scene) + " out of range", "scene");
            roots = mModel.scenes[std::size_t(scene)].nodes;
        } else {
            std::vector<char> isChild(nodeCount, 0);
            for (std::size_t i = 0; i < nodeCount; ++i)
                for (int child : mModel.nodes[i].children)
                    if (child >= 0 && std::size_t(child) < nodeCount) isChild[std::size_t(child)] = 1;
            for (std::size_t i = 0; i < nodeCount; ++i)
                if (!isChild[i]) roots.push_back(int(i));
            if (nodeCount > 0 && roots.empty())
                throw InputError(mFile, "node cycle: every node is some node's child", "nodes");
        }

        // Depth-first over the node forest with an explicit stack; glTF requires strict
        // trees, so a node met twice is a cycle or a shared child: refused either way.
        std::vector<char> state(nodeCount, 0);  // 0 unseen, 1 on the current path, 2 done
        struct Frame {
            int node;
            Eigen::Matrix4d world;
            std::size_t nextChild;
        };
        for (int root : roots) {
            if (root < 0 || std::size_t(root) >= nodeCount)
                throw InputError(mFile, "node " + std::to_string(root) + " out of range", "scenes");
            std::vector<Frame> stack;
            enter(root, Eigen::Matrix4d::Identity(), state, stack);
            while (!stack.empty()) {
                Frame& top = stack.back();
                const auto& children = mModel.nodes[std::size_t(top.node)].children;
                if (top.nextChild < children.size()) {
                    const int child = children[top.nextChild++];
                    const Eigen::Matrix4d parentWorld = top.world;
                    const std::string where = "nodes[" + std::to_string(top.node) + "].children";
                    if (child < 0 || std::size_t(child) >= nodeCount)
                        throw InputError(mFile, "child " + std::to_string(child) + " out of range", where);
                    if (state[std::size_t(child)] == 1)
                        throw InputError(mFile, "node cycle through node " + std::to_string(child), where);
                    if (state[std::size_t(child)] == 2)
                        throw InputError(mFile, "node " + std::to_string(child) +
                                                    " has more than one parent (glTF requires a tree)", where);
                    enter(child, parentWorld, state, stack);
                } else {
                    state[std::size_t(top.node)] = 2;
                    stack.pop_back();
                }
            }
        }
    }

private:
    template <class Stack>
    void enter(int node, const Eigen::Matrix4d& parent, std::vector<char>& state, Stack& stack) {
        const std::string where = "nodes[" + std::to_string(node) + "]";
        if (state[std::size_t(node)] != 0)
            throw InputError(mFile, "node " + std::to_string(node) + " is reached twice (cycle or shared node)", where);
        state[std::size_t(node)] = 1;
        const auto& n = mModel.nodes[std::size_t(node)];
        const Eigen::Matrix4d world = parent * nodeTransform(n, mFile, where);
        if (n.mesh >= 0) {
            if (std::size_t(n.mesh) >= mModel.meshes.size())
                throw InputError(mFile, "mesh " + std::to_string(n.mesh) + " out of range", where);
            addMesh(n.mesh, world);
        }
        stack.push_back({node, world, 0});
    }

    int materialIndex(int gltfMaterial, const std::string& where) {
        if (gltfMaterial < 0) {
            if (mDefaultMaterial < 0) {
                mDefaultMaterial = int(mOut.materials.size());
                mOut.materials.emplace_back();
            }
            return mDefaultMaterial;
        }
        if (std::size_t(gltfMaterial) >= mModel.materials.size())
            throw InputError(mFile, "material " + std::to_string(gltfMaterial) + " out of range", where);
        auto found = mMaterials.find(gltfMaterial);
        if (found != mMaterials.end()) return found->second;

        const auto& source = mModel.materials[std::size_t(gltfMaterial)];
        const std::string materialWhere = "materials[" + std::to_string(gltfMaterial) + "]";
        Material material;
        material.name = source.name;
        const auto& factor = source.pbrMetallicRoughness.baseColorFactor;
        if (!factor.empty()) {
            if (factor.size() != 4) throw InputError(mFile, "baseColorFactor must hold 4 numbers", materialWhere);
            for (int i = 0; i < 4; ++i) {
                if (!std::isfinite(factor[std::size_t(i)]))
                    throw InputError(mFile, "baseColorFactor is not finite", materialWhere);
                material.baseColorFactor[i] = float(std::clamp(factor[std::size_t(i)], 0.0, 1.0));
            }
        }
        const int texture = source.pbrMetallicRoughness.baseColorTexture.index;
        if (texture >= 0) material.baseColorTexture = textureIndex(texture, materialWhere);
        const int index = int(mOut.materials.size());
        mOut.materials.push_back(material);
        mMaterials[gltfMaterial] = index;
        mMaterialTexCoord[index] = source.pbrMetallicRoughness.baseColorTexture.texCoord;
        return index;
    }

    // Decodes glTF texture `texture` into mOut.textures; -1 (with a warning) when it cannot.
    int textureIndex(int texture, const std::string& where) {
        if (std::size_t(texture) >= mModel.textures.size())
            throw InputError(mFile, "texture " + std::to_string(texture) + " out of range", where);
        auto found = mTextures.find(texture);
        if (found != mTextures.end()) return found->second;
        int result = -1;
        const int source = mModel.textures[std::size_t(texture)].source;
        std::string why;
        if (source < 0 || std::size_t(source) >= mModel.images.size()) {
            why = "texture has no valid image source";
        } else {
            const auto& image = mModel.images[std::size_t(source)];
            std::string_view bytes;
            if (image.bufferView >= 0)
                bytes = mDecoder.viewBytes(image.bufferView, "images[" + std::to_string(source) + "]");
            else
                bytes = {reinterpret_cast<const char*>(image.image.data()), image.image.size()};
            if (bytes.empty() && !image.uri.empty())
                why = "image '" + image.uri + "' could not be read";
            else if (auto decoded = decodeImage(bytes, mOptions, why)) {
                result = int(mOut.textures.size());
                mOut.textures.push_back(std::move(*decoded));
            }
        }
        if (result < 0)
            mOut.warnings.push_back("textures[" + std::to_string(texture) + "]: " + why +
                                    "; base colour texture ignored");
        mTextures[texture] = result;
        return result;
    }

    // Where a mesh instance puts its primitives: its transform, the normals' (the inverse
    // transpose), whether it mirrors (winding flipped), the faces' group.
    struct Instance {
        Eigen::Matrix4d world;
        Eigen::Matrix3d normalMatrix;
        bool mirrored;
        std::uint32_t group;
    };

    void addMesh(int meshIndex, const Eigen::Matrix4d& world) {
        const auto& mesh = mModel.meshes[std::size_t(meshIndex)];
        const Eigen::Matrix3d linear = world.topLeftCorner<3, 3>();
        const double det = linear.determinant();
        if (!std::isfinite(det) || std::abs(det) < 1e-300) {
            mOut.warnings.push_back("meshes[" + std::to_string(meshIndex) +
                                    "]: instance with a singular transform skipped");
            return;
        }
        const Instance instance{world, linear.inverse().transpose(), det < 0, groupOf(meshIndex)};
        for (std::size_t p = 0; p < mesh.primitives.size(); ++p)
            addPrimitive(mesh.primitives[p], "meshes[" + std::to_string(meshIndex) + "].primitives[" + std::to_string(p) + "]",
                         instance);
    }

    // The mesh's name is its faces' group (a base mesh's faces take texels by it).
    std::uint32_t groupOf(int meshIndex) {
        const auto& mesh = mModel.meshes[std::size_t(meshIndex)];
        if (mesh.name.empty()) return kNoGroup;
        const auto [it, inserted] = mGroups.try_emplace(meshIndex, std::uint32_t(mOut.groups.size()));
        if (inserted) mOut.groups.push_back(mesh.name);
        return it->second;
    }

    void addPrimitive(const tinygltf::Primitive& primitive, const std::string& where, const Instance& instance) {
        if (primitive.mode == TINYGLTF_MODE_POINTS || primitive.mode == TINYGLTF_MODE_LINE ||
            primitive.mode == TINYGLTF_MODE_LINE_LOOP || primitive.mode == TINYGLTF_MODE_LINE_STRIP) {
            warnOnce(where + ": points and lines skipped");
            return;
        }
        if (primitive.mode != TINYGLTF_MODE_TRIANGLES && primitive.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            primitive.mode != TINYGLTF_MODE_TRIANGLE_FAN)
            throw InputError(mFile, "unknown primitive mode " + std::to_string(primitive.mode), where);
        const auto position = primitive.attributes.find("POSITION");
        if (position == primitive.attributes.end()) {
            warnOnce(where + ": no POSITION attribute, skipped");
            return;
        }
        std::size_t vertexCount = 0;
        int components = 0;
        const std::vector<double> positions = mDecoder.readAccessor(position->second, {3}, true, &vertexCount, &components);
        std::vector<double> normals;
        if (auto normal = primitive.attributes.find("NORMAL"); normal != primitive.attributes.end()) {
            std::size_t n = 0;
            normals = mDecoder.readAccessor(normal->second, {3}, true, &n, &components);
            if (n != vertexCount) throw InputError(mFile, "NORMAL count differs from POSITION count", where);
        }
        const int material = materialIndex(primitive.material, where);
        const std::vector<double> uvs = readUvs(primitive, material, vertexCount, where);
        // Corner indices, then triangles by mode.
        std::vector<std::uint32_t> corners;
        if (primitive.indices >= 0) {
            corners = mDecoder.readIndices(primitive.indices);
        } else {
            corners.resize(vertexCount);
            for (std::size_t i = 0; i < vertexCount; ++i) corners[i] = std::uint32_t(i);
        }
        const std::vector<std::array<std::uint32_t, 3>> triangles = trianglesByMode(primitive.mode, corners, where);
        if (mOut.triangles.size() + triangles.size() > mOptions.maxTriangles)
            throw InputError(mFile, "more than " + std::to_string(mOptions.maxTriangles) + " triangles (see --max-triangles)", where);
        const std::size_t base = mOut.positions.size();
        if (base + vertexCount > std::numeric_limits<std::uint32_t>::max())
            throw InputError(mFile, "more than 2^32 vertices", where);
        appendVertices(instance, positions, normals, uvs, vertexCount);
        appendTriangles(triangles, base, vertexCount, instance, material, where);
    }

    // UVs: the set the base-colour texture samples, else TEXCOORD_0, kept either way.
    std::vector<double> readUvs(const tinygltf::Primitive& primitive, int material, std::size_t vertexCount, const std::string& where) {
        std::vector<double> uvs;
        const bool textured = mOut.materials[std::size_t(material)].baseColorTexture >= 0;
        const std::string name = "TEXCOORD_" + std::to_string(textured ? mMaterialTexCoord[material] : 0);
        if (auto uv = primitive.attributes.find(name); uv != primitive.attributes.end()) {
            std::size_t n = 0;
            int components = 0;
            uvs = mDecoder.readAccessor(uv->second, {2}, true, &n, &components);
            if (n != vertexCount) throw InputError(mFile, name + " count differs from POSITION count", where);
        } else if (textured) {
            warnOnce(where + ": textured material without " + name + "; texture unused here");
        }
        return uvs;
    }

    std::vector<std::array<std::uint32_t, 3>> trianglesByMode(int mode, const std::vector<std::uint32_t>& corners,
                                                              const std::string& where) {
        std::vector<std::array<std::uint32_t, 3>> triangles;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (corners.size() % 3) warnOnce(where + ": index count not a multiple of 3, extra indices ignored");
            for (std::size_t i = 0; i + 2 < corners.size(); i += 3) triangles.push_back({corners[i], corners[i + 1], corners[i + 2]});
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (std::size_t i = 0; i + 2 < corners.size(); ++i) {
                if (i % 2 == 0) triangles.push_back({corners[i], corners[i + 1], corners[i + 2]});
                else triangles.push_back({corners[i + 1], corners[i], corners[i + 2]});
            }
        } else {
            for (std::size_t i = 1; i + 1 < corners.size(); ++i) triangles.push_back({corners[0], corners[i], corners[i + 1]});
        }
        return triangles;
    }

    // The primitive's vertices, transformed; normals and UVs are kept for every vertex once any
    // primitive has them (zero where one has not).
    void appendVertices(const Instance& instance, const std::vector<double>& positions, const std::vector<double>& normals,
                        const std::vector<double>& uvs, std::size_t vertexCount) {
        const std::size_t base = mOut.positions.size();
        const bool anyNormals = !normals.empty() || !mOut.normals.empty();
        const bool anyUvs = !uvs.empty() || !mOut.uvs.empty();
        if (anyNormals && mOut.normals.size() < base) mOut.normals.resize(base, Eigen::Vector3f::Zero());
        if (anyUvs && mOut.uvs.size() < base) mOut.uvs.resize(base, Eigen::Vector2f::Zero());
        for (std::size_t i = 0; i < vertexCount; ++i) {
            const Eigen::Vector4d p(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2], 1.0);
            mOut.positions.push_back((instance.world * p).head<3>().cast<float>());
            if (anyNormals) {
                Eigen::Vector3f n = Eigen::Vector3f::Zero();
                if (!normals.empty()) {
                    const Eigen::Vector3d source(normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]);
                    const Eigen::Vector3d transformed = instance.normalMatrix * source;
                    const double length = transformed.norm();
                    if (std::isfinite(length) && length > 0) n = (transformed / length).cast<float>();
                }
                mOut.normals.push_back(n);
            }
            if (anyUvs)
                mOut.uvs.push_back(uvs.empty() ? Eigen::Vector2f::Zero() : Eigen::Vector2f(float(uvs[2 * i]), float(uvs[2 * i + 1])));
        }
    }

    // The triangles, offset by `base` and with the winding fixed; one with an index past the
    // primitive's vertices is an error, or dropped and counted with --drop-invalid-faces.
    void appendTriangles(const std::vector<std::array<std::uint32_t, 3>>& triangles, std::size_t base, std::size_t vertexCount,
                         const Instance& instance, int material, const std::string& where) {
        for (auto t : triangles) {
            bool valid = true;
            for (std::uint32_t v : t) valid &= (v < vertexCount);
            if (!valid) {
                if (!mOptions.dropInvalidFaces) {
                    const auto bad = std::max({t[0], t[1], t[2]});
                    throw InputError(mFile, "index " + std::to_string(bad) + " out of range (" + std::to_string(vertexCount) + " vertices)",
                                     where + ".indices");
                }
                ++mOut.repairs.invalidIndexFaces;
                continue;
            }
            if (instance.mirrored) std::swap(t[1], t[2]);
            mOut.triangles.push_back({std::uint32_t(base + t[0]), std::uint32_t(base + t[1]), std::uint32_t(base + t[2])});
            mOut.triangleMaterials.push_back(std::uint32_t(material));
            mOut.triangleGroups.push_back(instance.group);
        }
    }

    void warnOnce(const std::string& warning) {
        if (mOut.warnings.size() < 100 &&
            std::find(mOut.warnings.begin(), mOut.warnings.end(), warning) == mOut.warnings.end())
            mOut.warnings.push_back(warning);
    }

    const tinygltf::Model& mModel;
    fs::path mFile;
    const IngestOptions& mOptions;
    GltfDecoder mDecoder;
    RawMesh& mOut;
    int mDefaultMaterial = -1;
    std::map<int, int> mMaterials;         // glTF material → mOut.materials
    std::map<int, std::uint32_t> mGroups;  // glTF mesh → mOut.groups
    std::map<int, int> mMaterialTexCoord;  // mOut material → TEXCOORD set of its texture
    std::map<int, int> mTextures;          // glTF texture → mOut.textures (or -1)
};

std::string firstLine(const std::string& text) {
    std::string line = text.substr(0, text.find('\n'));
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.size() > 300) line = line.substr(0, 300) + "...";
    return line;
}

}  // namespace

RawMesh readGltf(std::string_view bytes, bool binary, const fs::path& file, const fs::path& directory,
                 const IngestOptions& options) {
    if (bytes.empty()) throw InputError(file, "empty file");
    if (bytes.size() > std::numeric_limits<unsigned int>::max())
        throw InputError(file, "larger than 4 GiB, which glTF cannot address");
    const std::string_view json = binary ? checkGlbContainer(bytes, file) : bytes;
    checkJsonDepth(json, file);
    checkGltfSchema(json, file);

    FsContext context;
    context.maxBytes = options.maxFileBytes;
    if (!directory.empty()) {
        std::error_code error;
        context.root = fs::canonical(directory, error);
        if (error) context.root.clear();
    }
    tinygltf::FsCallbacks callbacks{};
    callbacks.FileExists = fsFileExists;
    callbacks.ExpandFilePath = fsExpandFilePath;
    callbacks.ReadWholeFile = fsReadWholeFile;
    callbacks.WriteWholeFile = fsWriteWholeFile;
    callbacks.user_data = &context;

    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks(callbacks);
    loader.SetImageLoader(captureImageBytes, nullptr);
    loader.SetStoreOriginalJSONForExtrasAndExtensions(false);

    tinygltf::Model model;
    std::string err, warn;
    const std::string base = context.root.string();
    bool ok = false;
    try {
        ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                                  reinterpret_cast<const unsigned char*>(bytes.data()),
                                                  static_cast<unsigned int>(bytes.size()), base)
                    : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(),
                                                 static_cast<unsigned int>(bytes.size()), base);
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(file, std::string("invalid glTF: ") + e.what());
    }
    if (!context.refused.empty())
        throw InputError(file, "refused to read '" + context.refused.front() +
                                   "': outside the input's folder, missing, or not a regular file");
    if (!ok || !err.empty())
        throw InputError(file, "invalid glTF: " + (err.empty() ? std::string("tinygltf failed") : firstLine(err)));
    if (model.asset.version.rfind("2.", 0) != 0)
        throw InputError(file, "glTF version '" + model.asset.version + "' is not supported (2.x required)",
                         "asset.version");

    RawMesh out;
    out.format = binary ? "glb" : "gltf";
    // glTF is +Y up by its specification; the canonical mesh vtex writes is already +Z up.
    out.up = model.asset.generator.rfind("vtex", 0) == 0 ? 'z' : 'y';
    for (std::size_t start = 0; start < warn.size();) {
        const std::size_t end = warn.find('\n', start);
        std::string line = warn.substr(start, end == std::string::npos ? std::string::npos : end - start);
        if (!line.empty() && out.warnings.size() < 50) out.warnings.push_back("tinygltf: " + firstLine(line));
        if (end == std::string::npos) break;
        start = end + 1;
    }
    GltfMeshBuilder(model, file, options, out).build();
    return out;
}

}  // namespace vtex::ingest::detail
