// The demo's simulated sensors: Performer -> protocol encoder -> pty (device path), or
// Performer -> pipeline (direct path), on one thread paced by the wall clock. The demo also
// requests an N-pose calibration (as `mocapctl calibrate npose` does) during each of the
// performer's N-pose stands, so the avatar calibrates itself at start and on every loop. Its
// sensors come with their one-time gyro scale calibration (demo.gyro_scale_calibration).
#include "mocap/daemon/demo.hpp"

#include <poll.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

#include "mocap/core/time.hpp"
#include "mocap/devsim/sim_encoder.hpp"
#include "mocap/sim/performer.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/sim/table_spin.hpp"

namespace mocap::daemon {

namespace {

class DemoService final : public Service {
 public:
  /// Fills `cfg`, the demo's own rig (Demo::rig), with the performer's sensors.
  DemoService(Config& cfg, Logger log)
      : log_(std::move(log)), direct_(cfg.demo.path == DemoPath::direct) {
    sim::PerformerParams p;
    p.seed = cfg.demo.seed;
    p.rate_hz = cfg.demo.rate_hz;
    p.height_m = cfg.body.model.height_m;
    p.motion = cfg.demo.motion;
    p.loop = true;
    params_ = p;
    performer_ = std::make_unique<sim::Performer>(p);  // validates the motion name
    if (performer_->track().motion().dimensions()) {
      // A BVH file's bones: the avatar gets the performer's segment lengths.
      const BodyDimensions& d = performer_->dims();
      cfg.body.model.height_m = d.height_m;
      for (int s = 0; s < kSegmentCount; ++s) {
        cfg.body.model.joint_offset_m[s] = d.joint_offset_m[s];
        cfg.body.model.end_offset_m[s] = d.end_offset_m[s];
      }
    }
    cfg.sensors.clear();
    for (int i = 0; i < sim::Performer::kSensorCount; ++i) {
      SensorConfig s;
      s.name = std::string(sim::Performer::sensor_name(i));
      s.segment = s.name;
      s.rate_hz = cfg.demo.rate_hz;
      if (cfg.demo.gyro_scale_calibration) {
        // What `mocap gyro-scale` measures on the sensor's table spins, as a user does once.
        const Eigen::Vector3d g =
            sim::calibrated_gyro_scale(performer_->sensor_errors(i), s.rate_hz);
        s.gyr_scale = std::array<double, 3>{g.x(), g.y(), g.z()};
      }
      if (direct_) {
        s.driver = "direct";
        s.port = "demo";
      } else {
        EncoderOptions eo;
        eo.rate_hz = cfg.demo.rate_hz;
        encoders_.push_back(make_encoder(cfg.demo.protocol, eo));
        ptys_.push_back(std::make_unique<PtyEndpoint>());
        s.driver = cfg.demo.protocol;
        s.port = ptys_.back()->slave_path();
      }
      cfg.sensors.push_back(s);
    }
    samples_.reserve(4096);
    bytes_.reserve(1 << 16);
    plan_calibration(cfg);
  }
  ~DemoService() override { stop(); }

  void start(Pipeline& pipeline) override {
    pipeline_ = &pipeline;
    running_ = true;
    thread_ = std::thread([this] { run(); });
  }
  void stop() override {
    if (!running_.exchange(false)) return;
    if (thread_.joinable()) thread_.join();
  }

 private:
  void run() {
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, nullptr);
    // Performer time zero = now: sample host times are the times we emit them.
    params_.t0_ns = monotonic_ns();
    performer_ = std::make_unique<sim::Performer>(params_);
    const int64_t tick = 1'000'000;  // 1 ms: fine-grained enough for 100-1000 Hz sensors
    int64_t next = params_.t0_ns + tick;
    uint8_t host_in[256];
    while (running_) {
      const int64_t wait = next - monotonic_ns();
      if (wait > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
      const int64_t now = monotonic_ns();
      next += tick;
      if (next < now) next = now + tick;
      samples_.clear();
      performer_->step_to(now, samples_);
      for (const ImuSample& s : samples_) {
        if (direct_) {
          pipeline_->on_sample(s);  // performer times are host monotonic times already
          continue;
        }
        bytes_.clear();
        encoders_[s.sensor_id]->encode(s, bytes_);
        if (!bytes_.empty() && !ptys_[s.sensor_id]->write(bytes_)) ++overruns_;
      }
      if (!direct_) answer_host_commands(host_in, sizeof host_in);
      maybe_request_calibration(now);
    }
    if (overruns_)
      log_.warn("demo: %llu writes did not fit a pty (nobody reading)",
                static_cast<unsigned long long>(overruns_));
  }

  // The performer straps its sensors on the standard sites (calibration.heading =
  // "mount_normals", the default); with "pelvis_sensor" its belt clip's axis is the heading axis
  // (docs/sim.md). The capture
  // ends kCalibMarginS before the stand does; the countdown is shortened if the first stand
  // cannot hold countdown + capture after the filters have had kCalibSettleS to converge.
  void plan_calibration(Config& cfg) {
    const Eigen::Vector3d axis = sim::pelvis_forward_axis_sensor();
    cfg.calibration.heading_axis_sensor = {axis.x(), axis.y(), axis.z()};
    const auto [begin_s, end_s] = performer_->calibration_window_s();
    period_s_ = performer_->track().period_s();
    const double capture_start_s = end_s - kCalibMarginS - cfg.calibration.capture_s;
    if (capture_start_s < begin_s + kCalibSettleS) {
      log_.warn(
          "demo: the performer's %.1f s N-pose stand is too short for a %.1f s capture; "
          "no automatic calibration",
          end_s - begin_s, cfg.calibration.capture_s);
      return;
    }
    const double countdown_s =
        std::min(cfg.calibration.countdown_s, capture_start_s - begin_s - kCalibSettleS);
    cfg.calibration.countdown_s = countdown_s;
    calib_request_s_ = capture_start_s - countdown_s;
  }

  // Requests a calibration once per loop when the performer reaches calib_request_s_.
  void maybe_request_calibration(int64_t now_ns) {
    if (calib_request_s_ < 0 || period_s_ <= 0) return;
    const double t_s = static_cast<double>(now_ns - params_.t0_ns) * 1e-9;
    const double loop = std::floor(t_s / period_s_);
    if (loop < next_calib_loop_ || t_s - loop * period_s_ < calib_request_s_) return;
    next_calib_loop_ = loop + 1;
    pipeline_->calibrate(CalibrationPose::npose);
  }

  // Drivers may configure their device (rate, outputs): let each encoder answer.
  void answer_host_commands(uint8_t* buf, size_t cap) {
    for (size_t i = 0; i < ptys_.size(); ++i) {
      const size_t n = ptys_[i]->read(std::span<uint8_t>(buf, cap), 0);
      if (n == 0) continue;
      reply_.clear();
      encoders_[i]->handle_host_bytes(std::span<const uint8_t>(buf, n), reply_);
      if (!reply_.empty()) ptys_[i]->write(reply_);
    }
  }

  static constexpr double kCalibSettleS = 1.0;  // filter convergence before a capture
  static constexpr double kCalibMarginS = 0.3;  // capture ends this long before the stand does

  Logger log_;
  bool direct_;
  double period_s_ = 0;
  double calib_request_s_ = -1;  // performer time within a loop; < 0: no automatic calibration
  double next_calib_loop_ = 0;
  sim::PerformerParams params_;
  std::unique_ptr<sim::Performer> performer_;
  std::vector<std::unique_ptr<ProtocolEncoder>> encoders_;
  std::vector<std::unique_ptr<PtyEndpoint>> ptys_;
  std::vector<ImuSample> samples_;
  std::vector<uint8_t> bytes_, reply_;
  Pipeline* pipeline_ = nullptr;
  std::atomic<bool> running_{false};
  std::thread thread_;
  uint64_t overruns_ = 0;
};

}  // namespace

Demo make_demo(const Config& cfg, Logger log) {
  Demo d{cfg, nullptr};
  d.service = std::make_unique<DemoService>(d.rig, std::move(log));
  return d;
}

}  // namespace mocap::daemon
