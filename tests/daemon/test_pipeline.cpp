// Pipeline: the deterministic core (sample-time frame clock, health, staleness, NaN rejection,
// calibration countdown, per-sample publishing) and the live threaded pipeline (rings from
// several producer threads, frames at the configured rate, drops counted, commands, taps).
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

#include "mocap/core/time.hpp"
#include "mocap/daemon/pipeline.hpp"
#include "test_engine.hpp"

using namespace mocap;
using namespace mocap::daemon;

namespace {

struct CollectSink final : mocap::outputs::Output {
  std::mutex mu;
  std::vector<PoseFrame> frames;
  void on_frame(const PoseFrame& f) override {
    std::lock_guard l(mu);
    frames.push_back(f);
  }
  size_t count() {
    std::lock_guard l(mu);
    return frames.size();
  }
};

ImuSample sample(uint16_t id, int64_t t_ns, double gz = 0) {
  ImuSample s;
  s.sensor_id = id;
  s.t_host_ns = t_ns;
  s.valid = kFieldGyr | kFieldAcc;
  s.gyr_rad_s = {0, 0, gz};
  s.acc_m_s2 = {0, 0, 9.81};
  return s;
}

std::vector<SensorInfo> two_sensors() {
  return {{"pelvis", 0}, {"head", 3}};
}

/// A PipelineCore over two_sensors() (pelvis, head) at rate_hz, sensors stale after 100 ms,
/// publishing into `sink`.
struct TwoSensorCore {
  explicit TwoSensorCore(double rate_hz, bool per_sample = false)
      : core(config(rate_hz, per_sample), {}, two_sensors(), eng) {
    core.add_sink(&sink);
  }
  static PipelineConfig config(double rate_hz, bool per_sample) {
    PipelineConfig pc;
    pc.rate_hz = rate_hz;
    pc.stale_after_ms = 100;
    pc.publish_every_sample = per_sample;
    return pc;
  }
  test::GyroEngine eng = [] {
    test::GyroEngine e;
    e.segment[0] = 0;
    e.segment[1] = 3;
    return e;
  }();
  PipelineCore core;
  CollectSink sink;
};

}  // namespace

TEST(PipelineCore, SampleClockPublishesAtRateWithHealth) {
  TwoSensorCore pipe(50);
  auto& [eng, core, sink] = pipe;
  // 2 s of sensor 0 at 100 Hz turning at 1 rad/s; sensor 1 stops after 0.5 s.
  for (int k = 0; k <= 200; ++k) {
    const int64_t t = k * 10'000'000LL;
    core.advance_clock_to(t);
    core.process(sample(0, t, 1.0));
    if (t <= 500'000'000) core.process(sample(1, t));
  }
  ASSERT_EQ(sink.frames.size(), 100u);  // 2 s at 50 Hz
  const PoseFrame& f = sink.frames.back();
  EXPECT_EQ(f.frame, 100u);
  EXPECT_EQ(f.sensor_count, 2u);
  EXPECT_STREQ(f.sensors[0].name, "pelvis");
  EXPECT_EQ(f.sensors[0].state, kStreaming);
  EXPECT_NEAR(f.sensors[0].rate_hz, 100.0, 0.5);
  EXPECT_EQ(f.sensors[1].state, kStale);
  EXPECT_TRUE(f.segment_flags[3] & kSegStale);
  EXPECT_FALSE(eng.live[1]);
  EXPECT_GT(f.sensors[1].last_age_ms, 1000);
  // The pelvis turned ~2 rad about z.
  const Eigen::Quaterniond q(f.q_earth_segment[0][0], f.q_earth_segment[0][1],
                             f.q_earth_segment[0][2], f.q_earth_segment[0][3]);
  EXPECT_NEAR(Eigen::AngleAxisd(q).angle(), 1.99, 0.02);
}

// Frames faster than the sensors (120 Hz over 100 Hz): every frame has a time of its own, the
// newest sample's, so exports have one frame per time; silent sensors still get frames (at the
// clock's time) that report them stale.
TEST(PipelineCore, EveryFrameHasItsOwnTime) {
  TwoSensorCore pipe(120);
  auto& [eng, core, sink] = pipe;
  for (int k = 0; k <= 100; ++k) {  // 1 s of both sensors at 100 Hz
    const int64_t t = k * 10'000'000LL;
    core.advance_clock_to(t);
    core.process(sample(0, t));
    core.process(sample(1, t));
  }
  const size_t while_streaming = sink.frames.size();
  EXPECT_GE(while_streaming, 95u);
  EXPECT_LE(while_streaming, 101u);
  for (int64_t t = 1'000'000'000; t <= 2'000'000'000; t += 1'000'000)  // then silence, 1 s
    core.advance_clock_to(t);
  ASSERT_GT(sink.frames.size(), while_streaming);
  for (size_t i = 1; i < sink.frames.size(); ++i)
    EXPECT_GT(sink.frames[i].t_ns, sink.frames[i - 1].t_ns) << i;
  for (size_t i = 0; i < while_streaming; ++i)
    EXPECT_EQ(sink.frames[i].t_ns % 10'000'000, 0) << i;  // sample times
  EXPECT_EQ(sink.frames.back().sensors[0].state, kStale);
  // A flag changed without a new sample: the next tick publishes it (at the clock's time).
  const size_t before_flag = sink.frames.size();
  core.set_frame_flag(kFrameDemo, true);
  core.advance_clock_to(2'010'000'000);
  ASSERT_EQ(sink.frames.size(), before_flag + 1);
  EXPECT_TRUE(sink.frames.back().flags & kFrameDemo);
  EXPECT_GT(sink.frames.back().t_ns, sink.frames[before_flag - 1].t_ns);
}

// A frame before any sample (a flag set at start-up) is at the clock's time, not at 0: a
// recording's first pose once sat hours before the next (the host's uptime), which put an
// imported take's keys past Blender's last frame.
TEST(PipelineCore, AFrameBeforeAnySampleHasTheClocksTime) {
  TwoSensorCore pipe(100);
  auto& [eng, core, sink] = pipe;
  const int64_t t0 = 47'000'000'000'000LL;  // 13 h after boot
  core.set_frame_flag(kFrameDemo, true);
  core.advance_clock_to(t0);
  core.advance_clock_to(t0 + 20'000'000);
  ASSERT_FALSE(sink.frames.empty());
  EXPECT_EQ(sink.frames.front().t_ns, t0 + 10'000'000);
  core.process(sample(0, t0 + 25'000'000));
  core.advance_clock_to(t0 + 30'000'000);
  ASSERT_GE(sink.frames.size(), 2u);
  EXPECT_EQ(sink.frames.back().t_ns, t0 + 25'000'000);  // then the sample's
}

// Per-sample mode: the frame published after a sample shows that sample (its number, device
// time and turn of its segment), also when the sample is older than the last frame (each
// sensor's clock maps its samples with a delay of its own, so one can come "late"): such a
// sample once got no frame and waited for a newer sample of any sensor.
TEST(PipelineCore, PerSampleFrameShowsTheSample) {
  TwoSensorCore pipe(120, true);
  auto& [eng, core, sink] = pipe;
  for (uint32_t k = 0; k < 100; ++k) {
    for (uint16_t i = 0; i < 2; ++i) {
      // Sensor 1's sample is 100 us older than sensor 0's, which was processed first.
      ImuSample s = sample(i, 1'000'000'000 + k * 5'000'000LL + (i == 0 ? 200'000 : 100'000),
                           i == 1 ? 2.0 : 0.0);
      s.seq = 7 + k;
      s.t_device_ns = 3'000'000'000 + k * 5'000'000LL + i;
      const size_t before = sink.frames.size();
      core.process(s);
      ASSERT_EQ(sink.frames.size(), before + 1) << "sample " << k << " of sensor " << i;
      const PoseFrame& f = sink.frames.back();
      EXPECT_EQ(f.sensors[i].seq, s.seq);
      EXPECT_EQ(f.sensors[i].t_device_ns, s.t_device_ns);
      const int seg = eng.segment[i];
      EXPECT_FLOAT_EQ(f.q_earth_segment[seg][0], static_cast<float>(eng.q[i].w()));
      EXPECT_FLOAT_EQ(f.q_earth_segment[seg][3], static_cast<float>(eng.q[i].z()));
      if (before > 0) {
        EXPECT_GT(f.t_ns, sink.frames[before - 1].t_ns);
      }
    }
  }
  // Sensor 1 turned at 2 rad/s for 99 periods of 5 ms, and the last frame shows it all.
  const auto& q = sink.frames.back().q_earth_segment[3];
  EXPECT_NEAR(2 * std::atan2(q[3], q[0]), 2.0 * 99 * 0.005, 1e-4);
}

TEST(PipelineCore, RejectsNanAndUnknownSensors) {
  test::GyroEngine eng;
  PipelineCore core(PipelineConfig{}, CalibrationConfig{}, two_sensors(), eng);
  ImuSample bad = sample(0, 1000);
  bad.gyr_rad_s.x() = std::nan("");
  core.process(bad);
  core.process(sample(7, 1000));
  core.process(sample(1, 1000));
  EXPECT_EQ(core.rejected_samples(), 2u);
  EXPECT_EQ(core.samples_processed(), 1u);
  EXPECT_EQ(eng.samples, 1u);
}

TEST(PipelineCore, CalibrationAfterCountdownAndPerSampleMode) {
  test::GyroEngine eng;
  PipelineConfig pc;
  pc.publish_every_sample = true;
  CalibrationConfig cc;
  cc.countdown_s = 1.0;
  PipelineCore core(pc, cc, two_sensors(), eng);
  CollectSink sink;
  core.add_sink(&sink);
  core.request_calibration(CalibrationPose::npose, 0);
  core.process(sample(0, 500'000'000));
  EXPECT_EQ(eng.calibrations, 0);
  ASSERT_EQ(sink.frames.size(), 1u);
  EXPECT_TRUE(sink.frames[0].flags & kFrameCalibrating);
  EXPECT_NEAR(sink.frames[0].calib_countdown_s, 0.5, 1e-6);
  core.process(sample(0, 1'000'000'000));
  EXPECT_EQ(eng.calibrations, 1);
  ASSERT_EQ(sink.frames.size(), 2u);
  EXPECT_FALSE(sink.frames[1].flags & kFrameCalibrating);
  EXPECT_TRUE(sink.frames[1].flags & kFrameCalibrated);
}

TEST(Pipeline, LiveThreadsDeliverFramesAndCountDrops) {
  test::GyroEngine eng;
  PipelineConfig pc;
  pc.rate_hz = 200;
  LogSink logs(stderr);
  Pipeline p(pc, CalibrationConfig{}, two_sensors(), eng, Logger(logs, "p", LogLevel::error));
  CollectSink sink;
  p.add_sink(&sink);

  // Before start: overflow sensor 1's ring to count drops.
  for (size_t k = 0; k < Pipeline::kRingCapacity + 10; ++k)
    p.on_sample(sample(1, 1 + static_cast<int64_t>(k)));
  EXPECT_EQ(p.ring_drops(), 10u);

  struct Tap final : mocap::outputs::RecordTap {
    std::atomic<int> raw{0}, samples{0}, frames{0};
    void on_raw(uint16_t, int64_t, std::span<const uint8_t>) override { ++raw; }
    void on_sample(const ImuSample&) override { ++samples; }
    void on_frame(const PoseFrame&) override { ++frames; }
  } tap;
  p.set_record_tap(&tap);
  p.start();
  // Let the pipeline drain the full ring before the producers start: pushing into a ring that
  // is still full would drop more samples, by an amount that depends on scheduling.
  const int64_t drain_deadline = monotonic_ns() + 10'000'000'000;
  while (p.status().samples < Pipeline::kRingCapacity && monotonic_ns() < drain_deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ASSERT_EQ(p.status().samples, Pipeline::kRingCapacity);
  // Two producer threads (one per sensor), like two device reader threads.
  std::vector<std::thread> producers;
  for (uint16_t id = 0; id < 2; ++id) {
    producers.emplace_back([&, id] {
      const uint8_t bytes[3] = {1, 2, 3};
      for (int k = 0; k < 300; ++k) {
        p.on_sample(sample(id, monotonic_ns(), 0.5));
        p.on_raw(id, monotonic_ns(), bytes);
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    });
  }
  for (auto& t : producers)
    t.join();
  p.calibrate(CalibrationPose::tpose);
  p.reset_heading();
  p.set_frame_flag(kFrameDemo, true);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  p.set_record_tap(nullptr);
  const int frames_at_detach = tap.frames.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  p.stop();

  const uint64_t expected = 600 + Pipeline::kRingCapacity;
  EXPECT_EQ(eng.samples, expected);
  EXPECT_EQ(tap.samples.load(), static_cast<int>(expected));
  EXPECT_EQ(tap.raw.load(), 600);
  EXPECT_EQ(tap.frames.load(), frames_at_detach);  // nothing after removal
  EXPECT_GT(sink.count(), 5u);
  EXPECT_EQ(eng.heading_resets, 1);
  const PipelineStatus st = p.status();
  EXPECT_EQ(st.samples, expected);
  EXPECT_EQ(st.ring_drops, 10u);
  EXPECT_TRUE(st.frame.flags & kFrameDemo);
  EXPECT_EQ(st.frame.sensors[1].drops, 10u);
  // Frames are numbered consecutively.
  std::lock_guard l(sink.mu);
  for (size_t i = 1; i < sink.frames.size(); ++i)
    EXPECT_EQ(sink.frames[i].frame, sink.frames[i - 1].frame + 1);
}
