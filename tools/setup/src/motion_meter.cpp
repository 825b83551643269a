// Each sensor's angular speed per window (see motion_meter.hpp).
#include "mocap/setup/motion_meter.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/time.hpp"

namespace mocap::setup {

MotionMeter::MotionMeter(std::size_t sensors) : window_start_ns_(monotonic_ns()) {
  for (std::size_t i = 0; i < sensors; ++i)
    sensors_.push_back(std::make_unique<Sensor>());
}

void MotionMeter::on_sample(const ImuSample& s) {
  if (s.sensor_id >= sensors_.size()) return;
  Sensor& m = *sensors_[s.sensor_id];
  std::lock_guard lk(m.mu);
  ++m.samples;
  ++m.total;
  m.fields |= s.valid;
  if (s.has(kFieldGyr)) {
    m.gyro_sum += s.gyr_rad_s.norm();
    ++m.gyro_count;
  } else if (s.has(kFieldQuat)) {
    const Eigen::Quaterniond q = s.q_device_sensor.normalized();
    if (m.has_q) {
      const Eigen::Quaterniond d = m.last_q.conjugate() * q;
      m.angle_sum += 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
    }
    m.last_q = q;
    m.has_q = true;
  }
}

std::vector<MotionMeter::Window> MotionMeter::take(int64_t now_ns) {
  std::lock_guard wl(window_mu_);
  const double span_s = std::max(1e-3, static_cast<double>(now_ns - window_start_ns_) * 1e-9);
  window_start_ns_ = now_ns;
  std::vector<Window> out(sensors_.size());
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    Sensor& m = *sensors_[i];
    std::lock_guard lk(m.mu);
    out[i].samples = m.samples;
    out[i].rate_hz = static_cast<double>(m.samples) / span_s;
    out[i].speed_rad_s =
        m.gyro_count > 0 ? m.gyro_sum / static_cast<double>(m.gyro_count) : m.angle_sum / span_s;
    m.samples = m.gyro_count = 0;
    m.gyro_sum = m.angle_sum = 0;
  }
  return out;
}

MotionMeter::Seen MotionMeter::seen(std::size_t sensor) const {
  const Sensor& m = *sensors_.at(sensor);
  std::lock_guard lk(m.mu);
  Seen s;
  s.samples = m.total;
  s.fields = m.fields;
  return s;
}

}  // namespace mocap::setup
