// See input_file.h.
#include <vtex/core/input_file.h>

#include <vtex/core/error.h>

#include <algorithm>
#include <fstream>

namespace vtex {

std::uint64_t checkInputFile(const std::filesystem::path& file, std::uint64_t maxBytes, std::string_view what) {
    std::error_code error;
    const auto status = std::filesystem::status(file, error);
    if (error || !std::filesystem::exists(status)) throw InputError(file, "no such " + std::string(what));
    if (status.type() != std::filesystem::file_type::regular)
        throw InputError(file, std::string(what) + " is not a regular file");
    const auto size = std::filesystem::file_size(file, error);
    if (error) throw InputError(file, "cannot read: " + error.message());
    if (size > maxBytes)
        throw InputError(file, std::string(what) + " of " + std::to_string(size) + " bytes is larger than the " +
                                   std::to_string(maxBytes >> 20) + " MiB it may be");
    return size;
}

namespace {

// Reads `size` bytes (checkInputFile's answer) of `file` into `out`.
void readWhole(const std::filesystem::path& file, std::uint64_t size, char* out) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(file, "cannot open for reading");
    in.read(out, std::streamsize(size));
    if (std::uint64_t(in.gcount()) != size) throw IoError(file, "short read");
}

}  // namespace

std::string readInputFile(const std::filesystem::path& file, std::uint64_t maxBytes, std::string_view what) {
    const std::uint64_t size = checkInputFile(file, maxBytes, what);
    std::string bytes(size, '\0');
    readWhole(file, size, bytes.data());
    return bytes;
}

InputBytes readInputBytes(const std::filesystem::path& file, std::uint64_t maxBytes, std::string_view what) {
    const std::uint64_t size = checkInputFile(file, maxBytes, what);
    InputBytes bytes;
    bytes.data.reset(new char[std::max<std::uint64_t>(size, 1)]);  // not value-initialised: the read fills it
    bytes.size = std::size_t(size);
    readWhole(file, size, bytes.data.get());
    return bytes;
}

}  // namespace vtex
