// See ply_transcode.h: every value of the PLY file read and checked in the file's order, so that
// OpenMesh only sees what was checked.
#include "ply_transcode.h"

#include "detail.h"
#include "text_tokens.h"

#include <vtex/core/error.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

namespace vtex::ingest::detail {
namespace {

namespace fs = std::filesystem;

enum class PlyScalar { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64, Invalid };

PlyScalar plyScalar(std::string_view type) {
    if (type == "char" || type == "int8") return PlyScalar::Int8;
    if (type == "uchar" || type == "uint8") return PlyScalar::UInt8;
    if (type == "short" || type == "int16") return PlyScalar::Int16;
    if (type == "ushort" || type == "uint16") return PlyScalar::UInt16;
    if (type == "int" || type == "int32") return PlyScalar::Int32;
    if (type == "uint" || type == "uint32") return PlyScalar::UInt32;
    if (type == "float" || type == "float32") return PlyScalar::Float32;
    if (type == "double" || type == "float64") return PlyScalar::Float64;
    return PlyScalar::Invalid;
}
int plySize(PlyScalar t) {
    switch (t) {
        case PlyScalar::Int8: case PlyScalar::UInt8: return 1;
        case PlyScalar::Int16: case PlyScalar::UInt16: return 2;
        case PlyScalar::Int32: case PlyScalar::UInt32: case PlyScalar::Float32: return 4;
        case PlyScalar::Float64: return 8;
        case PlyScalar::Invalid: break;
    }
    return 0;
}
bool plyIsInteger(PlyScalar t) { return t != PlyScalar::Float32 && t != PlyScalar::Float64; }
const char* plyName(PlyScalar t) {
    static constexpr const char* names[] = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64", "?"};
    return names[int(t)];
}

struct PlyProperty {
    std::string name;
    PlyScalar type = PlyScalar::Invalid;   // the scalar's type, or a list's item type
    PlyScalar count = PlyScalar::Invalid;  // a list's count type; Invalid for a scalar
    bool isList() const { return count != PlyScalar::Invalid; }
};
struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

// The values of a PLY body, one at a time, each checked against its declared type: ASCII
// tokens must be whole numbers of that type (an integer type's range included), binary
// values must be present. Errors name the element and record being read.
class PlyValues {
public:
    PlyValues(std::string_view body, bool ascii, bool bigEndian, const fs::path& file)
        : mBody(body), mAscii(ascii), mBig(bigEndian), mFile(file) {}

    void at(const std::string& element, std::uint64_t record) {
        mElement = &element;
        mRecord = record;
    }
    double next(PlyScalar type) { return mAscii ? nextToken(type) : nextBinary(type); }
    // A list's item count, bounded by the bytes left (an item takes at least one byte).
    std::uint64_t listCount(PlyScalar countType, PlyScalar itemType) {
        const double n = next(countType);
        if (n < 0) fail("negative list count");
        const std::uint64_t count = std::uint64_t(n);
        const std::uint64_t left = mBody.size() - mAt;
        if (count > left / std::uint64_t(mAscii ? 1 : plySize(itemType)))
            fail("list of " + std::to_string(count) + " items runs past the end");
        return count;
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(mFile, "PLY '" + *mElement + "' record " + std::to_string(mRecord) + ": " + what);
    }
    double nextToken(PlyScalar type) {
        while (mAt < mBody.size() && isSpace(mBody[mAt])) ++mAt;
        std::size_t end = mAt;
        while (end < mBody.size() && !isSpace(mBody[end])) ++end;
        std::string_view token = mBody.substr(mAt, end - mAt);
        mAt = end;
        if (token.empty()) fail("truncated (missing values)");
        const std::string_view shown = token.substr(0, 40);
        if (plyIsInteger(type)) {
            if (token.size() > 1 && token.front() == '+' && token[1] != '-') token.remove_prefix(1);
            std::int64_t value = 0;
            const auto [stop, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
            const std::int64_t bits = 8 * plySize(type);
            const bool isSigned = type == PlyScalar::Int8 || type == PlyScalar::Int16 || type == PlyScalar::Int32;
            const std::int64_t lo = isSigned ? -(std::int64_t(1) << (bits - 1)) : 0;
            const std::int64_t hi = isSigned ? (std::int64_t(1) << (bits - 1)) - 1 : (std::int64_t(1) << bits) - 1;
            if (ec != std::errc() || stop != token.data() + token.size() || value < lo || value > hi)
                fail("'" + std::string(shown) + "' does not read as " + plyName(type));
            return double(value);
        }
        // A float32 value is rounded once from the text, as OpenMesh's own reader did.
        std::optional<double> value;
        if (type != PlyScalar::Float32) value = parseDecimal<double>(token);
        else if (const auto single = parseDecimal<float>(token)) value = *single;
        if (!value) fail("'" + std::string(shown) + "' is not a number");
        return *value;
    }
    double nextBinary(PlyScalar type) {
        const int size = plySize(type);
        if (mBody.size() - mAt < std::size_t(size)) fail("truncated (the data ends inside it)");
        unsigned char b[8];
        std::memcpy(b, mBody.data() + mAt, std::size_t(size));
        mAt += std::size_t(size);
        if (mBig) std::reverse(b, b + size);
        auto load = [&b]<typename T>(T) {
            T v;
            std::memcpy(&v, b, sizeof(T));
            return double(v);
        };
        switch (type) {
            case PlyScalar::Int8: return load(std::int8_t{});
            case PlyScalar::UInt8: return load(std::uint8_t{});
            case PlyScalar::Int16: return load(std::int16_t{});
            case PlyScalar::UInt16: return load(std::uint16_t{});
            case PlyScalar::Int32: return load(std::int32_t{});
            case PlyScalar::UInt32: return load(std::uint32_t{});
            case PlyScalar::Float32: return load(float{});
            case PlyScalar::Float64: return load(double{});
            case PlyScalar::Invalid: break;
        }
        return 0;
    }

    std::string_view mBody;
    std::size_t mAt = 0;
    bool mAscii, mBig;
    const fs::path& mFile;
    const std::string* mElement = nullptr;
    std::uint64_t mRecord = 0;
};

// A double beyond float's range becomes ±inf (the cast itself would be undefined); the
// mesh's repair then refuses the coordinate by name.
float toFloat(double value) {
    if (value > double(std::numeric_limits<float>::max())) return std::numeric_limits<float>::infinity();
    if (value < -double(std::numeric_limits<float>::max())) return -std::numeric_limits<float>::infinity();
    return float(value);
}

template <typename T>
void appendLittleEndian(std::string& out, T value) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
}

// The header: its format and elements, and where the body starts. Lines that are not PLY
// keywords are dropped as comments (Blender 2.4 wrote such lines).
struct PlyHeader {
    std::string format;
    std::vector<PlyElement> elements;
    std::size_t dataStart = 0;
};
PlyHeader readPlyHeader(std::string_view bytes, const fs::path& file) {
    if (bytes.substr(0, 4) != "ply\n" && bytes.substr(0, 5) != "ply\r\n")
        throw InputError(file, "not a PLY file (no 'ply' magic line)");
    std::size_t headerEnd = std::string_view::npos;
    for (std::size_t at = bytes.find("\nend_header"); at != std::string_view::npos; at = bytes.find("\nend_header", at + 1)) {
        const std::size_t after = at + 11;
        if (after < bytes.size() && (bytes[after] == '\n' || (bytes[after] == '\r' && after + 1 < bytes.size() && bytes[after + 1] == '\n'))) {
            headerEnd = at + 1;
            break;
        }
    }
    if (headerEnd == std::string_view::npos) throw InputError(file, "PLY: no end_header line");
    PlyHeader out;
    out.dataStart = bytes.find('\n', headerEnd) + 1;
    const std::string_view header = bytes.substr(0, headerEnd);
    for (char c : header)
        if (!(c == '\n' || c == '\r' || c == '\t' || (c >= 0x20 && c < 0x7f)))
            throw InputError(file, "PLY header: not printable ASCII");
    for (std::size_t at = 0; at < header.size();) {
        std::size_t end = header.find('\n', at);
        if (end == std::string_view::npos) end = header.size();
        const std::string_view text = header.substr(at, end - at);
        at = end + 1;
        Tokens line(text);
        std::vector<std::string_view> tokens;
        for (std::string_view t = line.next(); !t.empty(); t = line.next()) tokens.push_back(t);
        if (tokens.empty()) continue;
        const std::string_view keyword = tokens[0];
        const bool ok = keyword == "ply" ? tokens.size() == 1
                      : keyword == "format" ? tokens.size() == 3
                      : keyword == "comment" || keyword == "obj_info" ? true
                      : keyword == "element" ? tokens.size() == 3
                      : keyword == "property" ? (tokens.size() == 3 || (tokens.size() == 5 && tokens[1] == "list"))
                      : true;  // not a keyword: a comment
        if (!ok) throw InputError(file, "PLY header: malformed line '" + std::string(trimmed(text).substr(0, 40)) + "'");
        if (keyword == "format") {
            out.format = std::string(tokens[1]);
            if (tokens[2] != "1.0") throw InputError(file, "PLY header: format version must be 1.0");
        } else if (keyword == "element") {
            PlyElement element;
            element.name = std::string(tokens[1]);
            if (!parseCount(tokens[2], element.count)) throw InputError(file, "PLY header: bad element count");
            out.elements.push_back(element);
        } else if (keyword == "property") {
            if (out.elements.empty()) throw InputError(file, "PLY header: property before any element");
            PlyProperty property;
            if (tokens.size() == 5) {  // "property list <count> <item> <name>"
                property.count = plyScalar(tokens[2]);
                property.type = plyScalar(tokens[3]);
                property.name = std::string(tokens[4]);
                if (property.type == PlyScalar::Invalid || !plyIsInteger(property.count))
                    throw InputError(file, "PLY header: bad list property types");
            } else {
                property.type = plyScalar(tokens[1]);
                property.name = std::string(tokens[2]);
                if (property.type == PlyScalar::Invalid) throw InputError(file, "PLY header: unknown property type");
            }
            out.elements.back().properties.push_back(property);
        }
    }
    return out;
}

// The vertex and face elements, after checking every element's claimed count against the bytes
// the body has: every record takes at least a byte per property (ascii: a digit and a space), so
// the counts are checked before anything is allocated for them.
struct PlyRoles {
    const PlyElement* vertices = nullptr;
    const PlyElement* faces = nullptr;
};
PlyRoles checkPlyCounts(const std::vector<PlyElement>& elements, bool ascii, std::uint64_t available, const fs::path& file,
                        const IngestOptions& options) {
    std::uint64_t minimum = 0;
    PlyRoles roles;
    for (const auto& element : elements) {
        std::uint64_t record = 0;
        for (const auto& p : element.properties) record += ascii ? 2 : std::uint64_t(plySize(p.isList() ? p.count : p.type));
        // An element of many empty records would only make the walk spin (found by the
        // fuzzer: 10^12 records of no property).
        if (record == 0) {
            if (element.count > 0)
                throw InputError(file, "PLY header: element '" + element.name + "' has records but no properties");
            continue;
        }
        if (element.count > available / record || minimum + element.count * record > available)
            throw InputError(file, "PLY header claims " + std::to_string(element.count) + " '" + element.name +
                                       "' elements, more than the file's bytes can hold");
        minimum += element.count * record;
        const PlyElement** role = element.name == "vertex" ? &roles.vertices : element.name == "face" ? &roles.faces : nullptr;
        if (role && *role) throw InputError(file, "PLY header: two '" + element.name + "' elements");
        if (role) *role = &element;
    }
    if (roles.faces && roles.faces->count > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " faces (see --max-triangles)");
    return roles;
}

// Where each value the mesh needs sits in its record: x, y, z, nx, ny, nz of a vertex (−1: not
// there) and a face's corner list.
struct PlyLayout {
    int coordinate[6];
    bool hasNormals;
    int cornerList;
};
PlyLayout locatePlyValues(const PlyRoles& roles, const fs::path& file) {
    const PlyElement* vertices = roles.vertices;
    const PlyElement* faces = roles.faces;
    auto find = [](const PlyElement* element, std::initializer_list<std::string_view> names) -> int {
        if (!element) return -1;
        for (std::size_t i = 0; i < element->properties.size(); ++i)
            for (const auto name : names)
                if (element->properties[i].name == name) return int(i);
        return -1;
    };
    PlyLayout out;
    int* coordinate = out.coordinate;  // x, y, z, nx, ny, nz
    const char* coordinateNames[6] = {"x", "y", "z", "nx", "ny", "nz"};
    for (int c = 0; c < 6; ++c) {
        coordinate[c] = find(vertices, {coordinateNames[c]});
        if (coordinate[c] >= 0 && vertices->properties[std::size_t(coordinate[c])].isList())
            throw InputError(file, std::string("PLY header: vertex property '") + coordinateNames[c] + "' is a list");
    }
    if (vertices && vertices->count > 0 && (coordinate[0] < 0 || coordinate[1] < 0 || coordinate[2] < 0))
        throw InputError(file, "PLY header: vertices without x, y and z");
    out.hasNormals = coordinate[3] >= 0 && coordinate[4] >= 0 && coordinate[5] >= 0;
    const int cornerList = out.cornerList = find(faces, {"vertex_indices", "vertex_index"});
    if (faces && faces->count > 0) {
        if (cornerList < 0 || !faces->properties[std::size_t(cornerList)].isList())
            throw InputError(file, "PLY header: faces without a vertex_indices list");
        if (!plyIsInteger(faces->properties[std::size_t(cornerList)].type))
            throw InputError(file, "PLY header: vertex_indices must hold integers");
    }
    return out;
}

// The body, value by value in the file's order: the vertices' coordinates (and normals) as
// float32, the faces as an int32 count and int32 indices (−1 for an index that names no vertex).
struct PlyBodies {
    std::string vertices, faces;
};
PlyBodies transcodePlyBody(std::string_view data, bool ascii, bool big, const std::vector<PlyElement>& elements,
                           const PlyRoles& roles, const PlyLayout& layout, const fs::path& file, const IngestOptions& options) {
    const std::uint64_t vertexCount = roles.vertices ? roles.vertices->count : 0;
    PlyBodies out;
    PlyValues values(data, ascii, big, file);
    std::uint64_t triangles = 0;
    std::vector<std::int64_t> corners;
    for (const auto& element : elements) {
        const bool isVertex = &element == roles.vertices;
        const bool isFace = &element == roles.faces;
        for (std::uint64_t r = 0; r < element.count; ++r) {
            values.at(element.name, r);
            float vertex[6] = {0, 0, 0, 0, 0, 0};
            for (std::size_t i = 0; i < element.properties.size(); ++i) {
                const PlyProperty& p = element.properties[i];
                if (!p.isList()) {
                    const double value = values.next(p.type);
                    if (isVertex)
                        for (int c = 0; c < 6; ++c)
                            if (layout.coordinate[c] == int(i)) vertex[c] = toFloat(value);
                    continue;
                }
                const std::uint64_t n = values.listCount(p.count, p.type);
                const bool isCorners = isFace && int(i) == layout.cornerList;
                if (isCorners) corners.clear();
                for (std::uint64_t k = 0; k < n; ++k) {
                    const double value = values.next(p.type);
                    if (isCorners) corners.push_back(value >= 0 && value < double(vertexCount) ? std::int64_t(value) : -1);
                }
                if (isCorners) {
                    triangles += n >= 3 ? n - 2 : 0;
                    if (triangles > options.maxTriangles)
                        throw InputError(file, "more than " + std::to_string(options.maxTriangles) +
                                                   " triangles (see --max-triangles)");
                    appendLittleEndian(out.faces, std::int32_t(n));
                    for (const std::int64_t c : corners) appendLittleEndian(out.faces, std::int32_t(c));
                }
            }
            if (isVertex)
                for (int c = 0; c < (layout.hasNormals ? 6 : 3); ++c) appendLittleEndian(out.vertices, vertex[c]);
        }
    }
    return out;
}

}  // namespace

OpenMeshInput transcodePly(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
    const PlyHeader header = readPlyHeader(bytes, file);
    const bool ascii = header.format == "ascii";
    const bool little = header.format == "binary_little_endian";
    const bool big = header.format == "binary_big_endian";
    if (!ascii && !little && !big) throw InputError(file, "PLY header: unknown format '" + header.format + "'");
    const PlyRoles roles = checkPlyCounts(header.elements, ascii, bytes.size() - header.dataStart, file, options);
    const PlyLayout layout = locatePlyValues(roles, file);
    const std::uint64_t vertexCount = roles.vertices ? roles.vertices->count : 0;
    const std::uint64_t faceCount = roles.faces ? roles.faces->count : 0;
    const PlyBodies bodies =
        transcodePlyBody(bytes.substr(header.dataStart), ascii, big, header.elements, roles, layout, file, options);
    std::string canonical = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertexCount) +
                            "\nproperty float x\nproperty float y\nproperty float z\n";
    if (layout.hasNormals) canonical += "property float nx\nproperty float ny\nproperty float nz\n";
    canonical += "element face " + std::to_string(faceCount) + "\nproperty list int int vertex_indices\nend_header\n";
    return {canonical + bodies.vertices + bodies.faces, layout.hasNormals};
}

}  // namespace vtex::ingest::detail
