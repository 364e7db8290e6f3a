// The JSON types of every glTF property vtex relies on, checked before tinygltf parses the
// document: tinygltf 2.7 silently skips a property of the wrong type (a "name": 42, a
// "children": "0"), which would turn a malformed file into a quietly different mesh.
#include "detail.h"

#include <vtex/core/error.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>

namespace vtex::ingest::detail {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

bool isBase64Payload(std::string_view uri) {
    const auto comma = uri.find(',');
    if (comma == std::string_view::npos) return false;
    const std::string_view header = uri.substr(0, comma);
    if (header.size() < 7 || header.substr(header.size() - 7) != ";base64") return false;
    std::string_view payload = uri.substr(comma + 1);
    if (payload.size() % 4) return false;
    std::size_t padding = 0;
    for (std::size_t i = 0; i < payload.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(payload[i]);
        if (c == '=') {
            if (i + 2 < payload.size()) return false;
            ++padding;
        } else if (padding || !(std::isalnum(c) || c == '+' || c == '/')) {
            return false;
        }
    }
    return true;
}

// The file name tinygltf opens for a URI: it percent-decodes it as its bundled dlib::urldecode
// does ('+' is a space; "%XY" the byte of two hex digits, a non-hex digit counting as 0; a '%'
// among the last two characters stays), so the check below looks at exactly that name.
std::string decodeUriAsTinygltf(const std::string& uri) {
    const auto hex = [](char c) -> unsigned {
        if (c >= '0' && c <= '9') return unsigned(c - '0');
        if (c >= 'a' && c <= 'f') return unsigned(c - 'a' + 10);
        if (c >= 'A' && c <= 'F') return unsigned(c - 'A' + 10);
        return 0;
    };
    std::string out;
    for (std::size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '+') {
            out += ' ';
        } else if (uri[i] == '%' && uri.size() > i + 2) {
            out += char((hex(uri[i + 1]) << 4) | hex(uri[i + 2]));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

// A URI that is absolute, names a scheme or climbs out of the folder, as written or once
// percent-decoded (`my%20buffer.bin` is the file `my buffer.bin`; `..%2F` climbs as `../` does),
// is refused before tinygltf resolves anything (its file-system callbacks refuse such reads too,
// and symbolic links leading out of the folder; this gives the clearer message). Data URIs must
// be base64.
void checkUri(const std::string& uri, const std::string& where, const fs::path& file) {
    if (uri.empty()) return;
    if (uri.rfind("data:", 0) == 0) {
        if (!isBase64Payload(uri)) throw InputError(file, "data URI is not valid base64", where);
        return;
    }
    bool escapes = false;
    for (std::string name : {uri, decodeUriAsTinygltf(uri)}) {
        escapes = escapes || name.empty() || name.find('\0') != std::string::npos || name.find(':') != std::string::npos ||
                  name[0] == '\\' || name[0] == '/';
        std::replace(name.begin(), name.end(), '\\', '/');
        for (const auto& part : fs::path(name))
            if (part == "..") escapes = true;
    }
    if (escapes) throw InputError(file, "URI '" + uri.substr(0, 200) + "' escapes the input's folder (refused)", where);
}

enum class Kind { Uint, Number, String, Bool, Object, Numbers, Uints, Strings, Objects, TextureInfo };

struct Rule {
    const char* name;
    Kind kind;
};

class SchemaChecker {
public:
    explicit SchemaChecker(const std::filesystem::path& file) : mFile(file) {}

    [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
        throw InputError(mFile, problem, where);
    }

    bool matches(const json& v, Kind kind) const {
        switch (kind) {
            case Kind::Uint: return v.is_number_unsigned() || (v.is_number_integer() && v.get<std::int64_t>() >= 0) ||
                                    (v.is_number_float() && v.get<double>() >= 0 && v.get<double>() == std::floor(v.get<double>()));
            case Kind::Number: return v.is_number();
            case Kind::String: return v.is_string();
            case Kind::Bool: return v.is_boolean();
            case Kind::Object:
            case Kind::TextureInfo: return v.is_object();
            case Kind::Numbers:
                if (!v.is_array()) return false;
                for (const auto& e : v)
                    if (!e.is_number()) return false;
                return true;
            case Kind::Uints:
                if (!v.is_array()) return false;
                for (const auto& e : v)
                    if (!matches(e, Kind::Uint)) return false;
                return true;
            case Kind::Strings:
                if (!v.is_array()) return false;
                for (const auto& e : v)
                    if (!e.is_string()) return false;
                return true;
            case Kind::Objects:
                if (!v.is_array()) return false;
                for (const auto& e : v)
                    if (!e.is_object()) return false;
                return true;
        }
        return false;
    }

    static const char* kindName(Kind kind) {
        switch (kind) {
            case Kind::Uint: return "a non-negative integer";
            case Kind::Number: return "a number";
            case Kind::String: return "a string";
            case Kind::Bool: return "a boolean";
            case Kind::Object:
            case Kind::TextureInfo: return "an object";
            case Kind::Numbers: return "an array of numbers";
            case Kind::Uints: return "an array of non-negative integers";
            case Kind::Strings: return "an array of strings";
            case Kind::Objects: return "an array of objects";
        }
        return "?";
    }

    void object(const json& o, const std::string& where, std::initializer_list<Rule> rules,
                std::initializer_list<const char*> required = {}) const {
        if (!o.is_object()) fail(where, "must be an object");
        for (const char* name : required)
            if (!o.contains(name)) fail(where, std::string("required property '") + name + "' is missing");
        for (const Rule& rule : rules) {
            const auto it = o.find(rule.name);
            if (it == o.end()) continue;
            const std::string at = where + "." + rule.name;
            if (!matches(*it, rule.kind)) fail(at, std::string("must be ") + kindName(rule.kind));
            if (rule.kind == Kind::TextureInfo)
                object(*it, at, {{"index", Kind::Uint}, {"texCoord", Kind::Uint}, {"scale", Kind::Number},
                                 {"strength", Kind::Number}}, {"index"});
        }
    }

    template <class F>
    void array(const json& root, const char* name, F&& each) const {
        const auto it = root.find(name);
        if (it == root.end()) return;
        if (!it->is_array()) fail(name, "must be an array");
        for (std::size_t i = 0; i < it->size(); ++i) each((*it)[i], std::string(name) + "[" + std::to_string(i) + "]");
    }

    void check(const json& root) const {
        if (!root.is_object()) fail("", "the glTF JSON document is not an object");
        object(root, "", {{"asset", Kind::Object}, {"scene", Kind::Uint}, {"extensionsUsed", Kind::Strings},
                          {"extensionsRequired", Kind::Strings}}, {"asset"});
        object(root["asset"], "asset", {{"version", Kind::String}, {"minVersion", Kind::String},
                                        {"generator", Kind::String}}, {"version"});
        if (const auto it = root.find("extensionsRequired"); it != root.end())
            for (const auto& name : *it)
                if (name != "KHR_materials_emissive_strength" && name != "KHR_texture_transform" &&
                    name != "KHR_materials_unlit")
                    fail("extensionsRequired", "requires extension " + name.get<std::string>() +
                                                   ", which vtex does not support");
        array(root, "accessors", [&](const json& a, const std::string& w) {
            object(a, w, {{"bufferView", Kind::Uint}, {"byteOffset", Kind::Uint}, {"componentType", Kind::Uint},
                          {"normalized", Kind::Bool}, {"count", Kind::Uint}, {"type", Kind::String},
                          {"max", Kind::Numbers}, {"min", Kind::Numbers}, {"sparse", Kind::Object},
                          {"name", Kind::String}}, {"componentType", "count", "type"});
            if (const auto s = a.find("sparse"); s != a.end()) {
                object(*s, w + ".sparse", {{"count", Kind::Uint}, {"indices", Kind::Object}, {"values", Kind::Object}},
                       {"count", "indices", "values"});
                object((*s)["indices"], w + ".sparse.indices",
                       {{"bufferView", Kind::Uint}, {"byteOffset", Kind::Uint}, {"componentType", Kind::Uint}},
                       {"bufferView", "componentType"});
                object((*s)["values"], w + ".sparse.values", {{"bufferView", Kind::Uint}, {"byteOffset", Kind::Uint}},
                       {"bufferView"});
            }
        });
        array(root, "bufferViews", [&](const json& v, const std::string& w) {
            object(v, w, {{"buffer", Kind::Uint}, {"byteOffset", Kind::Uint}, {"byteLength", Kind::Uint},
                          {"byteStride", Kind::Uint}, {"target", Kind::Uint}, {"name", Kind::String}},
                   {"buffer", "byteLength"});
        });
        array(root, "buffers", [&](const json& b, const std::string& w) {
            object(b, w, {{"uri", Kind::String}, {"byteLength", Kind::Uint}, {"name", Kind::String}}, {"byteLength"});
            if (const auto uri = b.find("uri"); uri != b.end()) checkUri(uri->get<std::string>(), w + ".uri", mFile);
        });
        array(root, "meshes", [&](const json& m, const std::string& w) {
            object(m, w, {{"primitives", Kind::Objects}, {"weights", Kind::Numbers}, {"name", Kind::String}},
                   {"primitives"});
            const auto& primitives = m["primitives"];
            for (std::size_t i = 0; i < primitives.size(); ++i) {
                const std::string pw = w + ".primitives[" + std::to_string(i) + "]";
                object(primitives[i], pw, {{"attributes", Kind::Object}, {"indices", Kind::Uint},
                                           {"material", Kind::Uint}, {"mode", Kind::Uint}, {"targets", Kind::Objects}},
                       {"attributes"});
                for (const auto& [name, value] : primitives[i]["attributes"].items())
                    if (!matches(value, Kind::Uint)) fail(pw + ".attributes." + name, "must be a non-negative integer");
            }
        });
        array(root, "nodes", [&](const json& n, const std::string& w) {
            object(n, w, {{"camera", Kind::Uint}, {"skin", Kind::Uint}, {"mesh", Kind::Uint}, {"children", Kind::Uints},
                          {"matrix", Kind::Numbers}, {"rotation", Kind::Numbers}, {"scale", Kind::Numbers},
                          {"translation", Kind::Numbers}, {"weights", Kind::Numbers}, {"name", Kind::String}});
        });
        array(root, "materials", [&](const json& m, const std::string& w) {
            object(m, w, {{"name", Kind::String}, {"pbrMetallicRoughness", Kind::Object},
                          {"normalTexture", Kind::TextureInfo}, {"occlusionTexture", Kind::TextureInfo},
                          {"emissiveTexture", Kind::TextureInfo}, {"emissiveFactor", Kind::Numbers},
                          {"alphaMode", Kind::String}, {"alphaCutoff", Kind::Number}, {"doubleSided", Kind::Bool}});
            if (const auto p = m.find("pbrMetallicRoughness"); p != m.end())
                object(*p, w + ".pbrMetallicRoughness",
                       {{"baseColorFactor", Kind::Numbers}, {"baseColorTexture", Kind::TextureInfo},
                        {"metallicFactor", Kind::Number}, {"roughnessFactor", Kind::Number},
                        {"metallicRoughnessTexture", Kind::TextureInfo}});
        });
        array(root, "textures", [&](const json& t, const std::string& w) {
            object(t, w, {{"sampler", Kind::Uint}, {"source", Kind::Uint}, {"name", Kind::String}});
        });
        array(root, "images", [&](const json& i, const std::string& w) {
            object(i, w, {{"uri", Kind::String}, {"mimeType", Kind::String}, {"bufferView", Kind::Uint},
                          {"name", Kind::String}});
            if (const auto uri = i.find("uri"); uri != i.end()) checkUri(uri->get<std::string>(), w + ".uri", mFile);
        });
        array(root, "samplers", [&](const json& s, const std::string& w) {
            object(s, w, {{"magFilter", Kind::Uint}, {"minFilter", Kind::Uint}, {"wrapS", Kind::Uint},
                          {"wrapT", Kind::Uint}, {"name", Kind::String}});
        });
        array(root, "scenes", [&](const json& s, const std::string& w) {
            object(s, w, {{"nodes", Kind::Uints}, {"name", Kind::String}});
        });
    }

private:
    std::filesystem::path mFile;
};

}  // namespace

void checkGltfSchema(std::string_view jsonText, const std::filesystem::path& file) {
    json root = json::parse(jsonText.begin(), jsonText.end(), nullptr, false);
    if (root.is_discarded()) throw InputError(file, "invalid glTF: the JSON does not parse");
    SchemaChecker(file).check(root);
}

}  // namespace vtex::ingest::detail
