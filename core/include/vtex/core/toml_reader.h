/// @file
/// @brief Checked reading of TOML files (scene and pipeline files) with toml++.
///
/// Header-only, so that only the translation units that read TOML pay for toml++. Every value
/// is checked for presence, type and range; a problem throws vtex::InputError naming the file
/// and the key path ("surface[1].material.diffuse"); unknown keys become warnings.
#pragma once

#include <vtex/core/enum_names.h>

#include <vtex/core/error.h>

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace vtex {

class TomlReader {
public:
    TomlReader(const std::filesystem::path& file, std::vector<std::string>& warnings)
        : mFile(file), mWarnings(warnings) {}

    /// Parses `text`; a syntax error becomes an InputError with its line and column.
    toml::table parse(std::string_view text) const {
        try {
            return toml::parse(text, mFile.string());
        } catch (const toml::parse_error& e) {
            const auto& where = e.source().begin;
            fail("line " + std::to_string(where.line) + ", column " + std::to_string(where.column),
                 "TOML syntax error: " + std::string(e.description()));
        }
    }

    [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
        throw InputError(mFile, problem, key);
    }

    /// Also records each unknown key's path in `keys` (a caller that refuses them: `--strict`).
    void collectUnknownKeys(std::vector<std::string>& keys) { mUnknownKeys = &keys; }

    /// Warns about the keys of `table` that are not in `known`.
    void checkKeys(const toml::table& table, const std::string& path,
                   std::initializer_list<std::string_view> known) {
        for (const auto& [key, value] : table) {
            bool found = false;
            for (auto k : known) found = found || key.str() == k;
            if (found) continue;
            mWarnings.push_back(oneLine(mFile.string() + ": unknown key '" + join(path, key.str()) + "' ignored"));
            if (mUnknownKeys) mUnknownKeys->push_back(join(path, key.str()));
        }
    }

    double number(const toml::node& node, const std::string& key) const {
        if (auto v = node.as_floating_point()) {
            const double x = v->get();
            if (!std::isfinite(x)) fail(key, "must be a finite number");
            return x;
        }
        if (auto v = node.as_integer()) return double(v->get());
        fail(key, "must be a number");
    }

    double number(const toml::table& table, const std::string& path, std::string_view name,
                  std::optional<double> fallback, double min, double max, bool openMin = false) const {
        const std::string key = join(path, name);
        const toml::node* node = table.get(name);
        if (!node) {
            if (!fallback) fail(key, "missing key");
            return *fallback;
        }
        const double x = number(*node, key);
        if (x < min || x > max || (openMin && x == min)) {
            std::ostringstream s;
            s << "must be " << (openMin ? "in (" : "in [") << min << ", " << max << "], got " << x;
            fail(key, s.str());
        }
        return x;
    }

    long long integer(const toml::table& table, const std::string& path, std::string_view name,
                      std::optional<long long> fallback, long long min, long long max) const {
        const std::string key = join(path, name);
        const toml::node* node = table.get(name);
        if (!node) {
            if (!fallback) fail(key, "missing key");
            return *fallback;
        }
        const auto v = node->as_integer();
        if (!v) fail(key, "must be an integer");
        if (v->get() < min || v->get() > max)
            fail(key, "must be in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
        return v->get();
    }

    bool boolean(const toml::table& table, const std::string& path, std::string_view name,
                 std::optional<bool> fallback) const {
        const std::string key = join(path, name);
        const toml::node* node = table.get(name);
        if (!node) {
            if (!fallback) fail(key, "missing key");
            return *fallback;
        }
        const auto v = node->as_boolean();
        if (!v) fail(key, "must be true or false");
        return v->get();
    }

    std::string string(const toml::table& table, const std::string& path, std::string_view name,
                       std::optional<std::string> fallback) const {
        const std::string key = join(path, name);
        const toml::node* node = table.get(name);
        if (!node) {
            if (!fallback) fail(key, "missing key");
            return *fallback;
        }
        const auto v = node->as_string();
        if (!v) fail(key, "must be a string");
        return v->get();
    }

    /// A string that must be one of `allowed`.
    std::string choice(const toml::table& table, const std::string& path, std::string_view name,
                       std::optional<std::string> fallback, std::initializer_list<std::string_view> allowed) const {
        const std::string value = string(table, path, name, fallback);
        std::string list;
        for (auto a : allowed) {
            if (value == a) return value;
            list += (list.empty() ? "" : ", ") + std::string(a);
        }
        fail(join(path, name), "must be one of " + list + ", got '" + value + "'");
    }

    /// A value named in `names` (enum_names.h); `fallback` when the key is absent.
    template <class Enum, std::size_t N>
    Enum enumeration(const toml::table& table, const std::string& path, std::string_view name, Enum fallback,
                     const EnumNames<Enum, N>& names) const {
        const std::string value = string(table, path, name, std::string(names.name(fallback)));
        if (const auto parsed = names.parse(value)) return *parsed;
        std::string list;
        for (const auto& entry : names.entries) list += (list.empty() ? "" : ", ") + std::string(entry.second);
        fail(join(path, name), "must be one of " + list + ", got '" + value + "'");
    }

    const toml::table* subtable(const toml::table& table, const std::string& path, std::string_view name,
                                bool required) const {
        const toml::node* node = table.get(name);
        if (!node) {
            if (required) fail(join(path, name), "missing table");
            return nullptr;
        }
        const auto t = node->as_table();
        if (!t) fail(join(path, name), "must be a table");
        return t;
    }

    std::vector<const toml::table*> arrayOfTables(const toml::table& table, std::string_view name) const {
        std::vector<const toml::table*> out;
        const toml::node* node = table.get(name);
        if (!node) return out;
        const auto array = node->as_array();
        if (!array) fail(std::string(name), "must be an array of tables ([[" + std::string(name) + "]])");
        for (std::size_t i = 0; i < array->size(); ++i) {
            const auto t = array->get(i)->as_table();
            if (!t) fail(std::string(name) + "[" + std::to_string(i) + "]", "must be a table");
            out.push_back(t);
        }
        return out;
    }

    /// The path the value of `key` gives, relative to the file being read (absolute paths are
    /// kept). A NUL in it is refused: no file has such a name, and the system would open the
    /// path only up to the NUL, another file than the one named (found by fuzz_scene).
    std::filesystem::path resolve(const std::string& key, const std::string& relative) const {
        if (relative.find('\0') != std::string::npos) fail(key, "a path may not hold a NUL character");
        const std::filesystem::path p(relative);
        if (p.is_absolute()) return p;
        return mFile.parent_path() / p;
    }

    static std::string join(const std::string& path, std::string_view name) {
        return path.empty() ? std::string(name) : path + "." + std::string(name);
    }

    const std::filesystem::path& file() const { return mFile; }

private:
    std::filesystem::path mFile;
    std::vector<std::string>& mWarnings;
    std::vector<std::string>* mUnknownKeys = nullptr;
};

}  // namespace vtex
