// OFF, PLY and STL: OFF read here, PLY and STL through OpenMesh 9 behind a check of every
// count the file claims.
//
// OpenMesh's readers trust their input: they reserve memory for the element counts a header
// states, size a vector by each face's stated corner count, and extract ASCII values with
// operator>> across line ends, carrying on after a failed extraction. So a PLY file is read
// whole here and handed to OpenMesh as a canonical binary PLY of just the values the mesh
// needs (transcodePly), an STL file's size is checked against its triangle count, and OFF,
// whose OpenMesh reader cannot be made safe from outside (see readOff), does not go through
// OpenMesh at all. Invalid PLY vertex indices are skipped by OpenMesh's importer.
#include "detail.h"

#include <vtex/core/error.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>

namespace vtex::ingest::detail {
namespace {

namespace fs = std::filesystem;
using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<>;

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// A cursor over whitespace-separated tokens that also knows about lines and '#' comments.
class Tokens {
public:
    explicit Tokens(std::string_view text) : mText(text) {}
    std::string_view next() {
        skip();
        std::size_t end = mAt;
        while (end < mText.size() && !isSpace(mText[end])) ++end;
        std::string_view token = mText.substr(mAt, end - mAt);
        mAt = end;
        return token;
    }
    // The rest of the current line, consumed (comments removed).
    std::string_view line() {
        while (true) {
            while (mAt < mText.size() && isSpace(mText[mAt])) ++mAt;
            std::size_t end = mText.find('\n', mAt);
            if (end == std::string_view::npos) end = mText.size();
            std::string_view l = mText.substr(mAt, end - mAt);
            mAt = std::min(end + 1, mText.size());
            if (const auto hash = l.find('#'); hash != std::string_view::npos) l = l.substr(0, hash);
            if (!l.empty() || mAt >= mText.size()) return l;
        }
    }
    bool done() {
        skip();
        return mAt >= mText.size();
    }

private:
    void skip() {
        while (mAt < mText.size()) {
            if (isSpace(mText[mAt])) ++mAt;
            else if (mText[mAt] == '#') {
                while (mAt < mText.size() && mText[mAt] != '\n') ++mAt;
            } else break;
        }
    }
    std::string_view mText;
    std::size_t mAt = 0;
};

std::string_view trimmed(std::string_view s) {
    while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
    return s;
}

bool parseCount(std::string_view token, std::uint64_t& value) {
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    return ec == std::errc() && end == token.data() + token.size();
}

// A polygon's fan from its first corner, as the OBJ reader makes it; polygons of fewer than
// three corners add nothing.
void appendFan(RawMesh& out, const std::vector<std::uint32_t>& corners, const fs::path& file,
               const IngestOptions& options) {
    if (corners.size() < 3) return;
    const std::size_t added = corners.size() - 2;
    if (out.triangles.size() + added > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " triangles (see --max-triangles)");
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) out.triangles.push_back({corners[0], corners[i], corners[i + 1]});
    out.polygonTriangles.push_back(std::uint32_t(added));
}

// OFF is read here, not by OpenMesh. OpenMesh's ASCII OFF reader extracts with operator>>
// across line ends and leaves a plain OFF face's colour on the stream, so "3 0 1 2 4000000000"
// made the next face 4·10⁹ corners long (out of memory); after a failed extraction ("nan") it
// carries on with the vertex count as every face's corner count. Read from a stream it also
// never parses the header line, so it ignores "NOFF" and "BINARY".
RawMesh readOff(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
    // Line by line: the keyword ([ST][C][N]OFF) alone on the first line, then exactly three
    // counts on one line (the fuzzer found that "OFF 0 0" made two readers disagree).
    Tokens tokens(bytes);
    Tokens magicLine(tokens.line());
    const std::string_view magic = magicLine.next();
    if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
        throw InputError(file, "not an OFF file (no OFF keyword)");
    if (magic.find('n') != std::string_view::npos || magic.find('4') != std::string_view::npos)
        throw InputError(file, "nOFF and 4OFF (higher-dimensional) files are not supported");
    std::string_view prefix = magic.substr(0, magic.size() - 3);
    if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
    if (prefix.substr(0, 1) == "C") prefix.remove_prefix(1);
    const bool hasNormals = prefix == "N";
    if (!prefix.empty() && !hasNormals) throw InputError(file, "not an OFF file (keyword '" + std::string(magic.substr(0, 40)) + "')");
    const std::string_view extra = magicLine.next();
    if (extra == "BINARY") throw InputError(file, "binary OFF is not supported");
    if (!extra.empty()) throw InputError(file, "OFF header: the keyword must be alone on its line");
    Tokens countLine(tokens.line());
    std::uint64_t vertices = 0, faces = 0, edges = 0;
    if (!parseCount(countLine.next(), vertices) || !parseCount(countLine.next(), faces) ||
        !parseCount(countLine.next(), edges) || !countLine.next().empty())
        throw InputError(file, "OFF header: bad vertex/face/edge counts");
    // Each vertex takes at least "0 0 0\n" (6 bytes), each face "3 0 0 0\n" (8 bytes).
    const std::uint64_t available = bytes.size();
    if (vertices > available / 6 || faces > available / 8 || vertices * 6 + faces * 8 > available)
        throw InputError(file, "OFF header claims " + std::to_string(vertices) + " vertices and " +
                                   std::to_string(faces) + " faces, more than the file's " +
                                   std::to_string(available) + " bytes can hold");
    if (faces > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " faces (see --max-triangles)");

    RawMesh out;
    out.format = "off";
    out.positions.reserve(vertices);
    if (hasNormals) out.normals.reserve(vertices);
    // A vertex line: x y z, then nx ny nz for NOFF, then anything numeric (a colour, texture
    // coordinates), which is not kept.
    const int wanted = hasNormals ? 6 : 3;
    for (std::uint64_t v = 0; v < vertices; ++v) {
        const std::string_view record = tokens.line();
        if (record.empty() && tokens.done()) throw InputError(file, "truncated OFF: missing vertices");
        Tokens fields(record);
        float values[6] = {0, 0, 0, 0, 0, 0};
        int count = 0;
        for (std::string_view t = fields.next(); !t.empty(); t = fields.next(), ++count) {
            const auto value = parseDecimal<float>(t);
            if (!value) throw InputError(file, "OFF vertex " + std::to_string(v) + ": bad number '" + std::string(t.substr(0, 40)) + "'");
            if (count < wanted) values[count] = *value;
        }
        if (count < wanted)
            throw InputError(file, "OFF vertex " + std::to_string(v) + ": fewer than " + std::to_string(wanted) +
                                       (hasNormals ? " numbers (NOFF: a position and a normal)" : " coordinates"));
        out.positions.emplace_back(values[0], values[1], values[2]);
        if (hasNormals) out.normals.emplace_back(values[3], values[4], values[5]);
    }
    // A face line: a corner count, that many vertex indices in range, then numbers (a colour).
    std::vector<std::uint32_t> corners;
    for (std::uint64_t f = 0; f < faces; ++f) {
        std::string_view record = tokens.line();
        if (record.empty() && tokens.done()) throw InputError(file, "truncated OFF: missing faces");
        Tokens face(record);
        std::uint64_t count = 0;
        if (!parseCount(face.next(), count))
            throw InputError(file, "OFF face " + std::to_string(f) + ": bad corner count");
        if (count > vertices || count > record.size())
            throw InputError(file, "OFF face " + std::to_string(f) + " claims " + std::to_string(count) +
                                       " corners, more than the file holds");
        corners.clear();
        for (std::uint64_t k = 0; k < count; ++k) {
            std::uint64_t index = 0;
            if (!parseCount(face.next(), index) || index >= vertices)
                throw InputError(file, "OFF face " + std::to_string(f) + ": bad or out-of-range vertex index");
            corners.push_back(std::uint32_t(index));
        }
        for (std::string_view t = face.next(); !t.empty(); t = face.next())
            if (!parseDecimal<float>(t)) throw InputError(file, "OFF face " + std::to_string(f) + ": bad number '" + std::string(t.substr(0, 40)) + "'");
        appendFan(out, corners, file, options);
    }
    if (out.triangles.empty()) throw InputError(file, "no faces");
    return out;
}

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

// What OpenMesh is given to read, and whether the file has vertex normals (OpenMesh leaves
// its VertexNormal option set, and the normals zero, when it has none).
struct OpenMeshInput {
    std::string bytes;
    bool hasNormals = false;
};

// Returns the mesh as a canonical binary PLY that OpenMesh reads without surprises: vertex
// x, y, z (and nx, ny, nz when all three are there) as float32, then faces as an int32 count
// (OpenMesh takes no unsigned count type) and int32 indices, -1 for an index that names no
// vertex (OpenMesh skips such faces).
//
// OpenMesh's PLY reader cannot be given the file itself. Its header parser loops forever on a
// header it does not expect (the fuzzer found a stray line with '\r', "end_header" glued to a
// property name, an unparsable version). Its ASCII body reader extracts values with
// operator>> in whatever order its property table says, reads a list other than the face
// indices as one token, and keeps going after a failed extraction; so one token out of place
// became a face's corner count and a loop of 4·10⁹ push_backs (fuzzer, found in CI). So every
// value is read and checked here, in the file's order, and OpenMesh only sees what was
// checked. Header lines that are not PLY keywords are dropped as comments (Blender 2.4 wrote
// such lines).
OpenMeshInput transcodePly(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
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
    const std::size_t dataStart = bytes.find('\n', headerEnd) + 1;
    std::string format;
    std::vector<PlyElement> elements;
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
            format = std::string(tokens[1]);
            if (tokens[2] != "1.0") throw InputError(file, "PLY header: format version must be 1.0");
        } else if (keyword == "element") {
            PlyElement element;
            element.name = std::string(tokens[1]);
            if (!parseCount(tokens[2], element.count)) throw InputError(file, "PLY header: bad element count");
            elements.push_back(element);
        } else if (keyword == "property") {
            if (elements.empty()) throw InputError(file, "PLY header: property before any element");
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
            elements.back().properties.push_back(property);
        }
    }
    const bool ascii = format == "ascii";
    const bool little = format == "binary_little_endian";
    const bool big = format == "binary_big_endian";
    if (!ascii && !little && !big) throw InputError(file, "PLY header: unknown format '" + format + "'");

    // Every record takes at least a byte per property (ascii: a digit and a space), so the
    // counts the header claims can be checked before anything is allocated for them.
    const std::uint64_t available = bytes.size() - dataStart;
    std::uint64_t minimum = 0;
    const PlyElement* vertices = nullptr;
    const PlyElement* faces = nullptr;
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
        const PlyElement** role = element.name == "vertex" ? &vertices : element.name == "face" ? &faces : nullptr;
        if (role && *role) throw InputError(file, "PLY header: two '" + element.name + "' elements");
        if (role) *role = &element;
    }
    if (faces && faces->count > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " faces (see --max-triangles)");

    // Where each value the mesh needs sits in its record.
    auto find = [](const PlyElement* element, std::initializer_list<std::string_view> names) -> int {
        if (!element) return -1;
        for (std::size_t i = 0; i < element->properties.size(); ++i)
            for (const auto name : names)
                if (element->properties[i].name == name) return int(i);
        return -1;
    };
    int coordinate[6];
    const char* coordinateNames[6] = {"x", "y", "z", "nx", "ny", "nz"};
    for (int c = 0; c < 6; ++c) {
        coordinate[c] = find(vertices, {coordinateNames[c]});
        if (coordinate[c] >= 0 && vertices->properties[std::size_t(coordinate[c])].isList())
            throw InputError(file, std::string("PLY header: vertex property '") + coordinateNames[c] + "' is a list");
    }
    if (vertices && vertices->count > 0 && (coordinate[0] < 0 || coordinate[1] < 0 || coordinate[2] < 0))
        throw InputError(file, "PLY header: vertices without x, y and z");
    const bool hasNormals = coordinate[3] >= 0 && coordinate[4] >= 0 && coordinate[5] >= 0;
    const int cornerList = find(faces, {"vertex_indices", "vertex_index"});
    if (faces && faces->count > 0) {
        if (cornerList < 0 || !faces->properties[std::size_t(cornerList)].isList())
            throw InputError(file, "PLY header: faces without a vertex_indices list");
        if (!plyIsInteger(faces->properties[std::size_t(cornerList)].type))
            throw InputError(file, "PLY header: vertex_indices must hold integers");
    }
    const std::uint64_t vertexCount = vertices ? vertices->count : 0;
    const std::uint64_t faceCount = faces ? faces->count : 0;

    std::string body;
    std::string faceBody;
    PlyValues values(bytes.substr(dataStart), ascii, big, file);
    std::uint64_t triangles = 0;
    std::vector<std::int64_t> corners;
    for (const auto& element : elements) {
        const bool isVertex = &element == vertices;
        const bool isFace = &element == faces;
        for (std::uint64_t r = 0; r < element.count; ++r) {
            values.at(element.name, r);
            float vertex[6] = {0, 0, 0, 0, 0, 0};
            for (std::size_t i = 0; i < element.properties.size(); ++i) {
                const PlyProperty& p = element.properties[i];
                if (!p.isList()) {
                    const double value = values.next(p.type);
                    if (isVertex)
                        for (int c = 0; c < 6; ++c)
                            if (coordinate[c] == int(i)) vertex[c] = toFloat(value);
                    continue;
                }
                const std::uint64_t n = values.listCount(p.count, p.type);
                const bool isCorners = isFace && int(i) == cornerList;
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
                    appendLittleEndian(faceBody, std::int32_t(n));
                    for (const std::int64_t c : corners) appendLittleEndian(faceBody, std::int32_t(c));
                }
            }
            if (isVertex)
                for (int c = 0; c < (hasNormals ? 6 : 3); ++c) appendLittleEndian(body, vertex[c]);
        }
    }
    std::string canonical = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertexCount) +
                            "\nproperty float x\nproperty float y\nproperty float z\n";
    if (hasNormals) canonical += "property float nx\nproperty float ny\nproperty float nz\n";
    canonical += "element face " + std::to_string(faceCount) + "\nproperty list int int vertex_indices\nend_header\n";
    return {canonical + body + faceBody, hasNormals};
}

// Binary STL: an 80-byte header, a 32-bit triangle count, 50 bytes per triangle, exactly.
bool isBinaryStl(std::string_view bytes) {
    if (bytes.size() < 84) return false;
    std::uint32_t count;
    std::memcpy(&count, bytes.data() + 80, 4);
    return 84 + std::uint64_t(count) * 50 == bytes.size();
}

void precheckStl(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
    if (bytes.size() < 15) throw InputError(file, "truncated STL");
    if (isBinaryStl(bytes)) {
        if ((bytes.size() - 84) / 50 > options.maxTriangles)
            throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " triangles (see --max-triangles)");
        return;
    }
    // Anything else must be ASCII STL, which starts with "solid". (The fuzzer found that text
    // handed to OpenMesh's binary reader makes it loop over a count read from the text.)
    if (bytes.substr(0, 5) != "solid")
        throw InputError(file, "neither an ASCII STL (no 'solid') nor a binary STL (size does not match its triangle count)");
}

}  // namespace

RawMesh readOffPlyStl(std::string_view bytes, const std::string& format, const fs::path& file,
                      const IngestOptions& options) {
    if (bytes.empty()) throw InputError(file, "empty file");
    if (format == "off") return readOff(bytes, file, options);
    OpenMeshInput input;
    if (format == "ply") input = transcodePly(bytes, file, options);
    else if (format == "stl") {
        precheckStl(bytes, file, options);
        input.bytes = bytes;
    } else throw InputError(file, "unknown format '" + format + "'");

    // OpenMesh reports through omerr()/omlog(); libraries never print.
    omerr().disable();
    omlog().disable();
    omout().disable();

    PolyMesh mesh;
    mesh.request_vertex_normals();
    OpenMesh::IO::Options readOptions = OpenMesh::IO::Options::VertexNormal;
    if (format == "stl" && isBinaryStl(bytes)) readOptions += OpenMesh::IO::Options::Binary;
    std::istringstream stream{std::move(input.bytes)};
    bool ok = false;
    try {
        ok = OpenMesh::IO::read_mesh(mesh, stream, "." + format, readOptions);
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(file, std::string("OpenMesh could not read it: ") + e.what());
    }
    if (!ok) throw InputError(file, "OpenMesh could not read it as " + format);

    RawMesh out;
    out.format = format;
    out.positions.reserve(mesh.n_vertices());
    for (const auto vh : mesh.vertices()) {
        const auto& p = mesh.point(vh);
        out.positions.emplace_back(p[0], p[1], p[2]);
    }
    if (input.hasNormals) {
        out.normals.reserve(mesh.n_vertices());
        for (const auto vh : mesh.vertices()) {
            const auto& n = mesh.normal(vh);
            out.normals.emplace_back(n[0], n[1], n[2]);
        }
    }
    std::vector<std::uint32_t> corners;
    for (const auto fh : mesh.faces()) {
        corners.clear();
        // fv_ccw_range runs in the face's own order (counter-clockwise around its normal).
        for (const auto vh : mesh.fv_ccw_range(fh)) corners.push_back(std::uint32_t(vh.idx()));
        appendFan(out, corners, file, options);
    }
    if (out.triangles.empty()) throw InputError(file, "no faces");
    return out;
}

}  // namespace vtex::ingest::detail
