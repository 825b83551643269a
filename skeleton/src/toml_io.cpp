// Checked TOML parsing with positioned errors for the skeleton's readers.
#include "toml_io.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
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

std::string read_file(const std::string& path, std::string_view what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(path + ": cannot open " + std::string(what) + " (not a regular file)");
  if (std::filesystem::file_size(path, ec) > (1u << 20))
    throw std::runtime_error(path + ": " + std::string(what) + " too large (over 1 MiB)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open " + std::string(what));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

toml::table parse(std::string_view text, std::string_view source) {
  std::string ascii;  // what toml++ reads: non-ASCII only as escapes (text_check.hpp)
  if (const auto bad = toml_text_problem(text, &ascii))
    throw std::runtime_error(std::string(source) + ": " + bad->to_string());
  try {
    return toml::parse(ascii, source);
  } catch (const toml::parse_error& e) {
    fail(source, e.source(), std::string(e.description()));
  }
}

}  // namespace mocap::skeleton_toml
