// run_replay with the filters on a pool of threads (ReplayOptions::filter_threads) gives the
// same frames as with everything on one thread: with a stand-in engine whose per-sensor
// "filters" carry state from sample to sample and whose calibration capture, when it ends,
// changes every filter (as the real tracker hands suspected local fields to the filters), with
// unknown and non-finite samples in the input; and with the real RigEngine on the virtual
// performer, calibrating on the way.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "mocap/daemon/daemon.hpp"
#include "mocap/daemon/replay.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/sim/performer.hpp"

namespace mocap::daemon {
namespace {

class VectorSource final : public SampleSource {
 public:
  VectorSource(std::vector<ImuSample> s, Config cfg) : s_(std::move(s)), cfg_(std::move(cfg)) {}
  const Config& config() const override { return cfg_; }
  bool next(ImuSample& out) override {
    if (i_ == s_.size()) return false;
    out = s_[i_++];
    return true;
  }
  const std::string& error() const override { return error_; }
  double progress() const override { return static_cast<double>(i_) / s_.size(); }
  std::string calibration_text() const override { return ""; }

 private:
  std::vector<ImuSample> s_;
  Config cfg_;
  std::size_t i_ = 0;
  std::string error_;
};

/// Per-sensor state updated by every sample (its "filter"); the rest of the engine reads only
/// what prefilter returned. A capture (calibrate) lasts 0.3 s of samples; its end shifts every
/// sensor's filter, which only comes out right if the filters are in step with it.
class StandInEngine final : public PoseEngine {
 public:
  static constexpr int kSensors = 5;
  bool prefilter_allowed() const override { return !capturing_; }
  FilterOutput prefilter(int i, const ImuSample& s) override {
    x_[i] = 0.97 * x_[i] + s.gyr_rad_s.x() + shift_[i];
    FilterOutput o;
    o.gyro_bias_rad_s.x() = x_[i];
    return o;
  }
  void on_sample(int i, const ImuSample& s) override { on_prefiltered(i, s, prefilter(i, s)); }
  void on_prefiltered(int i, const ImuSample& s, const FilterOutput& o) override {
    seen_[i] = o.gyro_bias_rad_s.x();
    newest_ns_ = std::max(newest_ns_, s.t_host_ns);
    if (capturing_ && s.t_host_ns >= capture_end_ns_) {
      capturing_ = false;
      ++captures_;
      for (int k = 0; k < kSensors; ++k)
        shift_[k] += 0.25 * (k + 1);
    }
  }
  void set_sensor_live(int, bool) override {}
  void build_frame(int64_t, PoseFrame& out) override {
    for (int i = 0; i < kSensors; ++i)
      out.q_earth_segment[i][0] = static_cast<float>(seen_[i]);
    out.joint_violation_deg[0] = static_cast<float>(captures_);
  }
  SensorHealth sensor_health(int) const override { return {}; }
  void calibrate(CalibrationPose, bool) override {
    capturing_ = true;
    capture_end_ns_ = newest_ns_ + 300'000'000;
  }
  void reset_heading() override {}
  int captures() const { return captures_; }

 private:
  double x_[kSensors] = {}, shift_[kSensors] = {}, seen_[kSensors] = {};
  bool capturing_ = false;
  int64_t capture_end_ns_ = 0, newest_ns_ = 0;
  int captures_ = 0;
};

struct Frames final : mocap::outputs::Output {
  std::vector<PoseFrame> f;
  void on_frame(const PoseFrame& frame) override { f.push_back(frame); }
};

std::vector<SensorInfo> five_sensors() {
  std::vector<SensorInfo> s;
  for (int i = 0; i < StandInEngine::kSensors; ++i)
    s.push_back({"s" + std::to_string(i), i});
  return s;
}

/// 30 s of 5 sensors at 100 Hz, out of step by a few ms, with an unknown sensor's and a NaN
/// sample now and then.
std::vector<ImuSample> stand_in_input() {
  std::vector<ImuSample> v;
  for (int k = 0; k < 3000; ++k)
    for (int i = 0; i < StandInEngine::kSensors; ++i) {
      ImuSample s;
      s.sensor_id = static_cast<uint16_t>(i);
      s.t_host_ns = k * 10'000'000LL + i * 1'300'000LL;
      s.valid = kFieldGyr;
      s.gyr_rad_s = Eigen::Vector3d(std::sin(0.01 * k + i), 0, 0);
      v.push_back(s);
      if (k % 777 == 5) {
        ImuSample bad = s;
        bad.sensor_id = 9;
        v.push_back(bad);
        bad.sensor_id = static_cast<uint16_t>(i);
        bad.gyr_rad_s.x() = std::nan("");
        v.push_back(bad);
      }
    }
  return v;
}

bool same_frames(const std::vector<PoseFrame>& a, const std::vector<PoseFrame>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (std::memcmp(&a[k], &b[k], sizeof(PoseFrame)) != 0) return false;
  return true;
}

std::vector<PoseFrame> stand_in_replay(int threads, bool calibrate, int* captures = nullptr) {
  StandInEngine eng;
  PipelineConfig pc;
  pc.rate_hz = 60;
  PipelineCore core(pc, CalibrationConfig{.countdown_s = 0}, five_sensors(), eng);
  Frames frames;
  core.add_sink(&frames);
  VectorSource src(stand_in_input(), Config{});
  ReplayOptions opt;
  opt.filter_threads = threads;
  if (calibrate) {
    opt.calibrate_pose = CalibrationPose::npose;
    opt.calibrate_at_s = 7.0;
  }
  const ReplayResult r = run_replay(src, core, opt);
  EXPECT_EQ(r.samples, stand_in_input().size());
  if (captures) *captures = eng.captures();
  return frames.f;
}

}  // namespace

TEST(ReplayParallel, SameFramesAsOneThreadWithFiltersChangedAtACapturesEnd) {
  int captures = 0;
  const auto one = stand_in_replay(0, true, &captures);
  ASSERT_EQ(captures, 1);  // the capture ended (and changed every filter) on the way
  ASSERT_GT(one.size(), 1000u);
  EXPECT_FALSE(same_frames(one, stand_in_replay(0, false)));  // the change shows in the frames
  for (const int threads : {1, 2, 5}) {
    int c = 0;
    EXPECT_TRUE(same_frames(one, stand_in_replay(threads, true, &c))) << threads << " threads";
    EXPECT_EQ(c, 1);
  }
}

TEST(ReplayParallel, RealEngineOnThePerformerCalibratingGivesTheSameFrames) {
  sim::PerformerParams pp;
  pp.rate_hz = 100;
  sim::Performer performer(pp);
  std::vector<ImuSample> samples;
  performer.step_to(12'000'000'000LL, samples);
  const auto win = performer.calibration_window_s();
  ConfigErrors errs;
  Config cfg = *parse_config("", "<test>", {}, errs);
  for (int i = 0; i < sim::Performer::kSensorCount; ++i) {
    SensorConfig s;
    s.name = sim::Performer::sensor_name(i);
    s.segment = s.name;
    s.driver = "witmotion";
    s.port = "/dev/null";
    cfg.sensors.push_back(s);
  }
  cfg.calibration.countdown_s = 0;
  auto replay = [&](int threads) {
    RigEngine engine(cfg, nullptr);
    PipelineCore core(cfg.pipeline, cfg.calibration, sensor_infos(cfg), engine);
    Frames frames;
    core.add_sink(&frames);
    VectorSource src(samples, cfg);
    ReplayOptions opt;
    opt.filter_threads = threads;
    opt.calibrate_pose = CalibrationPose::npose;
    opt.calibrate_at_s = 0.5 * (win.first + win.second);
    run_replay(src, core, opt);
    EXPECT_TRUE(engine.skeleton().calibration().valid) << threads;
    return frames.f;
  };
  const auto one = replay(0);
  ASSERT_GT(one.size(), 1000u);
  EXPECT_TRUE(same_frames(one, replay(1)));
  EXPECT_TRUE(same_frames(one, replay(3)));
}

}  // namespace mocap::daemon
