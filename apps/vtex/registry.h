#pragma once

#include "cli.h"

#include <utility>
#include <vector>

namespace vtex::cli {
/// The subcommands registered by the cmd_*.cpp files, in registration order.
std::vector<std::pair<int, CommandFactory>>& commandRegistry();
}  // namespace vtex::cli
