// VRChat OSC trackers: our ENU segment poses to Unity world positions and Euler angles (Unity's
// Z-X-Y order), one OSC message per UDP datagram.
#include "mocap/outputs/vrchat.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/outputs/osc.hpp"

namespace mocap::outputs {
namespace {

/// Wraps degrees to (-180, 180].
double vrchat_wrap_deg(double a) {
  a = std::remainder(a, 360.0);
  return a <= -180.0 ? a + 360.0 : a;
}

}  // namespace

std::array<float, 3> unity_euler_deg(const std::array<double, 4>& q) noexcept {
  // Numerically Unity rotates a vector by a quaternion as Eigen does; only the axes differ.
  const Eigen::Matrix3d r =
      Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
  // R = Ry(b) Rx(a) Rz(c): R(1,2) = -sin a; R(1,0) = cos a sin c, R(1,1) = cos a cos c;
  // R(0,2) = sin b cos a, R(2,2) = cos b cos a.
  const double sa = std::clamp(-r(1, 2), -1.0, 1.0);
  const double a = std::asin(sa);
  double b, c;
  if (std::abs(sa) < 1.0 - 1e-9) {
    c = std::atan2(r(1, 0), r(1, 1));
    b = std::atan2(r(0, 2), r(2, 2));
  } else {  // gimbal lock: only b +- c is defined; put it all in b
    c = 0.0;
    b = std::atan2(-r(2, 0), r(0, 0));
  }
  return {static_cast<float>(a * kDegPerRad), static_cast<float>(vrchat_wrap_deg(b * kDegPerRad)),
          static_cast<float>(vrchat_wrap_deg(c * kDegPerRad))};
}

bool vrchat_tracker_from_frame(const PoseFrame& f, int s, double scale,
                               VrchatTracker& out) noexcept {
  if (s < 0 || s >= kSegmentCount) return false;
  const auto& q = f.q_earth_segment[s];
  const auto& p = f.p_earth_segment_m[s];
  Eigen::Quaterniond qe(q[0], q[1], q[2], q[3]);
  const Eigen::Vector3d pe(p[0], p[1], p[2]);
  if (!qe.coeffs().allFinite() || !pe.allFinite() || qe.norm() < 1e-6 || !std::isfinite(scale))
    return false;
  qe.normalize();
  // x_u = -y, y_u = z, z_u = x (determinant -1): a quaternion's vector part becomes -M v.
  out.p = {static_cast<float>(-pe.y() * scale), static_cast<float>(pe.z() * scale),
           static_cast<float>(pe.x() * scale)};
  out.euler_deg = unity_euler_deg({qe.y(), -qe.z(), -qe.x(), qe.w()});
  return true;
}

bool VrchatSender::open(const Options& options, std::string* error) {
  options_ = options;
  return target_.open(options, "VRChat", error);
}

bool VrchatSender::publish(const PoseFrame& frame) noexcept {
  if (!target_.due(frame.t_ns, stats_)) return false;
  std::array<VrchatTracker, kVrchatTrackerSlots> trackers;
  VrchatTracker head;
  for (int i = 0; i < kVrchatTrackerSlots; ++i) {
    if (options_.slots[i] < 0) continue;
    if (!vrchat_tracker_from_frame(frame, options_.slots[i], options_.scale, trackers[i])) {
      ++stats_.frames_invalid;
      return false;
    }
  }
  if (options_.head &&
      !vrchat_tracker_from_frame(frame, index(Segment::head), options_.scale, head)) {
    ++stats_.frames_invalid;
    return false;
  }
  target_.sent(frame.t_ns);

  bool ok = true;
  auto send = [&](const char* address, const std::array<float, 3>& v) {
    osc::MessageWriter m(message_, sizeof message_);
    m.address(address).tags(",fff").f32(v[0]).f32(v[1]).f32(v[2]);
    if (!m.ok()) return;
    if (!target_.send(message_, m.size())) {
      ++stats_.send_errors;
      ok = false;
    } else {
      ++stats_.messages_sent;
    }
  };
  static constexpr const char* kPosition[kVrchatTrackerSlots] = {
      "/tracking/trackers/1/position", "/tracking/trackers/2/position",
      "/tracking/trackers/3/position", "/tracking/trackers/4/position",
      "/tracking/trackers/5/position", "/tracking/trackers/6/position",
      "/tracking/trackers/7/position", "/tracking/trackers/8/position"};
  static constexpr const char* kRotation[kVrchatTrackerSlots] = {
      "/tracking/trackers/1/rotation", "/tracking/trackers/2/rotation",
      "/tracking/trackers/3/rotation", "/tracking/trackers/4/rotation",
      "/tracking/trackers/5/rotation", "/tracking/trackers/6/rotation",
      "/tracking/trackers/7/rotation", "/tracking/trackers/8/rotation"};
  for (int i = 0; i < kVrchatTrackerSlots; ++i) {
    if (options_.slots[i] < 0) continue;
    send(kPosition[i], trackers[i].p);
    send(kRotation[i], trackers[i].euler_deg);
  }
  if (options_.head) {
    send("/tracking/trackers/head/position", head.p);
    send("/tracking/trackers/head/rotation", head.euler_deg);
  }
  if (ok) ++stats_.frames_sent;
  return ok;
}

std::unique_ptr<Output> make_vrchat(const OutputsConfig& cfg, const OutputContext& ctx) {
  const VrchatOutputConfig& c = cfg.vrchat;
  VrchatSender::Options o;
  o.host = c.host;
  o.port = static_cast<uint16_t>(c.port);
  o.slots.fill(-1);
  for (std::size_t i = 0; i < c.trackers.size() && i < o.slots.size(); ++i)
    if (const auto s = segment_from_name(c.trackers[i])) o.slots[i] = index(*s);
  o.head = c.head;
  o.scale = c.height_m > 0 && ctx.model_height_m > 0 ? c.height_m / ctx.model_height_m : 1.0;
  auto sender = std::make_unique<VrchatSender>();
  std::string err;
  if (!sender->open(o, &err)) throw std::runtime_error(err);
  if (ctx.log)
    ctx.log->info("VRChat OSC trackers to %s:%d (position scale %.3f)", c.host.c_str(), c.port,
                  o.scale);
  return sender;
}

}  // namespace mocap::outputs
