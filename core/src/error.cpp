#include <vtex/core/error.h>

namespace vtex {

// One line, whatever the text carries (it may quote untrusted input), and all of it: a NUL (a
// scene path may hold one) would end the message where what() is printed, other control
// characters would garble the terminal; they are written as \xHH.
std::string oneLine(std::string_view message) {
    std::string clean;
    clean.reserve(message.size());
    for (const char c : message) {
        if (c == '\n' || c == '\r' || c == '\t') {
            clean += ' ';
        } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
            static constexpr char kHex[] = "0123456789abcdef";
            clean += "\\x";
            clean += kHex[(static_cast<unsigned char>(c) >> 4) & 15];
            clean += kHex[static_cast<unsigned char>(c) & 15];
        } else {
            clean += c;
        }
    }
    return clean;
}

namespace {
std::string joinMessage(const std::filesystem::path& file, const std::string& location,
                        const std::string& problem) {
    std::string message = file.string();
    if (!location.empty()) message += ": " + location;
    message += ": " + problem;
    return oneLine(message);
}
}  // namespace

InputError::InputError(const std::filesystem::path& file, const std::string& problem,
                       const std::string& location)
    : std::runtime_error(joinMessage(file, location, problem)),
      mFile(file),
      mLocation(location),
      mProblem(problem) {}

IoError::IoError(const std::filesystem::path& file, const std::string& problem)
    : std::runtime_error(joinMessage(file, {}, problem)), mFile(file) {}

}  // namespace vtex
