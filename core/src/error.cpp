#include <vtex/core/error.h>

namespace vtex {
namespace {
std::string joinMessage(const std::filesystem::path& file, const std::string& location,
                        const std::string& problem) {
    std::string message = file.string();
    if (!location.empty()) message += ": " + location;
    message += ": " + problem;
    // One line, whatever the problem text carries (it may quote untrusted input).
    for (char& c : message)
        if (c == '\n' || c == '\r') c = ' ';
    return message;
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
