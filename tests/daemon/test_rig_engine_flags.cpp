// The magnetometer states a frame reports per segment and sensor: during the filters' start-up
// every tracked segment says "no reference field yet" (kSegMagNoReference), not "disturbed";
// once the standing, then walking, virtual performer has given each filter a consistent field,
// no segment says either. With a magnet beside the right hip at the start position, the rig's
// consensus gives the sensors beside it the earth field's reference that the others agree on.
// The performer's samples go through the real RigEngine.
#include <gtest/gtest.h>

#include "mocap/daemon/config.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/sim/performer.hpp"

namespace mocap::daemon {
namespace {

std::optional<Config> performer_rig() {
  ConfigErrors errs;
  std::optional<Config> cfg = parse_config("", "<defaults>", {}, errs);
  EXPECT_TRUE(cfg) << errs.to_string();
  if (!cfg) return cfg;
  for (int i = 0; i < sim::Performer::kSensorCount; ++i) {
    SensorConfig s;
    s.name = std::string(sim::Performer::sensor_name(i));
    s.segment = s.name;
    s.driver = "direct";
    cfg->sensors.push_back(s);
  }
  return cfg;
}

TEST(DaemonMagFlags, NoReferenceDuringStartUpThenNeitherFlag) {
  std::optional<Config> cfg = performer_rig();
  ASSERT_TRUE(cfg);
  sim::PerformerParams pp;
  pp.motion = "walk";
  sim::Performer perf(pp);
  RigEngine engine(*cfg);
  PoseFrame frame;
  std::vector<ImuSample> samples;
  auto count = [&](uint32_t bit) {
    int n = 0;
    for (int s = 0; s < kSegmentCount; ++s)
      if ((frame.segment_flags[s] & kSegTracked) && (frame.segment_flags[s] & bit)) ++n;
    return n;
  };
  int tracked = 0, no_ref_early = -1, disturbed_early = -1;
  for (int k = 1; k <= 3000; ++k) {  // 30 s at 100 Hz
    const int64_t t_ns = static_cast<int64_t>(k) * 10'000'000;
    samples.clear();
    perf.step_to(t_ns, samples);
    for (const ImuSample& s : samples)
      engine.on_sample(s.sensor_id, s);
    if (k % 10 != 0) continue;
    engine.build_frame(t_ns, frame);
    if (k == 50) {  // 0.5 s: every filter is still in its start-up
      tracked = count(kSegTracked);
      no_ref_early = count(kSegMagNoReference);
      disturbed_early = count(kSegMagDisturbed);
      for (int i = 0; i < sim::Performer::kSensorCount; ++i)
        EXPECT_TRUE(engine.sensor_health(i).mag_no_reference) << i;
    }
  }
  EXPECT_EQ(tracked, sim::Performer::kSensorCount);
  EXPECT_EQ(no_ref_early, tracked);
  EXPECT_EQ(disturbed_early, 0);
  EXPECT_EQ(count(kSegMagNoReference), 0);
  EXPECT_EQ(count(kSegMagDisturbed), 0);
  for (int i = 0; i < sim::Performer::kSensorCount; ++i)
    EXPECT_FALSE(engine.sensor_health(i).mag_no_reference) << i;
}

// A SlimeVR tracker over UDP computes its orientation itself and keeps doing so through a
// silence of the link: the body tracker is told so (its heading survives the silence, a
// reboot loses it); the dongle's trackers and every other driver are not.
TEST(DaemonTrackerSensors, SlimeVrOverUdpIsFusedOnTheDevice) {
  std::optional<Config> cfg = performer_rig();
  ASSERT_TRUE(cfg);
  cfg->sensors[0].driver = "slimevr";
  cfg->sensors[1].driver = "slimevr_hid";
  cfg->sensors[2].driver = "witmotion";
  const std::vector<rig::TrackerSensor> t = tracker_sensors(*cfg);
  ASSERT_EQ(t.size(), cfg->sensors.size());
  EXPECT_TRUE(t[0].fused_on_device);
  EXPECT_FALSE(t[1].fused_on_device);
  EXPECT_FALSE(t[2].fused_on_device);
  EXPECT_FALSE(t[3].fused_on_device);  // "direct": the performer's samples
}

}  // namespace
}  // namespace mocap::daemon
