// Checked TOML parsing with positioned errors for the skeleton's readers.
#include "toml_io.hpp"

#include <sstream>
#include <stdexcept>

#include "mocap/core/text_check.hpp"

namespace mocap::skeleton_toml {

void fail(std::string_view source, const toml::source_region& r, const std::string& what) {
  std::ostringstream os;
  os << source << ":" << r.begin.line << ":" << r.begin.column << ": " << what;
  throw std::runtime_error(os.str());
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
