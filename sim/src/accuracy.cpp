// End-to-end accuracy run: the virtual performer through the body tracker, and through each
// sensor's filter alone, against the truth.
#include "mocap/sim/accuracy.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "mocap/core/units.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/filter/filter_param_names.hpp"
#include "mocap/rig/body_tracker.hpp"
#include "mocap/sim/motion.hpp"
#include "mocap/sim/performer.hpp"
#include "mocap/sim/segment_metric.hpp"
#include "mocap/sim/table_spin.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/joint_limits.hpp"
#include "mocap/skeleton/pose_frame.hpp"
#include "mocap/skeleton/sensor_sites.hpp"
#include "mocap/skeleton/skeleton.hpp"

namespace mocap::sim {
namespace {

double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return 2 * std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * kDegPerRad;
}

double yaw_deg(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x()) * kDegPerRad;
}

}  // namespace

bool is_inferred_joint(Segment child) {
  return child == Segment::neck || child == Segment::head;
}

bool is_measured_three_dof_joint(Segment child) {
  return child != Segment::pelvis && !is_hinge(child) && !is_inferred_joint(child);
}

bool in_rig(AccuracyOptions::Rig rig, Segment s) {
  if (Performer::sensor_of(s) < 0) return false;
  if (rig == AccuracyOptions::Rig::full) return true;
  switch (s) {
    case Segment::pelvis:
    case Segment::thigh_l:
    case Segment::thigh_r:
    case Segment::shank_l:
    case Segment::shank_r:
    case Segment::foot_l:
    case Segment::foot_r:
      return true;
    default:
      return false;
  }
}

AccuracyResult run_accuracy(const AccuracyOptions& o) {
  PerformerParams pp;
  pp.seed = o.seed;
  pp.rate_hz = o.rate_hz;
  pp.height_m = o.height_m;
  pp.motion = (o.session_s > 0 ? "session" + std::to_string(o.session_s) + "+" : "") +
              (o.warmup ? "warmup+" : "") +
              (o.calibration_moves ? "calibrate+" + o.motion : o.motion);
  pp.loop = false;
  pp.sensor = o.sensor;
  Performer perf(pp);
  const auto [calib_begin_s, calib_end_s] = perf.calibration_window_s();
  const double motion_start_s =
      o.calibration_moves ? calib_end_s + calibration_moves_s() : calib_begin_s;
  const double score_start_s = motion_start_s + o.score_after_s;
  // A disturbance with a time window starts 2 s into the motion.
  pp.field.dipoles = disturbance_preset(o.disturbance, o.height_m, motion_start_s + 2.0);
  if (!pp.field.dipoles.empty()) perf = Performer(pp);

  AccuracyResult r;
  r.motion = o.motion;
  r.disturbance = o.disturbance;

  FilterParams fp;
  for (const std::string& a : o.filter_params) {
    std::string err;
    if (!set_filter_param(fp, a, err))
      throw std::invalid_argument("accuracy: filter parameter '" + a + "': " + err);
  }
  // The body tracker, as mocapd builds it for a rig of the performer's sensors.
  std::vector<rig::TrackerSensor> sensors(Performer::kSensorCount);
  for (int id = 0; id < Performer::kSensorCount; ++id) {
    const Segment seg = Performer::sensor_segment(id);
    sensors[id].segment = in_rig(o.rig, seg) ? index(seg) : -1;
    sensors[id].fused_on_device = o.fused_on_device;
    if (o.gyro_scale_calibration)
      sensors[id].gyr_scale = calibrated_gyro_scale(perf.sensor_errors(id), o.rate_hz);
  }
  rig::TrackerOptions topt;
  topt.filter = fp;
  topt.use_mag = o.use_mag;
  topt.capture.capture_s = o.capture_s;
  topt.calibration.heading = o.heading;
  topt.calibration.explicit_heading_deg = o.explicit_heading_deg;
  topt.calibration.heading_axis_sensor = pelvis_forward_axis_sensor();
  rig::BodyTracker tracker(BodyModel(perf.dims()), default_joint_limits(), sensors, topt);

  // The reference: the same samples through each sensor's filter alone, no body model; in 6D
  // each aligned once at calibration to its sensor's true heading (the ideal alignment).
  std::vector<AttitudeFilter> alone(Performer::kSensorCount, AttitudeFilter(fp));
  std::array<Eigen::Quaterniond, Performer::kSensorCount> alone_align;
  alone_align.fill(Eigen::Quaterniond::Identity());
  const auto alone_q = [&](int id) {
    const FilterOutput out = alone[id].output();
    return o.use_mag ? out.q_earth_sensor : out.q_earth_sensor_6d;
  };
  std::array<bool, kSegmentCount> scored{};
  for (int s = 0; s < kSegmentCount; ++s)
    scored[s] = in_rig(o.rig, static_cast<Segment>(s));
  SegmentMetric metric(scored), alone_metric(scored);

  const double capture_start_s = calib_begin_s + o.settle_s;
  if (capture_start_s + o.capture_s > calib_end_s + 1e-9)
    throw std::invalid_argument("accuracy: calibration capture does not fit in the N-pose stand");
  const auto to_ns = [](double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e9)); };
  tracker.start_calibration(CalibrationPose::npose, to_ns(capture_start_s),
                            o.calibration_moves && o.mounting_motion);

  // Frames fall on the sample times (the performer's sensors sample together).
  const double frame_s = 1.0 / (o.frame_rate_hz > 0 ? o.frame_rate_hz : o.rate_hz);
  const double end_s = perf.track().period_s();
  std::vector<ImuSample> samples;
  samples.reserve(4 * Performer::kSensorCount);
  PoseFrame frame;
  TruthFrame truth;
  std::array<double, kSegmentCount> joint_sq{}, seg_sq{};
  // The dropped segment's joint to its parent; the root's, its joint with the torso; every
  // joint when every sensor drops.
  const bool drop_all = o.dropout_segment == AccuracyOptions::kDropoutAll;
  const int drop_joint = o.dropout_segment == 0 ? index(Segment::torso) : o.dropout_segment;
  double drop_before_sq = 0, drop_after_sq = 0;
  int drop_before_n = 0, drop_after_n = 0;
  Eigen::Vector3d prev_true_root = Eigen::Vector3d::Zero();
  bool evaluating = false;
  // Filter heading error at the first evaluated frame, per sensor, and the running sums.
  std::array<double, Performer::kSensorCount> heading0_deg{}, heading_sq{}, incl_sq{},
      mag_disturbed{};
  std::array<Eigen::Quaterniond, kSegmentCount> prev_est, prev_alone;  // the last evaluated frame

  for (int k = 1; k * frame_s <= end_s + 1e-9; ++k) {
    const int64_t t_ns = to_ns(k * frame_s);
    samples.clear();
    perf.step_to(t_ns, samples);
    const double dropout_from_s = motion_start_s + o.dropout_start_s;
    const bool dropping =
        k * frame_s >= dropout_from_s && k * frame_s < dropout_from_s + o.dropout_s;
    for (ImuSample& s : samples) {
      const bool dropped = dropping && (drop_all || index(Performer::sensor_segment(s.sensor_id)) ==
                                                        o.dropout_segment);
      if (dropped && !o.fused_on_device) continue;
      if (dropped)
        tracker.filter_sample(s.sensor_id, s);  // the device's own fusion runs on; unsent
      else
        tracker.on_sample(s.sensor_id, s);
      ImuSample a = s;
      a.gyr_rad_s = a.gyr_rad_s.cwiseQuotient(tracker.sensor(s.sensor_id).gyr_scale);
      if (!o.use_mag) a.valid = static_cast<uint8_t>(a.valid & ~kFieldMag);
      alone[s.sensor_id].update(a);
    }
    if (auto cr = tracker.take_calibration_result()) {
      r.calibration_message = cr->message;
      if (!cr->ok()) return r;
      r.calibrated = true;
      r.pose_deviation_deg = cr->pose_deviation_deg;
      perf.truth_at(k * frame_s, truth);
      tracker.skeleton().root_motion().reset(truth.p_earth_segment_m[0]);
      for (int id = 0; id < Performer::kSensorCount && !o.use_mag; ++id) {
        const Eigen::Quaterniond e =
            alone_q(id) * perf.sensor_kinematics(id, k * frame_s).q_earth_sensor.conjugate();
        alone_align[id] = Eigen::AngleAxisd(-yaw_deg(e) * kRadPerDeg, Eigen::Vector3d::UnitZ());
      }
      prev_true_root = truth.p_earth_segment_m[0];
      continue;
    }
    if (!r.calibrated) continue;
    tracker.solve(t_ns, frame);
    perf.truth_at(k * frame_s, truth);
    if (k * frame_s < score_start_s || !evaluating) {
      // The calibration moves, and the first frame after them (every sensor must have
      // delivered an orientation since calibration): not evaluated.
      evaluating = k * frame_s >= score_start_s;
      prev_true_root = truth.p_earth_segment_m[0];
      continue;
    }
    const Skeleton& skeleton = tracker.skeleton();
    {
      SegmentMetric::Orientations q_alone, q_true;
      for (int s = 0; s < kSegmentCount; ++s)
        q_true[s] = truth.q_earth_segment[s];
      q_alone = q_true;
      for (int id = 0; id < Performer::kSensorCount; ++id)
        q_alone[index(Performer::sensor_segment(id))] = alone_align[id] * alone_q(id);
      metric.add(skeleton.q_earth_segment(), q_true);
      alone_metric.add(q_alone, q_true);
      for (int id = 0; id < Performer::kSensorCount; ++id) {
        const int s = index(Performer::sensor_segment(id));
        if (!scored[s]) continue;
        if (r.frames > 0) {
          const double jump = angle_deg(skeleton.q_earth_segment()[s], prev_est[s]) -
                              angle_deg(q_alone[s], prev_alone[s]);
          r.max_jump_deg[s] = std::max(r.max_jump_deg[s], jump);
        }
        prev_est[s] = skeleton.q_earth_segment()[s];
        prev_alone[s] = q_alone[s];
      }
    }
    for (int s = 0; s < kSegmentCount; ++s) {
      const double e_seg = angle_deg(skeleton.q_earth_segment()[s], truth.q_earth_segment[s]);
      seg_sq[s] += e_seg * e_seg;
      if (s > 0) {
        const double e = angle_deg(skeleton.q_parent_segment()[s], truth.q_parent_segment[s]);
        joint_sq[s] += e * e;
        if (o.dropout_segment >= 0 && (s == drop_joint || drop_all)) {
          const double since_s = k * frame_s - motion_start_s - o.dropout_start_s;
          if (since_s < 0) drop_before_sq += e * e, ++drop_before_n;
          if (since_s >= o.dropout_s + 5.0) drop_after_sq += e * e, ++drop_after_n;
        }
      }
    }
    const Eigen::Vector3d d = skeleton.p_earth_segment_m()[0] - truth.p_earth_segment_m[0];
    r.root_drift_m = d.head<2>().norm();
    r.root_max_error_m = std::max(r.root_max_error_m, r.root_drift_m);
    r.distance_walked_m += (truth.p_earth_segment_m[0] - prev_true_root).head<2>().norm();
    prev_true_root = truth.p_earth_segment_m[0];
    ++r.frames;
    // The filters' own error (vs the sensor's true orientation): inclination, and the change of
    // the heading error since the evaluation began (a constant one is absorbed by calibration).
    for (int id = 0; id < Performer::kSensorCount; ++id) {
      const Eigen::Quaterniond q_err =
          (tracker.q_earth_sensor(id) *
           perf.sensor_kinematics(id, k * frame_s).q_earth_sensor.conjugate())
              .normalized();
      const double h = yaw_deg(q_err);
      if (r.frames == 1) heading0_deg[id] = h;
      const double dh = std::remainder(h - heading0_deg[id], 360.0);
      heading_sq[id] += dh * dh;
      if (tracker.filter(id).output().flags.mag_disturbed && o.use_mag) ++mag_disturbed[id];
      const double c = std::clamp((q_err * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0);
      incl_sq[id] += std::pow(std::acos(c) * kDegPerRad, 2);
    }
  }
  if (r.frames < 2) return r;  // no rotation since the reference instant to score
  r.evaluated_s = r.frames * frame_s;
  if (drop_before_n > 0) r.dropout_joint_before_deg = std::sqrt(drop_before_sq / drop_before_n);
  if (drop_after_n > 0) r.dropout_joint_after_deg = std::sqrt(drop_after_sq / drop_after_n);
  double seg_sum = 0;
  int seg_n = 0;
  for (int s = 0; s < kSegmentCount; ++s) {
    const Segment seg = static_cast<Segment>(s);
    r.segment_rmse_deg[s] = std::sqrt(seg_sq[s] / r.frames);
    if (scored[s]) {
      seg_sum += r.segment_rmse_deg[s];
      ++seg_n;
    }
    if (s == 0) continue;
    r.joint_rmse_deg[s] = std::sqrt(joint_sq[s] / r.frames);
    double& worst = is_hinge(seg)                      ? r.hinge_max_rmse_deg
                    : is_measured_three_dof_joint(seg) ? r.three_dof_max_rmse_deg
                                                       : r.inferred_max_rmse_deg;
    worst = std::max(worst, r.joint_rmse_deg[s]);
  }
  r.segment_mean_rmse_deg = seg_sum / seg_n;
  const SegmentMetric::Result mr = metric.result(), ar = alone_metric.result();
  r.metric_segment_deg = mr.segment_rms_deg;
  r.metric_segment_alone_g_deg = metric.result(&ar.g).segment_rms_deg;
  r.alone_segment_deg = ar.segment_rms_deg;
  r.metric_mean_deg = mr.mean_deg;
  r.alone_mean_deg = ar.mean_deg;
  // Calibration diagnostics: the mounting's yaw about the segment's vertical vs the true mount.
  const Calibration& used = tracker.skeleton().calibration();
  for (int id = 0; id < Performer::kSensorCount; ++id) {
    const int s = index(Performer::sensor_segment(id));
    if (!scored[s]) continue;
    const Eigen::Quaterniond& q_seg_sensor = perf.mount(id).q_segment_sensor;
    r.mount_yaw_error_deg[s] = yaw_deg(q_seg_sensor * used.q_sensor_segment[s]);
    r.sensor_heading_drift_deg[s] = std::sqrt(heading_sq[id] / r.frames);
    r.sensor_inclination_rmse_deg[s] = std::sqrt(incl_sq[id] / r.frames);
    r.sensor_mag_disturbed_fraction[s] = mag_disturbed[id] / r.frames;
  }
  r.root_drift_fraction = r.distance_walked_m >= 1.0 ? r.root_drift_m / r.distance_walked_m : 0.0;
  return r;
}

}  // namespace mocap::sim
