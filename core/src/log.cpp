// Log sink: timestamped, tagged lines to a FILE*.
#include "mocap/core/log.hpp"

#include "mocap/core/time.hpp"

namespace mocap {

std::string_view to_string(LogLevel l) {
  switch (l) {
    case LogLevel::trace:
      return "trace";
    case LogLevel::debug:
      return "debug";
    case LogLevel::info:
      return "info";
    case LogLevel::warn:
      return "warn";
    case LogLevel::error:
      return "error";
    case LogLevel::off:
      return "off";
  }
  return "?";
}

bool parse_log_level(std::string_view s, LogLevel& out) {
  for (LogLevel l : {LogLevel::trace, LogLevel::debug, LogLevel::info, LogLevel::warn,
                     LogLevel::error, LogLevel::off}) {
    if (s == to_string(l)) {
      out = l;
      return true;
    }
  }
  return false;
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
