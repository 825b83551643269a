// mocap bench skeleton: forward kinematics + joint-limit checking for the thesis's crowd of 150
// avatars x 16 segments, per-joint constraint-check cost, against a baseline measured in the same
// run (a plain loop doing the joint-rotation quaternion multiplies only). With the simulated
// performer (when built): skeleton-only accuracy from ideal sensor orientations (calibration in
// the performer's N-pose window, then joint-angle RMSE and root drift against ground truth).
// Prints one JSON object.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/skeleton/quat_math.hpp"
#include "mocap/skeleton/skeleton.hpp"
#if __has_include("mocap/sim/performer.hpp")
#include "mocap/rig/body_tracker.hpp"
#include "mocap/sim/performer.hpp"
#define MOCAP_BENCH_HAVE_SIM 1
#endif

namespace mocap::bench {

namespace {

using Clock = std::chrono::steady_clock;

double now_ns() {
  return static_cast<double>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
          .count());
}

Eigen::Quaterniond random_q(std::mt19937& rng, double max_deg) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Vector3d axis(n(rng), n(rng), n(rng));
  std::uniform_real_distribution<double> u(0, max_deg * kRadPerDeg);
  return Eigen::Quaterniond(Eigen::AngleAxisd(u(rng), axis.normalized()));
}

// Median of `reps` timings of fn() (ns per call of fn).
template <class F>
double median_ns(int reps, F&& fn) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const double a = now_ns();
    fn();
    t.push_back(now_ns() - a);
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

#ifdef MOCAP_BENCH_HAVE_SIM
/// The body tracker's cost for 15 sensors at 200 Hz (10 s of the performer's walk, frames at
/// 120 Hz) as a fraction of one core, and the same samples through the 15 filters alone (the
/// baseline in the same run). use_mag false: a 6D rig (the knees' axis fits and the joint holds
/// run; the samples reach the filters without their field, the baseline's too). mounting: the
/// N-pose is followed by the mounting motion and the walk (18 s), so every settled segment's
/// heading is held by its fit from then on (the most fits a 6D rig runs).
struct TrackerCost {
  double tracker_core_fraction = 0, filters_core_fraction = 0;
};

TrackerCost tracker_cost(double& sink, bool use_mag, bool mounting) {
  sim::PerformerParams pp;
  pp.motion = mounting ? "calibrate+walk" : "walk";
  pp.rate_hz = 200;
  pp.loop = false;
  sim::Performer perf(pp);
  std::vector<ImuSample> samples;
  const int steps = mounting ? 3600 : 2000;  // 18 / 10 s at 200 Hz
  for (int k = 1; k <= steps; ++k)
    perf.step_to(static_cast<int64_t>(k) * 5'000'000, samples);
  rig::TrackerOptions options;
  options.use_mag = use_mag;
  std::vector<ImuSample> filter_samples = samples;
  if (!use_mag)
    for (ImuSample& s : filter_samples)
      s.valid = static_cast<uint8_t>(s.valid & ~kFieldMag);
  std::vector<rig::TrackerSensor> sensors(sim::Performer::kSensorCount);
  for (int i = 0; i < sim::Performer::kSensorCount; ++i)
    sensors[i].segment = index(sim::Performer::sensor_segment(i));
  const double span_ns = steps * 5e6;
  TrackerCost c;
  c.tracker_core_fraction =
      median_ns(5,
                [&] {
                  rig::BodyTracker t(BodyModel(perf.dims()), default_joint_limits(), sensors,
                                     options);
                  t.start_calibration(CalibrationPose::npose, 1'000'000'000, mounting);
                  PoseFrame f;
                  int64_t next_frame_ns = 0;
                  for (const ImuSample& s : samples) {
                    t.on_sample(s.sensor_id, s);
                    if (s.t_host_ns >= next_frame_ns) {
                      t.solve(s.t_host_ns, f);
                      next_frame_ns += 8'333'333;
                    }
                  }
                  sink = sink + f.q_earth_segment[3][0];
                }) /
      span_ns;
  c.filters_core_fraction =
      median_ns(5,
                [&] {
                  std::vector<AttitudeFilter> filters(sim::Performer::kSensorCount,
                                                      AttitudeFilter(FilterParams{}));
                  for (const ImuSample& s : filter_samples)
                    filters[s.sensor_id].update(s);
                  sink = sink + filters[3].output().q_earth_sensor.w();
                }) /
      span_ns;
  return c;
}
#endif

struct Accuracy {
  bool ran = false;
  std::string motion, message;
  double hinge_rmse_deg = 0, ball_rmse_deg = 0, worst_joint_rmse_deg = 0;
  double root_drift_pct = 0, walked_m = 0, est_travel_m = 0, true_travel_m = 0;
  int frames = 0;
};

#ifdef MOCAP_BENCH_HAVE_SIM
Accuracy accuracy_with_performer(const std::string& motion, bool ankle_contact,
                                 double stance_hysteresis_m) {
  Accuracy a;
  a.motion = motion;
  sim::PerformerParams pp;
  pp.motion = motion;
  pp.loop = false;
  sim::Performer perf(pp);
  RigMapping rig = RigMapping::none();
  for (int s = 0; s < kSegmentCount; ++s)
    rig.sensor_for_segment[s] = sim::Performer::sensor_of(static_cast<Segment>(s));
  rig::CalibrationSetup setup;
  setup.heading = HeadingSource::pelvis_sensor;
  setup.heading_axis_sensor = sim::pelvis_forward_axis_sensor();
  rig::PoseCapturer cal(rig);
  const auto [c0, c1] = perf.calibration_window_s();
  const double dt = 0.01;
  const double cap_start = c0 + 0.25, cap_len = std::min(2.0, c1 - c0 - 0.5);
  cal.start(CalibrationPose::npose, static_cast<int64_t>(cap_start * 1e9));
  for (double t = cap_start; t <= cap_start + cap_len; t += dt)
    for (int id = 0; id < sim::Performer::kSensorCount; ++id)
      cal.add_sample(index(sim::Performer::sensor_segment(id)),
                     perf.sensor_kinematics(id, t).q_earth_sensor, static_cast<int64_t>(t * 1e9));
  rig::Alignment alignment;
  const rig::CalibrationResult r = rig::calibrate(cal.finish(), setup, {}, nullptr, alignment);
  a.message = r.message;
  if (!r.ok()) return a;
  SkeletonOptions so;
  so.root.ankle_contact = ankle_contact;
  if (stance_hysteresis_m > 0) so.root.stance_hysteresis_m = stance_hysteresis_m;
  Skeleton sk(BodyModel(perf.dims()), default_joint_limits(), rig, so);
  sk.set_calibration(r.calibration);
  sim::TruthFrame truth;
  double se_hinge = 0, se_ball = 0;
  int n_hinge = 0, n_ball = 0;
  std::array<double, kSegmentCount> se{};
  PoseFrame f;
  reset_pose(f);
  Eigen::Vector3d start_est = Eigen::Vector3d::Zero(), start_true = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev_true = Eigen::Vector3d::Zero();
  const double t_end = perf.track().motion().duration_s();
  bool first = true;
  for (double t = c1; t <= t_end; t += dt) {
    perf.truth_at(t, truth);
    for (int id = 0; id < sim::Performer::kSensorCount; ++id)
      sk.set_sensor_orientation(index(sim::Performer::sensor_segment(id)),
                                perf.sensor_kinematics(id, t).q_earth_sensor,
                                static_cast<int64_t>(t * 1e9));
    sk.solve(f);
    if (first) {
      start_est = sk.p_earth_segment_m()[0];
      start_true = truth.p_earth_segment_m[0];
      prev_true = start_true;
      first = false;
    }
    a.walked_m += (truth.p_earth_segment_m[0] - prev_true).head<2>().norm();
    prev_true = truth.p_earth_segment_m[0];
    for (int s = 1; s < kSegmentCount; ++s) {
      if (s == index(Segment::neck) || s == index(Segment::head)) continue;  // neck has no sensor
      const double e = angle_between_deg(sk.q_parent_segment()[s], truth.q_parent_segment[s]);
      se[s] += e * e;
      if (is_hinge(static_cast<Segment>(s))) {
        se_hinge += e * e;
        ++n_hinge;
      } else {
        se_ball += e * e;
        ++n_ball;
      }
    }
    ++a.frames;
  }
  a.ran = true;
  a.hinge_rmse_deg = std::sqrt(se_hinge / std::max(1, n_hinge));
  a.ball_rmse_deg = std::sqrt(se_ball / std::max(1, n_ball));
  for (int s = 1; s < kSegmentCount; ++s)
    a.worst_joint_rmse_deg =
        std::max(a.worst_joint_rmse_deg, std::sqrt(se[s] / std::max(1, a.frames)));
  const Eigen::Vector3d d_est = sk.p_earth_segment_m()[0] - start_est;
  const Eigen::Vector3d d_true = truth.p_earth_segment_m[0] - start_true;
  a.est_travel_m = d_est.head<2>().norm();
  a.true_travel_m = d_true.head<2>().norm();
  a.root_drift_pct = a.walked_m > 0.1 ? 100.0 * (d_est - d_true).head<2>().norm() / a.walked_m : 0;
  return a;
}
#endif

int run_skeleton(int avatars, int frames, double stance_hysteresis_m) {
  std::mt19937 rng(7);
  const BodyModel model;
  const JointLimits limits = default_joint_limits();
  // Pre-generated input poses (earth orientations per avatar per frame), a few distinct sets.
  constexpr int kPoseSets = 8;
  std::vector<std::array<Eigen::Quaterniond, kSegmentCount>> poses(kPoseSets);
  for (auto& p : poses) {
    for (int s = 0; s < kSegmentCount; ++s) {
      const int par = kSegmentParent[s];
      p[s] = par < 0 ? random_q(rng, 180) : (p[par] * random_q(rng, 60)).normalized();
    }
  }
  volatile double sink = 0;

  // Baseline: the joint-rotation multiplies alone (q_parent^-1 * q) for the whole crowd.
  const double baseline_ns = median_ns(frames, [&] {
    double acc = 0;
    for (int a = 0; a < avatars; ++a) {
      const auto& p = poses[a % kPoseSets];
      for (int s = 1; s < kSegmentCount; ++s)
        acc += (p[kSegmentParent[s]].conjugate() * p[s]).w();
    }
    sink = sink + acc;
  });

  auto crowd = [&] {
    SkeletonOptions o;
    std::vector<std::unique_ptr<Skeleton>> sk;
    for (int a = 0; a < avatars; ++a)
      sk.push_back(std::make_unique<Skeleton>(model, limits, RigMapping::full(), o));
    std::vector<PoseFrame> out(static_cast<size_t>(avatars));
    int64_t t = 0;
    int frame = 0;
    return median_ns(frames, [&] {
      t += 10'000'000;
      for (int a = 0; a < avatars; ++a) {
        const auto& p = poses[(a + frame) % kPoseSets];
        for (int s = 0; s < kSegmentCount; ++s)
          sk[a]->set_sensor_orientation(s, p[s], t);
        sk[a]->solve(out[a]);
      }
      ++frame;
      sink = sink + out[0].p_earth_segment_m[3][2];
    });
  };
  const double report_ns = crowd();

  // Per-joint constraint check: random joint rotations (about half violate).
  std::vector<Eigen::Quaterniond> jq(4096);
  for (auto& q : jq)
    q = random_q(rng, 120);
  int violated = 0;
  for (size_t k = 0; k < jq.size(); ++k)
    violated += check_joint(limits.joint[1 + k % 15], jq[k]).violated;
  const double check_ns =
      median_ns(50,
                [&] {
                  double acc = 0;
                  for (size_t k = 0; k < jq.size(); ++k)
                    acc += check_joint(limits.joint[1 + k % 15], jq[k]).violation_deg;
                  sink = sink + acc;
                }) /
      static_cast<double>(jq.size());
  Eigen::Quaterniond qc;
  const double clamp_check_ns =
      median_ns(50,
                [&] {
                  double acc = 0;
                  for (size_t k = 0; k < jq.size(); ++k)
                    acc += check_joint(limits.joint[1 + k % 15], jq[k], &qc).violation_deg + qc.w();
                  sink = sink + acc;
                }) /
      static_cast<double>(jq.size());
  const double mul_ns = median_ns(50,
                                  [&] {
                                    Eigen::Quaterniond acc = Eigen::Quaterniond::Identity();
                                    for (size_t k = 0; k < jq.size(); ++k)
                                      acc = acc * jq[k];
                                    sink = sink + acc.w();
                                  }) /
                        static_cast<double>(jq.size());

  std::printf(
      "{\n  \"benchmark\": \"skeleton\",\n  \"avatars\": %d,\n  \"segments\": %d,\n  \"frames\": "
      "%d,\n",
      avatars, kSegmentCount, frames);
  std::printf("  \"crowd_frame_ms\": %.4f,\n", report_ns * 1e-6);
  std::printf("  \"goal_crowd_frame_ms\": 0.5,\n  \"meets_goal\": %s,\n",
              report_ns * 1e-6 <= 0.5 ? "true" : "false");
  std::printf("  \"baseline_joint_multiplies_ms\": %.4f,\n  \"ratio_to_baseline\": %.2f,\n",
              baseline_ns * 1e-6, report_ns / baseline_ns);
  std::printf("  \"ns_per_avatar\": %.1f,\n", report_ns / avatars);
  std::printf(
      "  \"constraint_check_ns_per_joint\": %.1f,\n  \"constraint_check_with_clamp_ns_per_joint\": "
      "%.1f,\n",
      check_ns, clamp_check_ns);
  std::printf(
      "  \"quaternion_multiply_ns\": %.2f,\n  \"check_to_multiply_ratio\": %.1f,\n  "
      "\"violating_fraction\": %.2f",
      mul_ns, check_ns / mul_ns, static_cast<double>(violated) / static_cast<double>(jq.size()));
#ifdef MOCAP_BENCH_HAVE_SIM
  struct RigCase {
    const char* suffix;
    bool use_mag, mounting;
  };
  for (const RigCase r : {RigCase{"", true, false}, RigCase{"_6d", false, false},
                          RigCase{"_6d_mounting_motion", false, true}}) {
    double s = 0;
    const TrackerCost c = tracker_cost(s, r.use_mag, r.mounting);
    sink = sink + s;
    std::printf(
        ",\n  \"body_tracker_15_sensors_200hz%s\": {\"core_fraction\": %.4f, "
        "\"filters_alone_core_fraction\": %.4f, \"ratio_to_filters_alone\": %.3f, "
        "\"goal_core_fraction\": 0.01}",
        r.suffix, c.tracker_core_fraction, c.filters_core_fraction,
        c.tracker_core_fraction / c.filters_core_fraction);
  }
  for (int variant = 0; variant < 2; ++variant) {
    const char* m = variant % 2 == 0 ? "walk" : "sequence";
    const bool ankle = false;
    const Accuracy a = accuracy_with_performer(m, ankle, stance_hysteresis_m);
    std::printf(
        ",\n  \"ideal_orientations_%s_%s\": {\"ok\": %s, \"frames\": %d, \"hinge_rmse_deg\": %.3f, "
        "\"three_dof_rmse_deg\": %.3f, \"worst_joint_rmse_deg\": %.3f, \"walked_m\": %.2f, "
        "\"net_travel_true_m\": %.3f, \"net_travel_est_m\": %.3f, "
        "\"root_drift_pct_of_walked\": %.2f, \"calibration\": \"%s\"}",
        m, ankle ? "ankle_contact" : "heel_toe_contact", a.ran ? "true" : "false", a.frames,
        a.hinge_rmse_deg, a.ball_rmse_deg, a.worst_joint_rmse_deg, a.walked_m, a.true_travel_m,
        a.est_travel_m, a.root_drift_pct, a.message.c_str());
  }
#endif
  std::printf("\n}\n");
  return sink == 12345.678 ? 1 : 0;
}

}  // namespace

void add_skeleton(CLI::App& bench, int& exit_code) {
  struct Options {
    int avatars = 150, frames = 200;
    double stance_hysteresis_m = 0;  // 0: the RootMotionOptions default
  };
  auto o = std::make_shared<Options>();
  CLI::App* c = cli::add_command(bench, "skeleton",
                                 "forward kinematics and joint limits for a crowd of avatars");
  c->add_option("--avatars", o->avatars, "avatars solved per frame")->check(CLI::Range(1, 100000));
  c->add_option("--frames", o->frames, "frames timed")->check(CLI::Range(10, 10000000));
  c->add_option("--stance-hysteresis-m", o->stance_hysteresis_m,
                "root motion's stance hysteresis, m (0: the default)")
      ->check(CLI::NonNegativeNumber);
  c->callback(
      [o, &exit_code] { exit_code = run_skeleton(o->avatars, o->frames, o->stance_hysteresis_m); });
}

}  // namespace mocap::bench
