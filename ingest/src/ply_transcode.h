// PLY for OpenMesh: a PLY file read and checked value by value, handed on as a canonical binary
// PLY of just what the mesh needs. Internal (openmesh_reader.cpp reads what this returns).
#pragma once

#include <vtex/ingest/ingest.h>

#include <filesystem>
#include <string>
#include <string_view>

namespace vtex::ingest::detail {

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
OpenMeshInput transcodePly(std::string_view bytes, const std::filesystem::path& file, const IngestOptions& options);

}  // namespace vtex::ingest::detail
