// Log sink: timestamped, tagged lines to a FILE*.
#include "mocap/core/log.hpp"

#include "mocap/core/time.hpp"

namespace mocap {

std::string_view to_string(LogLevel l) {
  const auto i = static_cast<std::size_t>(l);
  return i < kLogLevelNames.size() ? kLogLevelNames[i] : "?";
}

std::string_view log_level_choices() {
  static const std::string choices = [] {
    std::string s;
    for (std::string_view n : kLogLevelNames)
      s.append(s.empty() ? "" : ", ").append(n);
    return s;
  }();
  return choices;
}

void LogSink::write(LogLevel level, std::string_view tag, std::string_view msg) {
  const double t = ns_to_s(monotonic_ns());
  std::lock_guard lock(mu_);
  std::fprintf(out_, "[%12.6f] %-5.*s %.*s: %.*s\n", t, static_cast<int>(to_string(level).size()),
               to_string(level).data(), static_cast<int>(tag.size()), tag.data(),
               static_cast<int>(msg.size()), msg.data());
  std::fflush(out_);
}

}  // namespace mocap
