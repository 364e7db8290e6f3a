// Wavefront OBJ (+ MTL `Kd`, `d`, `map_Kd`), parsed here rather than with OpenMesh's OBJ reader.
//
// Why not OpenMesh: its reader trusts the file. It hands face indices straight to the mesh
// (an index past the vertex count becomes an invalid handle), follows `mtllib` and `map_Kd`
// paths anywhere on disk, and to make it safe we would have to tokenize every face line and
// every path ourselves first, which is this parser. Parsing OBJ is a few hundred lines with
// std::from_chars; doing it here gives exact line numbers in errors, per-corner UV/normal
// handling, bounded memory (every element costs at least a few bytes of input) and no reads
// outside the input's folder. OFF, PLY and STL still go through OpenMesh (openmesh_reader.cpp).
#include "detail.h"

#include <vtex/core/input_file.h>

#include <vtex/core/error.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <unordered_map>

namespace vtex::ingest::detail {
namespace {

namespace fs = std::filesystem;

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view trim(std::string_view s) {
    while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
    while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
    return s;
}

// Splits off the next whitespace-separated token of `s`.
std::string_view nextToken(std::string_view& s) {
    while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
    std::size_t end = 0;
    while (end < s.size() && !isSpace(s[end])) ++end;
    std::string_view token = s.substr(0, end);
    s.remove_prefix(end);
    return token;
}

struct Corner {
    std::int64_t v = 0, vt = 0, vn = 0;
    bool operator==(const Corner&) const = default;
};
struct CornerHash {
    std::size_t operator()(const Corner& c) const {
        // Unsigned arithmetic: wrapping is defined (found by the fuzzer as a signed overflow).
        return std::size_t(std::uint64_t(c.v) * 0x9E3779B97F4A7C15ULL) ^ std::size_t(std::uint64_t(c.vt) * 0xC2B2AE3D27D4EB4FULL) ^
               std::size_t(std::uint64_t(c.vn) * 0x165667B19E3779F9ULL);
    }
};

class ObjParser {
public:
    ObjParser(std::string_view text, const fs::path& file, const fs::path& directory, const IngestOptions& options)
        : mText(text), mFile(file), mOptions(options) {
        if (!directory.empty()) {
            std::error_code error;
            mRoot = fs::canonical(directory, error);
            if (error) mRoot.clear();
        }
    }

    RawMesh parse() {
        mOut.format = "obj";
        std::size_t lineNumber = 0;
        std::string_view rest = mText;
        while (!rest.empty()) {
            const std::size_t end = rest.find('\n');
            std::string_view line = rest.substr(0, end);
            rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end + 1);
            ++lineNumber;
            mLine = lineNumber;
            if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
            line = trim(line);
            if (line.empty()) continue;
            std::string_view args = line;
            const std::string_view keyword = nextToken(args);
            if (keyword == "v") vertex(args);
            else if (keyword == "vt") texcoord(args);
            else if (keyword == "vn") normal(args);
            else if (keyword == "f" || keyword == "fo") face(args);
            else if (keyword == "l" || keyword == "p") ++mSkippedPrimitives;
            else if (keyword == "usemtl") useMaterial(trim(args));
            else if (keyword == "mtllib") loadMaterialLibraries(trim(args));
            else if (keyword == "g") useGroup(trim(args));
            // o, s, vp, curves, surfaces...: not geometry vtex uses.
        }
        if (mSkippedPrimitives)
            mOut.warnings.push_back(std::to_string(mSkippedPrimitives) + " point and line elements skipped");
        if (mOut.triangles.empty() && mOut.repairs.invalidIndexFaces == 0)
            throw InputError(mFile, mSkippedPrimitives ? "no faces (points and lines only)" : "no faces");
        // Normals and UVs: keep the arrays only when some corner had them.
        if (!mAnyNormal) mOut.normals.clear();
        const auto used = std::count_if(mFirstCorner.begin(), mFirstCorner.end(),
                                        [](const FirstCorner& c) { return c.vertex != kNoVertex; });
        mOut.repairs.unreferencedVertices = std::uint64_t(mPositions.size()) - std::uint64_t(used);
        if (!mAnyUv) mOut.uvs.clear();
        return std::move(mOut);
    }

private:
    [[noreturn]] void fail(const std::string& problem) const {
        throw InputError(mFile, problem, "line " + std::to_string(mLine));
    }

    template <int N>
    Eigen::Matrix<float, N, 1> numbers(std::string_view args, int required, const char* what) {
        Eigen::Matrix<float, N, 1> v = Eigen::Matrix<float, N, 1>::Zero();
        for (int i = 0; i < N; ++i) {
            const std::string_view token = nextToken(args);
            if (token.empty()) {
                if (i < required) fail(std::string("'") + what + "' needs " + std::to_string(required) + " numbers");
                break;
            }
            const auto value = parseDecimal<float>(token);
            if (!value) fail("bad number '" + std::string(token.substr(0, 40)) + "'");
            v[i] = *value;
        }
        return v;
    }

    void vertex(std::string_view args) { mPositions.push_back(numbers<3>(args, 3, "v")); }
    void texcoord(std::string_view args) {
        Eigen::Vector2f uv = numbers<2>(args, 1, "vt");
        uv.y() = 1.0f - uv.y();  // OBJ's v runs up, glTF's down
        mTexcoords.push_back(uv);
    }
    void normal(std::string_view args) { mNormals.push_back(numbers<3>(args, 3, "vn")); }

    // Resolves a 1-based (or negative, relative) OBJ index against `count` elements.
    std::int64_t resolve(std::string_view token, std::size_t count, const char* what, bool& valid) {
        std::int64_t index = 0;
        const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), index);
        if (ec == std::errc::result_out_of_range) {
            valid = false;
            return 0;
        }
        if (ec != std::errc() || end != token.data() + token.size())
            fail(std::string("bad ") + what + " index '" + std::string(token.substr(0, 40)) + "'");
        if (index == 0) fail(std::string(what) + " index 0 (OBJ indices start at 1)");
        const std::int64_t resolved = index > 0 ? index - 1 : std::int64_t(count) + index;
        if (resolved < 0 || resolved >= std::int64_t(count)) valid = false;
        return resolved;
    }

    void face(std::string_view args) {
        mCorners.clear();
        bool valid = true;
        std::string badIndex;
        for (std::string_view token = nextToken(args); !token.empty(); token = nextToken(args)) {
            Corner corner;
            const std::size_t slash1 = token.find('/');
            const std::string_view vToken = token.substr(0, slash1);
            bool ok = true;
            corner.v = resolve(vToken, mPositions.size(), "vertex", ok);
            if (!ok && badIndex.empty()) badIndex = "vertex index " + std::string(vToken.substr(0, 40));
            valid &= ok;
            corner.vt = corner.vn = -1;
            if (slash1 != std::string_view::npos) {
                std::string_view tail = token.substr(slash1 + 1);
                const std::size_t slash2 = tail.find('/');
                const std::string_view vtToken = tail.substr(0, slash2);
                if (!vtToken.empty()) {
                    ok = true;
                    corner.vt = resolve(vtToken, mTexcoords.size(), "texture coordinate", ok);
                    if (!ok && badIndex.empty()) badIndex = "texture coordinate index " + std::string(vtToken.substr(0, 40));
                    valid &= ok;
                }
                if (slash2 != std::string_view::npos) {
                    const std::string_view vnToken = tail.substr(slash2 + 1);
                    if (!vnToken.empty()) {
                        ok = true;
                        corner.vn = resolve(vnToken, mNormals.size(), "normal", ok);
                        if (!ok && badIndex.empty()) badIndex = "normal index " + std::string(vnToken.substr(0, 40));
                        valid &= ok;
                    }
                }
            }
            mCorners.push_back(corner);
        }
        if (mCorners.size() < 3) fail("face with fewer than 3 vertices");
        const std::size_t newTriangles = mCorners.size() - 2;
        if (!valid) {
            if (!mOptions.dropInvalidFaces) fail(badIndex + " out of range");
            mOut.repairs.invalidIndexFaces += newTriangles;
            return;
        }
        if (mOut.triangles.size() + newTriangles > mOptions.maxTriangles)
            fail("more than " + std::to_string(mOptions.maxTriangles) + " triangles (see --max-triangles)");
        // A fan: OBJ polygons are meant convex (OpenMesh and most tools triangulate the same way).
        std::uint32_t first = vertexFor(mCorners[0]);
        std::uint32_t previous = vertexFor(mCorners[1]);
        for (std::size_t i = 2; i < mCorners.size(); ++i) {
            const std::uint32_t current = vertexFor(mCorners[i]);
            mOut.triangles.push_back({first, previous, current});
            mOut.triangleMaterials.push_back(currentMaterial());
            mOut.triangleGroups.push_back(mGroup);
            previous = current;
        }
        mOut.polygonTriangles.push_back(std::uint32_t(newTriangles));
    }

    // The output vertex of a corner: one per distinct (v, vt, vn), numbered by first use. Most
    // corners repeat their position's first corner, so a table by position index answers them
    // without hashing; the map holds only the other (vt, vn) pairs of a position.
    std::uint32_t vertexFor(const Corner& corner) {
        if (std::size_t(corner.v) >= mFirstCorner.size()) mFirstCorner.resize(mPositions.size());
        FirstCorner& first = mFirstCorner[std::size_t(corner.v)];
        if (first.vertex == kNoVertex) {
            first = {newVertex(corner), corner.vt, corner.vn};
            return first.vertex;
        }
        if (first.vt == corner.vt && first.vn == corner.vn) return first.vertex;
        const auto [it, inserted] = mVertexIndex.try_emplace(corner, kNoVertex);
        if (inserted) it->second = newVertex(corner);
        return it->second;
    }

    std::uint32_t newVertex(const Corner& corner) {
        if (mOut.positions.size() >= std::numeric_limits<std::uint32_t>::max() - 1) fail("more than 2^32 vertices");
        mOut.positions.push_back(mPositions[std::size_t(corner.v)]);
        if (corner.vn >= 0) mAnyNormal = true;
        if (corner.vt >= 0) mAnyUv = true;
        mOut.normals.push_back(corner.vn >= 0 ? mNormals[std::size_t(corner.vn)] : Eigen::Vector3f::Zero());
        mOut.uvs.push_back(corner.vt >= 0 ? mTexcoords[std::size_t(corner.vt)] : Eigen::Vector2f::Zero());
        return std::uint32_t(mOut.positions.size() - 1);
    }

    std::uint32_t currentMaterial() {
        if (mMaterial < 0) {
            if (mDefaultMaterial < 0) {
                mDefaultMaterial = int(mOut.materials.size());
                mOut.materials.emplace_back();
            }
            return std::uint32_t(mDefaultMaterial);
        }
        return std::uint32_t(mMaterial);
    }

    void useMaterial(std::string_view name) {
        const auto it = mMaterialByName.find(std::string(name));
        if (it == mMaterialByName.end()) {
            if (!name.empty() && mOut.warnings.size() < 50)
                mOut.warnings.push_back("line " + std::to_string(mLine) + ": unknown material '" +
                                        std::string(name.substr(0, 80)) + "'");
            // Kept under its name with the default colour: a base mesh's faces are given their
            // texels by it (scene `texels`), with or without a material library.
            mMaterial = name.empty() ? -1 : int(mOut.materials.size());
            if (mMaterial >= 0) {
                mOut.materials.emplace_back().name = std::string(name);
                mMaterialByName.emplace(std::string(name), mMaterial);
            }
        } else {
            mMaterial = it->second;
        }
    }

    // `g name…`: the faces that follow are in that group (none for a bare `g`).
    void useGroup(std::string_view name) {
        if (name.empty()) {
            mGroup = kNoGroup;
            return;
        }
        const auto [it, inserted] = mGroupByName.try_emplace(std::string(name), std::uint32_t(mOut.groups.size()));
        if (inserted) mOut.groups.emplace_back(name);
        mGroup = it->second;
    }

    void loadMaterialLibraries(std::string_view names) {
        // Most files name one library; names with spaces exist too, so try the whole rest of
        // the line first, then each token.
        if (!loadMaterialLibrary(names)) {
            std::string_view rest = names;
            for (std::string_view token = nextToken(rest); !token.empty(); token = nextToken(rest))
                if (token != names) loadMaterialLibrary(token);
        }
    }

    // Resolves a file named in the OBJ or MTL inside the input's folder; empty when refused.
    // Windows separators are normal in MTL files (`map_Kd .\wal67ar_small.jpg`, assimp's
    // spider): read as '/', so that `..\` parts are refused like `../` ones.
    fs::path containedPath(std::string_view name) {
        if (mRoot.empty() || name.empty()) return {};
        std::string portable(name);
        std::replace(portable.begin(), portable.end(), '\\', '/');
        const fs::path relative{portable};
        if (relative.is_absolute()) return {};
        for (const auto& part : relative)
            if (part == "..") return {};
        const fs::path candidate = mRoot / relative;
        return isContainedRegularFile(mRoot, candidate) ? candidate : fs::path{};
    }

    bool loadMaterialLibrary(std::string_view name) {
        const fs::path path = containedPath(name);
        if (path.empty()) {
            if (mOut.warnings.size() < 50)
                mOut.warnings.push_back("material library '" + std::string(name.substr(0, 80)) +
                                        "' not found inside the input's folder; ignored");
            return false;
        }
        std::string text;
        try {
            text = readInputFile(path, mOptions.maxFileBytes, "file");
        } catch (const InputError& e) {
            mOut.warnings.push_back(std::string("material library ignored: ") + e.what());
            return false;
        }
        int current = -1;
        std::string_view rest = text;
        while (!rest.empty()) {
            const std::size_t end = rest.find('\n');
            std::string_view line = rest.substr(0, end);
            rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end + 1);
            if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
            line = trim(line);
            std::string_view args = line;
            const std::string_view keyword = nextToken(args);
            if (keyword == "newmtl") {
                const std::string materialName(trim(args));
                auto [it, inserted] = mMaterialByName.try_emplace(materialName, int(mOut.materials.size()));
                if (inserted) mOut.materials.emplace_back().name = materialName;
                current = it->second;
            } else if (current >= 0 && keyword == "Kd") {
                Eigen::Vector3f kd = Eigen::Vector3f::Ones();
                for (int i = 0; i < 3; ++i) {
                    const auto value = parseDecimal<float>(nextToken(args));
                    if (!value || !std::isfinite(*value)) break;
                    kd[i] = std::clamp(*value, 0.0f, 1.0f);
                }
                mOut.materials[std::size_t(current)].baseColorFactor.head<3>() = kd;
            } else if (current >= 0 && keyword == "d") {
                if (const auto value = parseDecimal<float>(nextToken(args)); value && std::isfinite(*value))
                    mOut.materials[std::size_t(current)].baseColorFactor[3] = std::clamp(*value, 0.0f, 1.0f);
            } else if (current >= 0 && keyword == "map_Kd") {
                // Options (-o, -s, ...) come first; the file name is the last token.
                std::string_view last, token, more = args;
                while (!(token = nextToken(more)).empty()) last = token;
                mOut.materials[std::size_t(current)].baseColorTexture = loadTexture(last);
            }
        }
        return true;
    }

    int loadTexture(std::string_view name) {
        const std::string key(name);
        if (auto it = mTextureByName.find(key); it != mTextureByName.end()) return it->second;
        int index = -1;
        const fs::path path = containedPath(name);
        std::string why = "not found inside the input's folder";
        if (!path.empty()) {
            try {
                const std::string bytes = readInputFile(path, mOptions.maxFileBytes, "file");
                if (auto image = decodeImage(bytes, mOptions, why)) {
                    index = int(mOut.textures.size());
                    mOut.textures.push_back(std::move(*image));
                }
            } catch (const InputError& e) {
                why = e.what();
            }
        }
        if (index < 0 && mOut.warnings.size() < 50)
            mOut.warnings.push_back("texture '" + key.substr(0, 80) + "': " + why + "; ignored");
        mTextureByName[key] = index;
        return index;
    }

    std::string_view mText;
    fs::path mFile;
    fs::path mRoot;
    const IngestOptions& mOptions;
    RawMesh mOut;
    std::size_t mLine = 0;
    std::vector<Eigen::Vector3f> mPositions;
    std::vector<Eigen::Vector2f> mTexcoords;
    std::vector<Eigen::Vector3f> mNormals;
    std::vector<Corner> mCorners;
    // Per position index, the output vertex of its first corner and that corner's vt, vn.
    static constexpr std::uint32_t kNoVertex = 0xffffffffu;
    struct FirstCorner {
        std::uint32_t vertex = kNoVertex;
        std::int64_t vt = -1, vn = -1;
    };
    std::vector<FirstCorner> mFirstCorner;
    std::unordered_map<Corner, std::uint32_t, CornerHash> mVertexIndex;  // the other corners
    std::unordered_map<std::string, int> mMaterialByName;
    std::unordered_map<std::string, int> mTextureByName;
    std::unordered_map<std::string, std::uint32_t> mGroupByName;
    std::uint32_t mGroup = kNoGroup;
    int mMaterial = -1;
    int mDefaultMaterial = -1;
    bool mAnyNormal = false;
    bool mAnyUv = false;
    std::size_t mSkippedPrimitives = 0;
};

}  // namespace

RawMesh readObj(std::string_view text, const fs::path& file, const fs::path& directory, const IngestOptions& options) {
    if (text.empty()) throw InputError(file, "empty file");
    // UTF-16 files (a byte-order mark) are not OBJ as any tool reads it.
    if (text.size() >= 2 && ((text[0] == '\xFF' && text[1] == '\xFE') || (text[0] == '\xFE' && text[1] == '\xFF')))
        throw InputError(file, "UTF-16 text is not supported (convert the OBJ to UTF-8)");
    return ObjParser(text, file, directory, options).parse();
}

}  // namespace vtex::ingest::detail
