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
#include "ply_transcode.h"
#include "text_tokens.h"

#include <vtex/core/error.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <cstring>
#include <sstream>

namespace vtex::ingest::detail {
namespace {

namespace fs = std::filesystem;
using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<>;

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
struct OffHeader {
    bool hasNormals = false;
    std::uint64_t vertices = 0, faces = 0;
};

// Line by line: the keyword ([ST][C][N]OFF) alone on the first line, then exactly three counts
// on one line (the fuzzer found that "OFF 0 0" made two readers disagree).
OffHeader readOffHeader(Tokens& tokens, std::size_t fileBytes, const fs::path& file, const IngestOptions& options) {
    Tokens magicLine(tokens.line());
    const std::string_view magic = magicLine.next();
    if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
        throw InputError(file, "not an OFF file (no OFF keyword)");
    if (magic.find('n') != std::string_view::npos || magic.find('4') != std::string_view::npos)
        throw InputError(file, "nOFF and 4OFF (higher-dimensional) files are not supported");
    std::string_view prefix = magic.substr(0, magic.size() - 3);
    if (prefix.substr(0, 2) == "ST") prefix.remove_prefix(2);
    if (prefix.substr(0, 1) == "C") prefix.remove_prefix(1);
    OffHeader header;
    header.hasNormals = prefix == "N";
    if (!prefix.empty() && !header.hasNormals) throw InputError(file, "not an OFF file (keyword '" + std::string(magic.substr(0, 40)) + "')");
    const std::string_view extra = magicLine.next();
    if (extra == "BINARY") throw InputError(file, "binary OFF is not supported");
    if (!extra.empty()) throw InputError(file, "OFF header: the keyword must be alone on its line");
    Tokens countLine(tokens.line());
    std::uint64_t edges = 0;
    if (!parseCount(countLine.next(), header.vertices) || !parseCount(countLine.next(), header.faces) ||
        !parseCount(countLine.next(), edges) || !countLine.next().empty())
        throw InputError(file, "OFF header: bad vertex/face/edge counts");
    // Each vertex takes at least "0 0 0\n" (6 bytes), each face "3 0 0 0\n" (8 bytes).
    const std::uint64_t available = fileBytes, vertices = header.vertices, faces = header.faces;
    if (vertices > available / 6 || faces > available / 8 || vertices * 6 + faces * 8 > available)
        throw InputError(file, "OFF header claims " + std::to_string(vertices) + " vertices and " +
                                   std::to_string(faces) + " faces, more than the file's " +
                                   std::to_string(available) + " bytes can hold");
    if (faces > options.maxTriangles)
        throw InputError(file, "more than " + std::to_string(options.maxTriangles) + " faces (see --max-triangles)");
    return header;
}

// A vertex line: x y z, then nx ny nz for NOFF, then anything numeric (a colour, texture
// coordinates), which is not kept.
void readOffVertices(Tokens& tokens, const OffHeader& header, const fs::path& file, RawMesh& out) {
    out.positions.reserve(header.vertices);
    if (header.hasNormals) out.normals.reserve(header.vertices);
    const int wanted = header.hasNormals ? 6 : 3;
    for (std::uint64_t v = 0; v < header.vertices; ++v) {
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
                                       (header.hasNormals ? " numbers (NOFF: a position and a normal)" : " coordinates"));
        out.positions.emplace_back(values[0], values[1], values[2]);
        if (header.hasNormals) out.normals.emplace_back(values[3], values[4], values[5]);
    }
}

// A face line: a corner count, that many vertex indices in range, then numbers (a colour).
void readOffFaces(Tokens& tokens, const OffHeader& header, const fs::path& file, const IngestOptions& options,
                  RawMesh& out) {
    std::vector<std::uint32_t> corners;
    for (std::uint64_t f = 0; f < header.faces; ++f) {
        std::string_view record = tokens.line();
        if (record.empty() && tokens.done()) throw InputError(file, "truncated OFF: missing faces");
        Tokens face(record);
        std::uint64_t count = 0;
        if (!parseCount(face.next(), count))
            throw InputError(file, "OFF face " + std::to_string(f) + ": bad corner count");
        if (count > header.vertices || count > record.size())
            throw InputError(file, "OFF face " + std::to_string(f) + " claims " + std::to_string(count) +
                                       " corners, more than the file holds");
        corners.clear();
        for (std::uint64_t k = 0; k < count; ++k) {
            std::uint64_t index = 0;
            if (!parseCount(face.next(), index) || index >= header.vertices)
                throw InputError(file, "OFF face " + std::to_string(f) + ": bad or out-of-range vertex index");
            corners.push_back(std::uint32_t(index));
        }
        for (std::string_view t = face.next(); !t.empty(); t = face.next())
            if (!parseDecimal<float>(t)) throw InputError(file, "OFF face " + std::to_string(f) + ": bad number '" + std::string(t.substr(0, 40)) + "'");
        appendFan(out, corners, file, options);
    }
}

RawMesh readOff(std::string_view bytes, const fs::path& file, const IngestOptions& options) {
    Tokens tokens(bytes);
    const OffHeader header = readOffHeader(tokens, bytes.size(), file, options);
    RawMesh out;
    out.format = "off";
    readOffVertices(tokens, header, file, out);
    readOffFaces(tokens, header, file, options, out);
    if (out.triangles.empty()) throw InputError(file, "no faces");
    return out;
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
