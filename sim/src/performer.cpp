// Virtual performer: ground-truth kinematics at each sensor (numerical differentiation of the
// exact trajectory: rotation rate from the quaternion change, acceleration of the off-axis mount
// point from second differences of its position) fed through each sensor's error model.
#include "mocap/sim/performer.hpp"

#include <cmath>
#include <stdexcept>

namespace mocap::sim {
namespace {

constexpr int64_t kNsPerS = 1'000'000'000;
// Differentiation step: central differences of a C2 trajectory, error O(h^2) ~ 1e-6 relative,
// round-off ~ 1e-16 / h^2 = 1e-10 m/s^2.
constexpr double kDiffStepS = 1e-3;

std::shared_ptr<const Motion> motion_from(const PerformerParams& p) {
  if (!(p.rate_hz > 0) || p.rate_hz > 10000)
    throw std::invalid_argument("performer rate_hz must be in (0, 10000], got " +
                                std::to_string(p.rate_hz));
  if (!(p.height_m > 0.5 && p.height_m < 2.8))
    throw std::invalid_argument("performer height_m must be in (0.5, 2.8), got " +
                                std::to_string(p.height_m));
  return make_motion(p.motion);
}

}  // namespace

Segment Performer::sensor_segment(int id) {
  return static_cast<Segment>(id < index(Segment::neck) ? id : id + 1);
}

int Performer::sensor_of(Segment s) {
  const int i = index(s);
  if (s == Segment::neck) return -1;
  return i < index(Segment::neck) ? i : i - 1;
}

Performer::Performer(const PerformerParams& params) : Performer(params, motion_from(params)) {}

Performer::Performer(const PerformerParams& params, std::shared_ptr<const Motion> motion)
    : params_(params),
      dims_(motion && motion->dimensions() ? *motion->dimensions()
                                           : body_dimensions_from_height(params.height_m)),
      track_(std::move(motion), dims_, params.loop) {
  if (!(params_.rate_hz > 0)) throw std::invalid_argument("performer rate_hz must be > 0");
  std::mt19937_64 mount_rng(params_.seed * 0x9E3779B97F4A7C15ull + 17);
  errors_.reserve(kSensorCount);
  for (int i = 0; i < kSensorCount; ++i) {
    mounts_[i] = make_mount(sensor_segment(i), dims_, params_.sensor, mount_rng);
    errors_.emplace_back(params_.sensor, params_.rate_hz,
                         params_.seed * 1000003ull + static_cast<uint64_t>(i) * 7919 + 1);
    next_t_ns_[i] = sample_time_ns(i, 0);
  }
  truth_at(0, truth_);
}

int64_t Performer::sample_time_ns(int id, uint32_t k) {
  const double period_s = 1.0 / params_.rate_hz;
  double jitter_s =
      params_.sensor.jitter_sigma_s > 0 ? errors_[id].gauss() * params_.sensor.jitter_sigma_s : 0.0;
  jitter_s = std::clamp(jitter_s, -0.4 * period_s, 0.4 * period_s);
  const double t_s = std::max(0.0, k * period_s + jitter_s);
  return params_.t0_ns + static_cast<int64_t>(std::llround(t_s * kNsPerS));
}

void Performer::truth_at(double t_s, TruthFrame& out) const {
  BodyPose pose;
  track_.pose(t_s, pose);
  truth_forward_kinematics(dims_, pose, out);
  out.t_s = t_s;
}

SensorKinematics Performer::sensor_kinematics(int id, double t_s) const {
  const SensorMount& m = mounts_[id];
  const int seg = index(m.segment);
  Eigen::Quaterniond q[3];
  Eigen::Vector3d p[3];
  TruthFrame f;
  for (int j = 0; j < 3; ++j) {
    truth_at(t_s + (j - 1) * kDiffStepS, f);
    q[j] = f.q_earth_segment[seg] * m.q_segment_sensor;
    p[j] = f.p_earth_segment_m[seg] + f.q_earth_segment[seg] * m.r_segment_sensor_m;
  }
  SensorKinematics k;
  k.q_earth_sensor = q[1];
  k.p_earth_m = p[1];
  // Body-frame rate: the rotation from t-h to t+h over 2h. Its rotation vector is the same in the
  // frames at t-h and t (a rotation leaves its own axis fixed).
  const Eigen::AngleAxisd d(q[0].conjugate() * q[2]);
  k.w_sensor_rad_s = d.angle() * d.axis() / (2 * kDiffStepS);
  // Acceleration as a real IMU's decimation filter reports it: averaged over the sample period
  // (second difference over +-T = triangular window of width 2T). The samples then integrate to
  // the exact velocity change, so a brief impulse (a foot contact switching within
  // milliseconds) is not aliased into a net acceleration bias as instantaneous values at 100 Hz
  // would be (that bias tilted the filters by up to 10 degrees during the walk).
  const double period_s = 1.0 / params_.rate_hz;
  Eigen::Vector3d p_avg[2];
  for (int j = 0; j < 2; ++j) {
    truth_at(t_s + (2 * j - 1) * period_s, f);
    p_avg[j] = f.p_earth_segment_m[seg] + f.q_earth_segment[seg] * m.r_segment_sensor_m;
  }
  k.a_earth_m_s2 = (p_avg[1] - 2 * p[1] + p_avg[0]) / (period_s * period_s);
  return k;
}

void Performer::measure(int id, ImuSample& s) {
  const int64_t t_ns = next_t_ns_[id];
  const double t_s = static_cast<double>(t_ns - params_.t0_ns) / kNsPerS;
  const SensorKinematics k = sensor_kinematics(id, t_s);
  Eigen::Vector3d b_uT;
  if (params_.field.time_varying()) {
    TruthFrame body;
    truth_at(t_s, body);
    b_uT = params_.field.field_uT(k.p_earth_m, t_s, &body);
  } else {
    b_uT = params_.field.field_uT(k.p_earth_m);
  }
  errors_[id].measure(k, b_uT, 1.0 / params_.rate_hz, s);
  s.t_host_ns = t_ns;
  s.t_device_ns = static_cast<int64_t>(std::llround(next_k_[id] * (kNsPerS / params_.rate_hz)));
  s.seq = next_k_[id];
  s.sensor_id = static_cast<uint16_t>(id);
}

void Performer::step_to(int64_t t_host_ns, std::vector<ImuSample>& out) {
  for (;;) {
    int id = 0;
    for (int i = 1; i < kSensorCount; ++i)
      if (next_t_ns_[i] < next_t_ns_[id]) id = i;
    if (next_t_ns_[id] > t_host_ns) break;
    ImuSample s;
    measure(id, s);
    const bool dropped = params_.sensor.drop_probability > 0 &&
                         errors_[id].uniform() < params_.sensor.drop_probability;
    if (dropped) {
      gap_[id] = true;
    } else {
      if (gap_[id]) s.flags |= kFlagGapBefore;
      gap_[id] = false;
      out.push_back(s);
    }
    next_t_ns_[id] = sample_time_ns(id, ++next_k_[id]);
  }
  truth_at(static_cast<double>(t_host_ns - params_.t0_ns) / kNsPerS, truth_);
}

}  // namespace mocap::sim
