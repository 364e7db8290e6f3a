/// @file
/// @brief The names an enum's values have on the command line and in files, in one table per
/// enum, so that the CLI's choices, a pipeline file's keys and the reports spell them alike.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace vtex {

template <class Enum, std::size_t N>
struct EnumNames {
    std::array<std::pair<Enum, std::string_view>, N> entries;

    constexpr std::string_view name(Enum value) const {
        for (const auto& [e, n] : entries)
            if (e == value) return n;
        return "?";
    }
    constexpr std::optional<Enum> parse(std::string_view text) const {
        for (const auto& [e, n] : entries)
            if (n == text) return e;
        return std::nullopt;
    }
    /// Every name, in the table's order (CLI::IsMember, TomlReader::choice).
    std::vector<std::string> names() const {
        std::vector<std::string> out;
        for (const auto& entry : entries) out.emplace_back(entry.second);
        return out;
    }
};

}  // namespace vtex
