// The live pipeline: device reader threads push samples into one lock-free ring per sensor
// (SampleSink), a pipeline thread drains them in timestamp order through PipelineCore and
// publishes frames at the configured rate (wall clock). Commands and status cross threads
// through short critical sections that the pipeline thread only try-locks.
#pragma once

#include <array>
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/core/spsc_ring.hpp"
#include "mocap/core/wakeup.hpp"
#include "mocap/daemon/pipeline_core.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/outputs/recorder.hpp"

namespace mocap::daemon {

/// A snapshot of the pipeline for status reports (copied under a mutex, at most per frame).
struct PipelineStatus {
  PoseFrame frame;  ///< the last published frame (includes per-sensor SensorStatus)
  CalibrationProgress calibration;
  uint64_t samples = 0, rejected = 0, ring_drops = 0, frames = 0;
  bool calibrating = false;
  /// What each sensor last reported about itself (battery, signal, temperature, identity;
  /// SampleSink::on_telemetry), by sensor index; all unknown for devices that report nothing.
  std::array<SensorTelemetry, kMaxSensors> telemetry{};
};

class Pipeline final : public SampleSink {
 public:
  static constexpr size_t kRingCapacity = 1024;

  Pipeline(const PipelineConfig& cfg, const CalibrationConfig& calib,
           std::vector<SensorInfo> sensors, PoseEngine& engine, Logger log);
  ~Pipeline() override;

  /// Before start(): frame consumers.
  void add_sink(outputs::Output* sink) { core_.add_sink(sink); }
  /// Any time: which frame flags to set (e.g. kFrameDemo).
  void start();
  void stop();

  // SampleSink (device reader threads; one producer per sensor).
  void on_sample(const ImuSample& sample) override;
  void on_raw(uint16_t device_index, int64_t t_host_ns, std::span<const uint8_t> bytes) override;
  void on_connection(uint16_t device_index, bool connected, std::string_view reason) override;
  /// A sensor's reset button: full = calibrate in the configured pose (as `mocapctl calibrate`),
  /// heading = `mocapctl reset-heading`.
  void on_reset_request(uint16_t device_index, ResetRequest what) override;
  /// Kept (short lock) for status(); not part of the frames.
  void on_telemetry(uint16_t sensor_id, const SensorTelemetry& telemetry) override;

  /// Maps device index -> sensor index for connection reports (default identity).
  void set_device_sensor(uint16_t device_index, int sensor);

  // Commands (any thread; executed on the pipeline thread).
  /// With mounting_motion (an N-pose) the mounting motion follows the capture.
  void calibrate(CalibrationPose pose, bool mounting_motion = false);
  void reset_heading();
  void set_frame_flag(uint32_t flag, bool on);
  /// Installs (or with nullptr removes) the recording tap. Returns once the old tap is no
  /// longer in use by any thread, so the caller may destroy it.
  void set_record_tap(outputs::RecordTap* tap);
  /// External counters per sensor (device decoder drops and errors), any thread.
  void set_device_counters(int sensor, uint32_t drops, uint32_t errors);

  PipelineStatus status() const;
  uint64_t ring_drops() const;

 private:
  struct Slot {
    SpscRing<ImuSample, kRingCapacity> ring;
    std::atomic<uint64_t> drops{0};
    std::atomic<int> connected{-1};  // -1 unknown, 0 no, 1 yes
    std::atomic<uint32_t> dev_drops{0}, dev_errors{0};
  };
  struct Command {
    enum Kind { calibrate, reset_heading, flag } kind;
    CalibrationPose pose = CalibrationPose::npose;
    bool mounting_motion = false;
    uint32_t flag_bits = 0;
    bool on = false;
  };
  void run();
  void drain();
  void apply_commands(int64_t now_ns);
  void publish(int64_t now_ns);
  void snapshot();

  PipelineConfig cfg_;
  CalibrationPose reset_pose_ = CalibrationPose::npose;  ///< the configured calibration pose
  Logger log_;
  PipelineCore core_;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::vector<std::vector<ImuSample>> scratch_;  // per sensor, capacity kRingCapacity
  std::vector<size_t> scratch_n_, scratch_pos_;
  std::vector<int> device_sensor_;
  Wakeup wake_;
  std::atomic<bool> running_{false};
  std::thread thread_;

  mutable std::mutex cmd_mu_;
  std::vector<Command> commands_, commands_work_;

  std::atomic<outputs::RecordTap*> tap_{nullptr};
  std::atomic<int> tap_users_{0};
  /// Calls f(tap) when a recording tap is installed, counted in tap_users_ so that
  /// set_record_tap() can wait until no caller still holds the tap it replaced.
  template <class F>
  void with_tap(F&& f) {
    tap_users_.fetch_add(1);
    if (outputs::RecordTap* t = tap_.load()) f(*t);
    tap_users_.fetch_sub(1);
  }

  mutable std::mutex status_mu_;
  PipelineStatus status_;
  mutable std::mutex telemetry_mu_;
  std::array<SensorTelemetry, kMaxSensors> telemetry_{};  // by sensor index
  int64_t last_snapshot_ns_ = 0;

  class TapSink final : public outputs::Output {
   public:
    explicit TapSink(Pipeline& p) : p_(p) {}
    void on_frame(const PoseFrame& f) override;

   private:
    Pipeline& p_;
  } tap_sink_{*this};
};

}  // namespace mocap::daemon
