// The skeleton's config tables read from an already-parsed TOML document, so a program that
// embeds them in its own config file (mocapd's [body]) reports errors at their real file:line.
// The standalone files (config/body/default.toml, config/body/joint_limits.toml) use the same
// readers through parse_body_config / parse_joint_limits.
#pragma once

#include <toml++/toml.h>

#include <stdexcept>
#include <string>
#include <string_view>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap {

/// What the skeleton's TOML readers throw: what() is "source:line:column: problem"; the parts
/// are kept for callers that report positions themselves.
struct TomlPositionError : std::runtime_error {
  TomlPositionError(std::string source, int line, int column, std::string problem);
  std::string source;
  int line = 0, column = 0;  ///< 1-based
  std::string problem;
};

/// Reads a `[segment]` node (`[segment.NAME]` tables with joint_offset_m / end_offset_m) into
/// cfg's overrides. Throws std::runtime_error "source:line:column: what" (unknown segment or
/// key, wrong type, out-of-range value); `source` names the file when a node has no path.
void read_body_segments(const toml::node& segment, std::string_view source, BodyModelConfig& cfg);

/// Reads a `[joint]` node (`[joint.NAME]` tables: a_deg, b_deg, twist_deg, hinge, limited) onto
/// `limits` and validates the result. Throws like read_body_segments.
void read_joint_limit_tables(const toml::node& joint, std::string_view source, JointLimits& limits);

/// The body height range both readers accept, metres.
inline constexpr double kMinBodyHeightM = 0.5, kMaxBodyHeightM = 2.6;

}  // namespace mocap
