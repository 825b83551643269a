// How much each sensor moves: a SampleSink on every device `mocap setup` opens, measuring each
// sensor's mean angular speed over windows the caller takes (take()), and what it has seen since
// it started (samples, which fields). Angular speed: |gyro| for a sensor with a gyro; for
// an orientation source (a SlimeVR tracker) the angle between its successive orientations over
// the window's time. Called from every device's reader thread: one short lock per sensor.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "mocap/drivers/device.hpp"

namespace mocap::setup {

class MotionMeter final : public SampleSink {
 public:
  /// Sensor ids 0..sensors-1 (the samples' sensor_id); others are ignored.
  explicit MotionMeter(std::size_t sensors);

  void on_sample(const ImuSample& s) override;

  struct Window {
    uint64_t samples = 0;
    double rate_hz = 0;      ///< samples per second of the window's (host) time
    double speed_rad_s = 0;  ///< mean angular speed over the window
  };
  /// Each sensor's motion since the last take() (or since construction) up to now_ns (host
  /// monotonic); starts the next window.
  std::vector<Window> take(int64_t now_ns);

  struct Seen {
    uint64_t samples = 0;
    uint8_t fields = 0;  ///< SampleField bits seen on any sample
  };
  Seen seen(std::size_t sensor) const;
  std::size_t size() const { return sensors_.size(); }

 private:
  struct Sensor {
    mutable std::mutex mu;
    // the current window
    uint64_t samples = 0;
    double gyro_sum = 0;      ///< sum of |gyro| over gyro samples
    uint64_t gyro_count = 0;  ///< samples with a gyro
    double angle_sum = 0;     ///< orientation sources: angle travelled
    // since the start
    uint64_t total = 0;
    uint8_t fields = 0;
    bool has_q = false;
    Eigen::Quaterniond last_q = Eigen::Quaterniond::Identity();
  };
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::mutex window_mu_;
  int64_t window_start_ns_ = 0;
};

}  // namespace mocap::setup
