/// @file
/// @brief The one way vtex reads a file it was given: a regular file (links followed), not
/// larger than the reader's stated cap, read whole.
///
/// Why in one place: a FIFO handed as a pipeline or an image hung the reader, `/dev/zero` grew
/// it past 3 GB and a directory read as an empty pipeline (issue 14, item 3). Every reader calls
/// checkInputFile (readers that hand a file name to a library: OpenEXR, tinygltf) or
/// readInputFile.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace vtex {

/// Throws vtex::InputError naming `file` unless it is a regular file of at most `maxBytes`;
/// `what` names the kind of file in the message ("scene file", "pipeline file", …).
/// Returns its size.
std::uint64_t checkInputFile(const std::filesystem::path& file, std::uint64_t maxBytes, std::string_view what);

/// checkInputFile, then the whole file. Throws vtex::InputError, vtex::IoError.
std::string readInputFile(const std::filesystem::path& file, std::uint64_t maxBytes, std::string_view what);

/// A whole file's bytes in a buffer the read fills directly: a std::string is cleared first,
/// which for the large files the octree build reads (a 1024³ .vtl is 200 MB) is one more pass
/// over memory than the read itself.
struct InputBytes {
    std::unique_ptr<char[]> data;
    std::size_t size = 0;
    std::string_view view() const { return {data.get(), size}; }
};
/// readInputFile into an InputBytes. Throws vtex::InputError, vtex::IoError.
InputBytes readInputBytes(const std::filesystem::path& file, std::uint64_t maxBytes, std::string_view what);

}  // namespace vtex
