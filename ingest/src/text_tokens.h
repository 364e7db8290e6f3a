// Whitespace-separated tokens of a text mesh format (OFF, the PLY header), shared by their
// readers. Internal.
#pragma once

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <string_view>
#include <system_error>

namespace vtex::ingest::detail {

inline bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

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

inline std::string_view trimmed(std::string_view s) {
    while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
    return s;
}

inline bool parseCount(std::string_view token, std::uint64_t& value) {
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    return ec == std::errc() && end == token.data() + token.size();
}

}  // namespace vtex::ingest::detail
