#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace vtex::pipelines {

/// 128-bit XXH3 of `bytes`, as 32 hex digits: the cache keys and artifact checksums.
std::string hashBytes(std::string_view bytes);
/// hashBytes of a file's content, streamed. Throws vtex::InputError when it cannot be read.
std::string hashFile(const std::filesystem::path& file);

}  // namespace vtex::pipelines
