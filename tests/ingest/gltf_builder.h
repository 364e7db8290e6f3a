// Builds small glTF documents (JSON + one binary buffer) for the ingest tests, valid or
// deliberately broken.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace vtex::test {

inline std::string base64(const std::string& bytes) {
    static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const std::uint32_t v = std::uint8_t(bytes[i]) << 16 | std::uint8_t(bytes[i + 1]) << 8 | std::uint8_t(bytes[i + 2]);
        for (int k = 3; k >= 0; --k) out += table[(v >> (6 * k)) & 63];
    }
    if (i + 1 == bytes.size()) {
        const std::uint32_t v = std::uint8_t(bytes[i]) << 16;
        out += table[(v >> 18) & 63];
        out += table[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == bytes.size()) {
        const std::uint32_t v = std::uint8_t(bytes[i]) << 16 | std::uint8_t(bytes[i + 1]) << 8;
        out += table[(v >> 18) & 63];
        out += table[(v >> 12) & 63];
        out += table[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

struct GltfBuilder {
    nlohmann::json doc = {{"asset", {{"version", "2.0"}}}};
    std::string bin;

    template <class T>
    int view(const std::vector<T>& values, std::size_t stride = 0) {
        while (bin.size() % 4) bin.push_back('\0');
        nlohmann::json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", values.size() * sizeof(T)}};
        if (stride) v["byteStride"] = stride;
        bin.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
        doc["bufferViews"].push_back(v);
        return int(doc["bufferViews"].size() - 1);
    }
    int accessor(int bufferView, int componentType, std::size_t count, const char* type,
                 nlohmann::json extra = nlohmann::json::object()) {
        nlohmann::json a = {{"componentType", componentType}, {"count", count}, {"type", type}};
        if (bufferView >= 0) a["bufferView"] = bufferView;
        a.update(extra);
        doc["accessors"].push_back(a);
        return int(doc["accessors"].size() - 1);
    }
    int positions(const std::vector<float>& xyz) {
        return accessor(view(xyz), 5126, xyz.size() / 3, "VEC3");
    }
    int indices(const std::vector<std::uint32_t>& values) {
        return accessor(view(values), 5125, values.size(), "SCALAR");
    }
    // A mesh with one primitive, instanced by a node with `node` properties, in scene 0.
    void meshNode(nlohmann::json primitive, nlohmann::json node = nlohmann::json::object()) {
        doc["meshes"].push_back({{"primitives", {primitive}}});
        node["mesh"] = doc["meshes"].size() - 1;
        doc["nodes"].push_back(node);
        if (!doc.contains("scenes")) doc["scenes"] = {{{"nodes", nlohmann::json::array()}}};
        doc["scenes"][0]["nodes"].push_back(doc["nodes"].size() - 1);
        doc["scene"] = 0;
    }
    void finishBuffer(const std::string& uri) {
        while (bin.size() % 4) bin.push_back('\0');
        doc["buffers"] = {{{"byteLength", bin.size()}}};
        if (!uri.empty()) doc["buffers"][0]["uri"] = uri;
    }
    // .gltf with the buffer as a data URI.
    std::string gltfEmbedded() {
        finishBuffer("data:application/octet-stream;base64," + base64(bin));
        return doc.dump();
    }
    // .glb with the buffer in the BIN chunk.
    std::string glb() {
        finishBuffer("");
        std::string json = doc.dump();
        while (json.size() % 4) json.push_back(' ');
        std::string out = "glTF";
        auto u32 = [&out](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
        u32(2);
        u32(std::uint32_t(12 + 8 + json.size() + 8 + bin.size()));
        u32(std::uint32_t(json.size()));
        u32(0x4E4F534A);
        out += json;
        u32(std::uint32_t(bin.size()));
        u32(0x004E4942);
        out += bin;
        return out;
    }
};

inline void writeBytes(const std::filesystem::path& path, const std::string& bytes) {
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path, std::ios::binary) << bytes;
}

// One triangle in the z = 0 plane, counter-clockwise seen from +z.
inline const std::vector<float> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

/// `name` in the test's own folder `folder` under the build's temporary directory (made).
inline std::filesystem::path tmpFile(const std::string& folder, const std::string& name) {
    const std::filesystem::path dir = std::filesystem::path(VTEX_TEST_TMP) / folder;
    std::filesystem::create_directories(dir);
    return dir / name;
}

}  // namespace vtex::test
