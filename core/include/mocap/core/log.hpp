// Leveled logging with a per-component tag and level. A Logger is an object passed to whoever
// logs (no global state); each device gets its own child with its own level.
#pragma once

#include <array>
#include <cstdio>
#include <mutex>
#include <string>
#include <string_view>

namespace mocap {

enum class LogLevel { trace, debug, info, warn, error, off };

/// The levels' names, in LogLevel order: the one list that log lines, the configuration
/// (`daemon.log_level`, a sensor's `log_level`) and its reference read.
inline constexpr std::array<std::string_view, 6> kLogLevelNames = {"trace", "debug", "info",
                                                                   "warn",  "error", "off"};
static_assert(kLogLevelNames.size() == static_cast<std::size_t>(LogLevel::off) + 1);

std::string_view to_string(LogLevel l);
/// kLogLevelNames as one list, "trace, debug, info, warn, error, off".
std::string_view log_level_choices();

/// Where log lines go (shared by all Loggers of one process; serialises writes).
class LogSink {
 public:
  explicit LogSink(FILE* out = stderr) : out_(out) {}
  void write(LogLevel level, std::string_view tag, std::string_view msg);

 private:
  std::mutex mu_;
  FILE* out_;
};

class Logger {
 public:
  Logger(LogSink& sink, std::string tag, LogLevel level = LogLevel::info)
      : sink_(&sink), tag_(std::move(tag)), level_(level) {}

  /// A logger for a sub-component, e.g. one device: "mocapd" -> "mocapd/imu3".
  Logger child(std::string_view sub, LogLevel level) const {
    return Logger(*sink_, tag_ + "/" + std::string(sub), level);
  }

  bool enabled(LogLevel l) const { return l >= level_; }
  void set_level(LogLevel l) { level_ = l; }
  LogLevel level() const { return level_; }
  const std::string& tag() const { return tag_; }

  template <typename... Args>
  void log(LogLevel l, const char* fmt, Args... args) const {
    if (!enabled(l)) return;
    char buf[512];
    if constexpr (sizeof...(Args) == 0) {
      sink_->write(l, tag_, fmt);
    } else {
      std::snprintf(buf, sizeof buf, fmt, args...);
      sink_->write(l, tag_, buf);
    }
  }
  template <typename... A>
  void trace(const char* f, A... a) const {
    log(LogLevel::trace, f, a...);
  }
  template <typename... A>
  void debug(const char* f, A... a) const {
    log(LogLevel::debug, f, a...);
  }
  template <typename... A>
  void info(const char* f, A... a) const {
    log(LogLevel::info, f, a...);
  }
  template <typename... A>
  void warn(const char* f, A... a) const {
    log(LogLevel::warn, f, a...);
  }
  template <typename... A>
  void error(const char* f, A... a) const {
    log(LogLevel::error, f, a...);
  }

 private:
  LogSink* sink_;
  std::string tag_;
  LogLevel level_;
};

}  // namespace mocap
