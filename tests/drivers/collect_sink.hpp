// Helpers for the driver tests: a SampleSink that keeps every sample, connection event and
// telemetry report (thread-safe), the log sink the tests' devices write to, and a free loopback
// port.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "../common/free_port.hpp"
#include "mocap/core/time.hpp"
#include "mocap/drivers/device.hpp"

namespace mocap::test {

/// Where the tests' devices log (written only; one per test program).
inline LogSink g_log_sink;

struct ConnectionEvent {
  bool connected;
  std::string reason;
  int64_t t_ns;
};

class CollectSink : public SampleSink {
 public:
  void on_sample(const ImuSample& s) override {
    std::lock_guard lk(mu_);
    samples.push_back(s);
  }
  void on_raw(uint16_t, int64_t, std::span<const uint8_t> b) override {
    std::lock_guard lk(mu_);
    raw_bytes += b.size();
  }
  void on_connection(uint16_t, bool c, std::string_view why) override {
    std::lock_guard lk(mu_);
    events.push_back({c, std::string(why), monotonic_ns()});
  }
  void on_telemetry(uint16_t sensor_id, const SensorTelemetry& t) override {
    std::lock_guard lk(mu_);
    telemetry.push_back({sensor_id, t});
  }
  std::vector<std::pair<uint16_t, SensorTelemetry>> telemetry_snapshot() const {
    std::lock_guard lk(mu_);
    return telemetry;
  }
  std::vector<ImuSample> snapshot() const {
    std::lock_guard lk(mu_);
    return samples;
  }
  std::vector<ConnectionEvent> events_snapshot() const {
    std::lock_guard lk(mu_);
    return events;
  }
  std::size_t count() const {
    std::lock_guard lk(mu_);
    return samples.size();
  }
  /// Waits (bounded) until pred() holds; returns whether it did.
  template <typename Pred>
  bool wait_for(Pred pred, double timeout_s = 10) const {
    const int64_t end = monotonic_ns() + static_cast<int64_t>(timeout_s * 1e9);
    while (monotonic_ns() < end) {
      if (pred()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return pred();
  }

  mutable std::mutex mu_;
  std::vector<ImuSample> samples;
  std::vector<ConnectionEvent> events;
  std::vector<std::pair<uint16_t, SensorTelemetry>> telemetry;  ///< (sensor id, report)
  std::size_t raw_bytes = 0;
};

}  // namespace mocap::test
