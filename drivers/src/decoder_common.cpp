// Shared decoder tail: time mapping, axis remap, NaN guard (see decoder_common.hpp).
#include "decoder_common.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "mocap/core/units.hpp"

namespace mocap {

DecoderCommon::DecoderCommon(const DeviceSpec& spec, SensorRange range)
    : sensor_id(spec.first_sensor_id),
      gyr_max_rad_s_(option_double(spec, "gyr_range_dps", range.gyr_dps) * kRadPerDeg),
      acc_max_m_s2_(option_double(spec, "acc_range_g", range.acc_g) * 9.80665),
      remap_(AxisRemap::parse(spec.axis_remap)) {
  if (!(gyr_max_rad_s_ > 0) || !(acc_max_m_s2_ > 0))
    throw std::invalid_argument("device " + spec.name +
                                ": gyr_range_dps and acc_range_g must be positive");
}

void DecoderCommon::check_range(ImuSample& s) {
  // Beyond 1.1 x full scale no reading of this sensor can be: a glitch behind a valid checksum
  // (dropped). At >= 0.99 x full scale the axis is clipped, or pegged by a glitch (flagged).
  bool implausible = false, saturated = false;
  auto check = [&](const Eigen::Vector3d& v, double full_scale, uint8_t field) {
    if (!(s.valid & field)) return false;
    const double m = v.cwiseAbs().maxCoeff();
    if (m > 1.1 * full_scale) {
      s.valid &= static_cast<uint8_t>(~field);
      implausible = true;
    } else if (m >= 0.99 * full_scale) {
      saturated = true;
      return true;
    }
    return false;
  };
  if (check(s.gyr_rad_s, gyr_max_rad_s_, kFieldGyr)) s.flags |= kFlagGyrClipped;
  check(s.acc_m_s2, acc_max_m_s2_, kFieldAcc);
  if (implausible) s.flags |= kFlagImplausible, ++stats.implausible;
  if (saturated) s.flags |= kFlagSaturated, ++stats.saturated;
}

void DecoderCommon::emit(ImuSample& s, int64_t t_device_ns, int64_t t_read_ns, int64_t dropped,
                         SampleSink& sink) {
  bool reset = false;
  s.t_host_ns = clock_.map(t_device_ns, t_read_ns, reset);
  s.t_device_ns = t_device_ns;
  if (reset) {
    s.flags |= kFlagClockReset;
    ++stats.clock_resets;
  }
  if (dropped > 0) {
    s.flags |= kFlagGapBefore;
    stats.dropped_samples += static_cast<uint64_t>(dropped);
  }
  seq_ += static_cast<uint32_t>(dropped > 0 ? dropped : 0);
  const uint64_t before = stats.samples;
  finish(s, sink);
  stats.timed_samples += stats.samples - before;
}

void DecoderCommon::emit_untimed(ImuSample& s, int64_t t_read_ns, SampleSink& sink) {
  if (first_read_ns_ < 0) first_read_ns_ = t_read_ns;
  s.t_host_ns = t_read_ns;
  s.t_device_ns = t_read_ns - first_read_ns_;
  finish(s, sink);
}

void DecoderCommon::finish(ImuSample& s, SampleSink& sink) {
  if (!s.gyr_rad_s.allFinite()) s.valid &= ~kFieldGyr;
  if (!s.acc_m_s2.allFinite()) s.valid &= ~kFieldAcc;
  if (!s.mag_uT.allFinite()) s.valid &= ~kFieldMag;
  check_range(s);
  if (s.has(kFieldQuat)) {
    const double n = s.q_device_sensor.norm();
    if (!std::isfinite(n) || n < 0.5 || n > 1.5) {
      s.valid &= ~kFieldQuat;
      s.q_device_sensor = Eigen::Quaterniond::Identity();
    } else {
      s.q_device_sensor.normalize();
    }
  }
  if (s.valid == 0) return;
  if (!remap_.identity()) {
    s.gyr_rad_s = remap_.apply(s.gyr_rad_s);
    s.acc_m_s2 = remap_.apply(s.acc_m_s2);
    s.mag_uT = remap_.apply(s.mag_uT);
    if (s.has(kFieldQuat)) s.q_device_sensor = remap_.apply(s.q_device_sensor);
  }
  // Host time never runs backwards for one sensor (clock resets, timed/untimed mixes).
  s.t_host_ns = std::max(s.t_host_ns, last_host_ns_);
  last_host_ns_ = s.t_host_ns;
  s.sensor_id = sensor_id;
  s.seq = seq_++;
  ++stats.samples;
  sink.on_sample(s);
}

double option_double(const DeviceSpec& spec, const char* key, double fallback) {
  const auto it = spec.options.find(key);
  if (it == spec.options.end()) return fallback;
  double v = 0;
  const auto& str = it->second;
  const auto r = std::from_chars(str.data(), str.data() + str.size(), v);
  if (r.ec != std::errc() || r.ptr != str.data() + str.size() || !std::isfinite(v))
    throw std::invalid_argument("device " + spec.name + ": option " + key + "=\"" + str +
                                "\" is not a number");
  return v;
}

std::string option_string(const DeviceSpec& spec, const char* key, const char* fallback) {
  const auto it = spec.options.find(key);
  return it == spec.options.end() ? std::string(fallback) : it->second;
}

}  // namespace mocap
