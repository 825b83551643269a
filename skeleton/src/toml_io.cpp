// Checked TOML parsing with positioned errors for the skeleton's readers.
#include "toml_io.hpp"

#include <stdexcept>

#include "mocap/core/text_check.hpp"
#include "mocap/skeleton/config_tables.hpp"

namespace mocap {

TomlPositionError::TomlPositionError(std::string source_, int line_, int column_,
                                     std::string problem_)
    : std::runtime_error(source_ + ":" + std::to_string(line_) + ":" + std::to_string(column_) +
                         ": " + problem_),
      source(std::move(source_)),
      line(line_),
      column(column_),
      problem(std::move(problem_)) {}

}  // namespace mocap

namespace mocap::skeleton_toml {

void fail(std::string_view source, const toml::source_region& r, const std::string& what) {
  throw TomlPositionError(std::string(source), static_cast<int>(r.begin.line),
                          static_cast<int>(r.begin.column), what);
}

toml::table parse(std::string_view text, std::string_view source) {
  if (const auto bad = text_problem(text, /*ascii_only=*/true))
    throw std::runtime_error(std::string(source) + ": " + bad->to_string());
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    fail(source, e.source(), std::string(e.description()));
  }
}

}  // namespace mocap::skeleton_toml
