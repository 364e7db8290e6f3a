#pragma once
// A double as the JSON vtex writes: JSON has no NaN or infinity, so such a value is null (a bias
// against a black channel, the PSNR of identical images, a level with nothing measured).

#include <nlohmann/json.hpp>

#include <cmath>

namespace vtex::cli {

inline nlohmann::json jsonNumber(double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace vtex::cli
