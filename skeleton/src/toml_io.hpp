// Shared by the skeleton's TOML readers (body config, joint limits, calibration): errors that
// name file:line:column, and parsing that first refuses text toml++ 3.3 cannot handle safely.
#pragma once

#include <toml++/toml.h>

#include <string>
#include <string_view>

namespace mocap::skeleton_toml {

/// Throws std::runtime_error "source:line:column: what".
[[noreturn]] void fail(std::string_view source, const toml::source_region& r,
                       const std::string& what);

/// Checks the text (ASCII, no NUL: core/text_check.hpp) and parses it; throws with the
/// position of the first problem.
toml::table parse(std::string_view text, std::string_view source);

}  // namespace mocap::skeleton_toml
