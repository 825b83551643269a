// Shared by the skeleton's TOML readers (body config, joint limits, calibration): errors that
// name file:line:column, and parsing that first refuses text toml++ 3.3 cannot handle safely.
#pragma once

#include <toml++/toml.h>

#include <string>
#include <string_view>

#include "mocap/core/segments.hpp"

namespace mocap::skeleton_toml {

/// Throws std::runtime_error "source:line:column: what".
[[noreturn]] void fail(std::string_view source, const toml::source_region& r,
                       const std::string& what);

/// Checks the text (valid UTF-8, no NUL, non-ASCII only in strings and comments:
/// toml_text_problem in core/text_check.hpp) and parses it; throws with the
/// position of the first problem.
toml::table parse(std::string_view text, std::string_view source);

/// Reads a config file of at most 1 MiB; throws std::runtime_error "path: cannot open <what>"
/// (also for a directory, a device or a FIFO, which would never end) or "path: too large".
std::string read_file(const std::string& path, std::string_view what);

/// For a `[segment]` node: calls fn(segment index, "segment.NAME", the NAME table) for each
/// entry; throws for a non-table, an unknown segment name or an entry that is not a table.
template <typename Fn>
void for_each_segment_table(std::string_view source, const toml::node& v, Fn&& fn) {
  const toml::table* segs = v.as_table();
  if (!segs) fail(source, v.source(), "[segment] must be a table of segment tables");
  for (auto&& [sk, sv] : *segs) {
    const auto seg = segment_from_name(sk.str());
    if (!seg) fail(source, sk.source(), "unknown segment '" + std::string(sk.str()) + "'");
    const std::string path = "segment." + std::string(sk.str());
    const toml::table* st = sv.as_table();
    if (!st) fail(source, sv.source(), path + " must be a table");
    fn(index(*seg), path, *st);
  }
}

}  // namespace mocap::skeleton_toml
