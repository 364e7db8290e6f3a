// OFF, PLY and STL through OpenMesh 9, behind a pre-check of what each header claims.
//
// OpenMesh's readers trust their headers: they reserve memory for the element counts an OFF
// or PLY header states and size a vector by each face's stated corner count. So before
// OpenMesh sees a byte, precheckOpenMeshInput() checks that the counts fit in the bytes
// present and walks the records that carry counts (OFF faces, PLY lists), bounding each by
// what the file can hold. Invalid vertex indices are skipped by OpenMesh's importer.
#include "detail.h"

#include <vtex/core/error.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <algorithm>
#include <charconv>
#include <cstring>
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
    std::size_t position() const { return mAt; }
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

void precheckOff(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
    // Line by line, as OpenMesh reads it: the keyword alone on the first line, then exactly
    // three counts (the fuzzer found that "OFF 0 0" made the two readers disagree on the counts).
    Tokens tokens(bytes);
    Tokens magicLine(tokens.line());
    const std::string_view magic = magicLine.next();
    if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
        throw InputError(file, "not an OFF file (no OFF keyword)");
    if (magic.find('n') != std::string_view::npos || magic.find('4') != std::string_view::npos)
        throw InputError(file, "nOFF and 4OFF (higher-dimensional) files are not supported");
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
    // Every record is checked token by token: vertex lines hold numbers only; face lines a
    // corner count (which OpenMesh uses to size a vector), that many vertex indices in range,
    // then numbers (a colour). OpenMesh's ASCII OFF reader loops forever on a token it cannot
    // extract (found by the fuzzer), so it only ever sees records that passed this check.
    auto isNumber = [](std::string_view token) {
        double value;
        if (!token.empty() && token.front() == '+') token.remove_prefix(1);
        const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
        return (ec == std::errc() || ec == std::errc::result_out_of_range) && end == token.data() + token.size();
    };
    for (std::uint64_t v = 0; v < vertices; ++v) {
        const std::string_view record = tokens.line();
        if (record.empty() && tokens.done()) throw InputError(file, "truncated OFF: missing vertices");
        Tokens fields(record);
        int count = 0;
        for (std::string_view t = fields.next(); !t.empty(); t = fields.next(), ++count)
            if (!isNumber(t)) throw InputError(file, "OFF vertex " + std::to_string(v) + ": bad number '" + std::string(t.substr(0, 40)) + "'");
        if (count < 3) throw InputError(file, "OFF vertex " + std::to_string(v) + ": fewer than 3 coordinates");
    }
    std::uint64_t triangles = 0;
    for (std::uint64_t f = 0; f < faces; ++f) {
        std::string_view record = tokens.line();
        if (record.empty() && tokens.done()) throw InputError(file, "truncated OFF: missing faces");
        Tokens face(record);
        std::uint64_t corners = 0;
        if (!parseCount(face.next(), corners))
            throw InputError(file, "OFF face " + std::to_string(f) + ": bad corner count");
        if (corners > vertices || corners > record.size())
            throw InputError(file, "OFF face " + std::to_string(f) + " claims " + std::to_string(corners) +
                                       " corners, more than the file holds");
        for (std::uint64_t k = 0; k < corners; ++k) {
            std::uint64_t index = 0;
            if (!parseCount(face.next(), index) || index >= vertices)
                throw InputError(file, "OFF face " + std::to_string(f) + ": bad or out-of-range vertex index");
        }
        for (std::string_view t = face.next(); !t.empty(); t = face.next())
            if (!isNumber(t)) throw InputError(file, "OFF face " + std::to_string(f) + ": bad number '" + std::string(t.substr(0, 40)) + "'");
        triangles += corners >= 3 ? corners - 2 : 0;
        if (triangles > options.maxTriangles)
            throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " triangles (see --max-triangles)");
    }
}

int plyTypeSize(std::string_view type) {
    if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
    if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
    if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
        type == "float32")
        return 4;
    if (type == "double" || type == "float64") return 8;
    return 0;
}

struct PlyProperty {
    int size = 0;       // scalar size, or list item size
    int countSize = 0;  // 0 for a scalar
    std::string countType;
};
struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

std::uint64_t readPlyCount(const unsigned char* p, int size, bool bigEndian, std::string_view type) {
    unsigned char b[4] = {0, 0, 0, 0};
    std::memcpy(b, p, std::size_t(size));
    if (bigEndian) std::reverse(b, b + size);
    if (size == 1) return (type == "char" || type == "int8") ? std::uint64_t(std::int8_t(b[0]) < 0 ? ~0ull : b[0]) : b[0];
    if (size == 2) {
        std::uint16_t v;
        std::memcpy(&v, b, 2);
        if ((type == "short" || type == "int16") && std::int16_t(v) < 0) return ~0ull;
        return v;
    }
    std::uint32_t v;
    std::memcpy(&v, b, 4);
    if ((type == "int" || type == "int32") && std::int32_t(v) < 0) return ~0ull;
    return v;
}

// Returns the file with its header rewritten canonically (known lines only, '\n' endings):
// OpenMesh never parses the original header.
std::string precheckPly(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
    // OpenMesh's PLY header parser loops forever on a header it does not expect (the fuzzer
    // found two: a stray line with '\r', and "end_header" glued to a property name). So the
    // header is held to the grammar here (printable ASCII, known keywords with their token
    // counts, "end_header" alone on its line), lines that are not PLY keywords are dropped
    // as comments (Blender 2.4 wrote such lines), and OpenMesh reads the rewritten header.
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
    std::size_t dataStart = bytes.find('\n', headerEnd) + 1;
    std::string format;
    std::vector<PlyElement> elements;
    std::string canonical;
    std::string_view header = bytes.substr(0, headerEnd);
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
        const bool known = keyword == "ply" || keyword == "format" || keyword == "comment" || keyword == "obj_info" ||
                           keyword == "element" || keyword == "property";
        if (!known) continue;
        if (keyword != "comment" && keyword != "obj_info") {
            for (const auto& t : tokens) canonical.append(t).push_back(' ');
            canonical.back() = '\n';
        }
        const bool ok = keyword == "ply" ? tokens.size() == 1
                      : keyword == "format" ? tokens.size() == 3
                      : keyword == "comment" || keyword == "obj_info" ? true
                      : keyword == "element" ? tokens.size() == 3
                      : keyword == "property" ? (tokens.size() == 3 || (tokens.size() == 5 && tokens[1] == "list"))
                      : false;
        if (!ok) throw InputError(file, "PLY header: malformed line '" + std::string(trimmed(text).substr(0, 40)) + "'");
        Tokens rest(text);
        rest.next();
        if (keyword == "format") {
            format = std::string(rest.next());
            // OpenMesh loops on a version it cannot parse (found by the fuzzer).
            if (rest.next() != "1.0") throw InputError(file, "PLY header: format version must be 1.0");
        } else if (keyword == "element") {
            PlyElement element;
            element.name = std::string(rest.next());
            if (!parseCount(rest.next(), element.count)) throw InputError(file, "PLY header: bad element count");
            elements.push_back(element);
        } else if (keyword == "property") {
            if (elements.empty()) throw InputError(file, "PLY header: property before any element");
            PlyProperty property;
            const std::string_view type = rest.next();
            if (type == "list") {
                property.countType = std::string(rest.next());
                property.countSize = plyTypeSize(property.countType);
                property.size = plyTypeSize(rest.next());
                if (property.countSize == 0 || property.countSize == 8 || property.size == 0 ||
                    property.countType == "float" || property.countType == "float32")
                    throw InputError(file, "PLY header: bad list property types");
            } else {
                property.size = plyTypeSize(type);
                if (property.size == 0) throw InputError(file, "PLY header: unknown property type");
            }
            elements.back().properties.push_back(property);
        }
    }
    const bool ascii = format == "ascii";
    const bool little = format == "binary_little_endian";
    const bool big = format == "binary_big_endian";
    if (!ascii && !little && !big) throw InputError(file, "PLY header: unknown format '" + format + "'");

    // Every element record needs at least one byte per property (ascii: a digit and a space).
    const std::uint64_t available = bytes.size() - dataStart;
    std::uint64_t minimum = 0;
    for (const auto& element : elements) {
        std::uint64_t record = 0;
        for (const auto& p : element.properties) record += ascii ? 2 : std::uint64_t(p.countSize ? p.countSize : p.size);
        // A record takes at least a byte: an element of many empty records would only make the
        // walk below spin (found by the fuzzer: 10^12 records of no property).
        if (record == 0) {
            if (element.count > 0)
                throw InputError(file, "PLY header: element '" + element.name + "' has records but no properties");
            continue;
        }
        if (element.count > available / record || minimum + element.count * record > available)
            throw InputError(file, "PLY header claims " + std::to_string(element.count) + " '" + element.name +
                                       "' elements, more than the file's bytes can hold");
        minimum += element.count * record;
        if (element.name == "face" && element.count > options.maxTriangles)
            throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " faces (see --max-triangles)");
    }

    // Walk the records: every list's count must fit in what remains.
    if (ascii) {
        Tokens tokens(bytes.substr(dataStart));
        for (const auto& element : elements)
            for (std::uint64_t r = 0; r < element.count; ++r) {
                const std::string_view record = tokens.line();
                if (record.empty() && tokens.done())
                    throw InputError(file, "truncated PLY: missing '" + element.name + "' records");
                Tokens fields(record);
                for (const auto& p : element.properties) {
                    const std::string_view token = fields.next();
                    if (p.countSize == 0) continue;
                    std::uint64_t count = 0;
                    if (!parseCount(token, count) || count > record.size())
                        throw InputError(file, "PLY '" + element.name + "' record " + std::to_string(r) +
                                                   ": list count larger than its line");
                    for (std::uint64_t i = 0; i < count; ++i) fields.next();
                }
            }
        return canonical + "end_header\n" + std::string(bytes.substr(dataStart));
    }
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data()) + dataStart;
    std::uint64_t at = 0;
    for (const auto& element : elements)
        for (std::uint64_t r = 0; r < element.count; ++r)
            for (const auto& p : element.properties) {
                if (p.countSize == 0) {
                    if (available - at < std::uint64_t(p.size)) throw InputError(file, "truncated PLY data");
                    at += std::uint64_t(p.size);
                    continue;
                }
                if (available - at < std::uint64_t(p.countSize)) throw InputError(file, "truncated PLY data");
                const std::uint64_t count = readPlyCount(data + at, p.countSize, big, p.countType);
                at += std::uint64_t(p.countSize);
                if (count > (available - at) / std::uint64_t(p.size))
                    throw InputError(file, "PLY '" + element.name + "' record " + std::to_string(r) +
                                               ": list of " + std::to_string(count) + " items runs past the end");
                at += count * std::uint64_t(p.size);
            }
    return canonical + "end_header\n" + std::string(bytes.substr(dataStart));
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

std::string precheckOpenMeshInput(std::string_view bytes, const std::string& format, const fs::path& file,
                                  const IngestOptions& options) {
    if (bytes.empty()) throw InputError(file, "empty file");
    if (format == "off") precheckOff(bytes, file, options);
    else if (format == "ply") return precheckPly(bytes, file, options);
    else if (format == "stl") precheckStl(bytes, file, options);
    else throw InputError(file, "unknown format '" + format + "'");
    return std::string(bytes);
}

RawMesh readWithOpenMesh(std::string_view bytes, const std::string& format, const fs::path& file,
                         const IngestOptions& options) {
    const std::string checked = precheckOpenMeshInput(bytes, format, file, options);

    // OpenMesh reports through omerr()/omlog(); libraries never print.
    omerr().disable();
    omlog().disable();
    omout().disable();

    PolyMesh mesh;
    mesh.request_vertex_normals();
    OpenMesh::IO::Options readOptions = OpenMesh::IO::Options::VertexNormal;
    if (format == "stl" && isBinaryStl(bytes)) readOptions += OpenMesh::IO::Options::Binary;
    std::istringstream stream{checked};
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
    // OpenMesh leaves the VertexNormal option set (and the normals unset) when the file has
    // none, so ask the header: "NOFF"/"CNOFF"/..., or a PLY vertex property "nx".
    bool fileHasNormals = false;
    if (format == "off") {
        const std::string_view magic = bytes.substr(0, std::min<std::size_t>(bytes.find_first_of(" \t\r\n"), 8));
        fileHasNormals = magic.find('N') != std::string_view::npos;
    } else if (format == "ply") {
        const std::string_view header = bytes.substr(0, bytes.find("end_header"));
        fileHasNormals = header.find(" nx\n") != std::string_view::npos || header.find(" nx\r") != std::string_view::npos;
    }
    if (fileHasNormals && readOptions.check(OpenMesh::IO::Options::VertexNormal)) {
        out.normals.reserve(mesh.n_vertices());
        for (const auto vh : mesh.vertices()) {
            const auto& n = mesh.normal(vh);
            out.normals.emplace_back(n[0], n[1], n[2]);
        }
    }
    std::vector<std::uint32_t> corners;
    for (const auto fh : mesh.faces()) {
        corners.clear();
        for (const auto vh : mesh.fv_ccw_range(fh)) corners.push_back(std::uint32_t(vh.idx()));
        if (corners.size() < 3) continue;
        // fv_ccw_range runs in the face's own order (counter-clockwise around its normal).
        const std::size_t added = corners.size() - 2;
        if (out.triangles.size() + added > options.maxTriangles)
            throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " triangles (see --max-triangles)");
        for (std::size_t i = 1; i + 1 < corners.size(); ++i)
            out.triangles.push_back({corners[0], corners[i], corners[i + 1]});
        out.polygonTriangles.push_back(std::uint32_t(added));
    }
    if (out.triangles.empty()) throw InputError(file, "no faces");
    return out;
}

}  // namespace vtex::ingest::detail
