// End-to-end accuracy run: virtual performer through filter, calibration and skeleton.
#include "mocap/sim/accuracy.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "mocap/core/units.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/filter/filter_param_names.hpp"
#include "mocap/filter/rig_field_consensus.hpp"
#include "mocap/sim/motion.hpp"
#include "mocap/sim/performer.hpp"
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

RigMapping performer_rig() {
  RigMapping rig = RigMapping::none();
  for (int s = 0; s < kSegmentCount; ++s)
    rig.sensor_for_segment[s] = Performer::sensor_of(static_cast<Segment>(s));
  return rig;
}

}  // namespace

bool is_inferred_joint(Segment child) {
  return child == Segment::neck || child == Segment::head;
}

bool is_measured_three_dof_joint(Segment child) {
  return child != Segment::pelvis && !is_hinge(child) && !is_inferred_joint(child);
}

AccuracyResult run_accuracy(const AccuracyOptions& o) {
  PerformerParams pp;
  pp.seed = o.seed;
  pp.rate_hz = o.rate_hz;
  pp.height_m = o.height_m;
  pp.motion =
      (o.warmup ? "warmup+" : "") + (o.calibration_moves ? "calibrate+" + o.motion : o.motion);
  pp.loop = false;
  pp.sensor = o.sensor;
  pp.field.dipoles = disturbance_preset(o.disturbance, o.height_m);
  Performer perf(pp);

  AccuracyResult r;
  r.motion = o.motion;
  r.disturbance = o.disturbance;

  const RigMapping rig = performer_rig();
  FilterParams fp;
  for (const std::string& a : o.filter_params) {
    std::string err;
    if (!set_filter_param(fp, a, err))
      throw std::invalid_argument("accuracy: filter parameter '" + a + "': " + err);
  }
  std::vector<AttitudeFilter> filters(Performer::kSensorCount, AttitudeFilter(fp));
  std::array<Eigen::Vector3d, Performer::kSensorCount> gyr_scale;
  gyr_scale.fill(Eigen::Vector3d::Ones());
  if (o.gyro_scale_calibration) {
    for (int id = 0; id < Performer::kSensorCount; ++id)
      gyr_scale[id] = calibrated_gyro_scale(perf.sensor_errors(id), o.rate_hz);
  }
  filt::RigFieldConsensus consensus(filters.size());
  CalibratorOptions copt;
  copt.capture_s = o.capture_s;
  copt.heading = o.heading;
  copt.explicit_heading_deg = o.explicit_heading_deg;
  copt.heading_axis_sensor = pelvis_forward_axis_sensor();
  if (o.heading == HeadingSource::mount_normals) {
    copt.heading_axis_sensor = Eigen::Vector3d::UnitZ();  // a strapped sensor's z: the normal
    for (int s = 0; s < kSegmentCount; ++s)
      copt.mount_normal_body[s] = standard_site_normal_body(static_cast<Segment>(s));
  }
  Calibrator calibrator(rig, copt);
  SkeletonOptions sopt;
  sopt.hinge_refine = o.hinge_refine;
  sopt.heading_coupling = o.heading_coupling;
  sopt.relative_mag_heading = o.relative_mag_heading;
  sopt.relative_mag_heading.gyro_scale_calibrated.fill(o.gyro_scale_calibration);
  Skeleton skeleton(BodyModel(perf.dims()), default_joint_limits(), rig, sopt);

  const auto [calib_begin_s, calib_end_s] = perf.calibration_window_s();
  const double capture_start_s = calib_begin_s + o.settle_s;
  if (capture_start_s + o.capture_s > calib_end_s + 1e-9)
    throw std::invalid_argument("accuracy: calibration capture does not fit in the N-pose stand");
  const auto to_ns = [](double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e9)); };
  calibrator.start(CalibrationPose::npose, to_ns(capture_start_s));

  const double frame_s = 1.0 / o.rate_hz;
  const double eval_start_s =
      o.calibration_moves ? calib_end_s + calibration_moves_s() : calib_begin_s;
  const double end_s = perf.track().period_s();
  std::vector<ImuSample> samples;
  samples.reserve(4 * Performer::kSensorCount);
  PoseFrame frame;
  TruthFrame truth;
  std::array<double, kSegmentCount> joint_sq{}, seg_sq{};
  Eigen::Vector3d prev_true_root = Eigen::Vector3d::Zero();
  bool evaluating = false;
  Calibration npose_calibration;
  // Filter heading error at the first evaluated frame, per sensor, and the running sums.
  std::array<double, Performer::kSensorCount> heading0_deg{}, heading_sq{}, incl_sq{},
      mag_disturbed{};
  const auto yaw_deg = [](const Eigen::Quaterniond& q) {
    const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
    return std::atan2(x.y(), x.x()) * kDegPerRad;
  };

  for (int k = 1; k * frame_s <= end_s + 1e-9; ++k) {
    const int64_t t_ns = to_ns(k * frame_s);
    samples.clear();
    perf.step_to(t_ns, samples);
    for (ImuSample& s : samples) {
      AttitudeFilter& f = filters[s.sensor_id];
      s.gyr_rad_s = s.gyr_rad_s.cwiseQuotient(gyr_scale[s.sensor_id]);
      f.update(s);
      const int seg = index(Performer::sensor_segment(s.sensor_id));
      const Eigen::Quaterniond q = f.q_earth_sensor();
      if (calibrator.capturing()) {
        calibrator.add_sample(seg, q, s.t_host_ns, &s.acc_m_s2);
      } else if (r.calibrated) {
        uint32_t flags = f.at_rest() ? uint32_t{kSegAtRest} : 0u;
        if (f.mag_disturbed()) flags |= kSegMagDisturbed;
        if (f.mag_no_reference()) flags |= kSegMagNoReference;
        skeleton.set_sensor_orientation(seg, q, s.t_host_ns, flags, f.mag_heading_rad());
      }
    }
    if (o.rig_consensus) consensus.step(t_ns, filters);
    if (calibrator.capturing() && calibrator.done(t_ns)) {
      const CalibrationResult cr = calibrator.finish();
      r.calibration_message = cr.message;
      if (!cr.ok()) return r;
      r.calibrated = true;
      skeleton.set_calibration(cr.calibration);
      npose_calibration = cr.calibration;
      if (o.anchor_heading)
        for (AttitudeFilter& f : filters)
          f.anchor_heading();
      perf.truth_at(k * frame_s, truth);
      skeleton.root_motion().reset(truth.p_earth_segment_m[0]);
      prev_true_root = truth.p_earth_segment_m[0];
      continue;
    }
    if (!r.calibrated) continue;
    if (k * frame_s < eval_start_s) {
      skeleton.solve(frame);  // the calibration moves: refinement only, not evaluated
      perf.truth_at(k * frame_s, truth);
      prev_true_root = truth.p_earth_segment_m[0];
      continue;
    }
    if (!evaluating) {
      // Every sensor must have delivered an orientation since calibration.
      evaluating = true;
      continue;
    }
    skeleton.solve(frame);
    perf.truth_at(k * frame_s, truth);
    for (int s = 0; s < kSegmentCount; ++s) {
      const double e_seg = angle_deg(skeleton.q_earth_segment()[s], truth.q_earth_segment[s]);
      seg_sq[s] += e_seg * e_seg;
      if (s > 0) {
        const double e = angle_deg(skeleton.q_parent_segment()[s], truth.q_parent_segment[s]);
        joint_sq[s] += e * e;
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
          (filters[id].q_earth_sensor() *
           perf.sensor_kinematics(id, k * frame_s).q_earth_sensor.conjugate())
              .normalized();
      const double h = yaw_deg(q_err);
      if (r.frames == 1) heading0_deg[id] = h;
      const double dh = std::remainder(h - heading0_deg[id], 360.0);
      heading_sq[id] += dh * dh;
      if (filters[id].mag_disturbed()) ++mag_disturbed[id];
      const double c = std::clamp((q_err * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0);
      incl_sq[id] += std::pow(std::acos(c) * kDegPerRad, 2);
    }
  }
  if (r.frames == 0) return r;
  r.evaluated_s = r.frames * frame_s;
  double seg_sum = 0;
  int seg_n = 0;
  for (int s = 0; s < kSegmentCount; ++s) {
    const Segment seg = static_cast<Segment>(s);
    r.segment_rmse_deg[s] = std::sqrt(seg_sq[s] / r.frames);
    if (Performer::sensor_of(seg) >= 0) {
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
  // Calibration diagnostics: the mounting's yaw about the segment's vertical vs the true mount.
  const Calibration& used = skeleton.calibration();
  r.hinges_identified = skeleton.hinge_refiner().valid_hinges();
  r.hinges = skeleton.hinge_refiner().hinges();
  r.coupling = skeleton.heading_coupling().hinges();
  for (int id = 0; id < Performer::kSensorCount; ++id) {
    const int s = index(Performer::sensor_segment(id));
    const Eigen::Quaterniond& q_seg_sensor = perf.mount(id).q_segment_sensor;
    r.npose_mount_yaw_error_deg[s] = yaw_deg(q_seg_sensor * npose_calibration.q_sensor_segment[s]);
    r.mount_yaw_error_deg[s] = yaw_deg(q_seg_sensor * used.q_sensor_segment[s]);
    r.sensor_heading_drift_deg[s] = std::sqrt(heading_sq[id] / r.frames);
    r.sensor_inclination_rmse_deg[s] = std::sqrt(incl_sq[id] / r.frames);
    r.sensor_mag_disturbed_fraction[s] = mag_disturbed[id] / r.frames;
    r.sensor_ref_imposed[s] = filters[id].mag_reference_imposed();
    r.sensor_anchor_trust_deg[s] = filters[id].anchor_trust_rad() * kDegPerRad;
  }
  r.root_drift_fraction = r.distance_walked_m >= 1.0 ? r.root_drift_m / r.distance_walked_m : 0.0;
  return r;
}

}  // namespace mocap::sim
