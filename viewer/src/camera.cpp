// Orbit camera maths (look-at with z up, perspective) and crowd layout.
#include "mocap/viewer/camera.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"

namespace mocap::viewer {
namespace {
constexpr float kRadPerDegF = static_cast<float>(kRadPerDeg);  // the viewer works in float
}

OrbitCamera OrbitCamera::framing(int avatars) {
  OrbitCamera c;
  if (avatars > 1) {
    const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<float>(avatars))));
    c.distance_m = std::max(4.2f, 1.3f * static_cast<float>(side) * 1.35f);
    c.pitch_deg = 28;
    c.target_m = Eigen::Vector3f(0, 0, 0.5f);
  }
  return c;
}

Eigen::Vector3f OrbitCamera::eye_m() const {
  const float y = yaw_deg * kRadPerDegF, p = pitch_deg * kRadPerDegF;
  return target_m + distance_m * Eigen::Vector3f(std::cos(p) * std::cos(y),
                                                 std::cos(p) * std::sin(y), std::sin(p));
}

Eigen::Matrix4f OrbitCamera::view() const {
  const Eigen::Vector3f eye = eye_m();
  const Eigen::Vector3f f = (target_m - eye).normalized();
  Eigen::Vector3f s = f.cross(Eigen::Vector3f::UnitZ());
  if (s.norm() < 1e-6f) s = Eigen::Vector3f::UnitY();
  s.normalize();
  const Eigen::Vector3f u = s.cross(f);
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Eigen::Matrix4f OrbitCamera::projection(float aspect) const {
  const float near_m = std::max(0.02f, distance_m * 0.01f), far_m = distance_m * 20 + 50;
  const float t = 1.0f / std::tan(0.5f * fov_y_deg * kRadPerDegF);
  Eigen::Matrix4f m = Eigen::Matrix4f::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = (far_m + near_m) / (near_m - far_m);
  m(2, 3) = 2 * far_m * near_m / (near_m - far_m);
  m(3, 2) = -1;
  return m;
}

void OrbitCamera::orbit(float dx_px, float dy_px) {
  yaw_deg -= 0.3f * dx_px;
  pitch_deg = std::clamp(pitch_deg + 0.3f * dy_px, -85.0f, 85.0f);
}

void OrbitCamera::pan(float dx_px, float dy_px, int viewport_h) {
  const Eigen::Matrix4f v = view();
  const Eigen::Vector3f right = v.block<1, 3>(0, 0).transpose();
  const Eigen::Vector3f up = v.block<1, 3>(1, 0).transpose();
  const float m_per_px = 2 * distance_m * std::tan(0.5f * fov_y_deg * kRadPerDegF) /
                         static_cast<float>(std::max(1, viewport_h));
  target_m += m_per_px * (-dx_px * right + dy_px * up);
}

void OrbitCamera::zoom(float steps) {
  distance_m = std::clamp(distance_m * std::pow(0.9f, steps), 0.3f, 200.0f);
}

std::optional<Eigen::Vector2f> OrbitCamera::project(const Eigen::Vector3f& p, int width,
                                                    int height) const {
  const Eigen::Vector4f clip = projection(static_cast<float>(width) / static_cast<float>(height)) *
                               view() * Eigen::Vector4f(p.x(), p.y(), p.z(), 1);
  if (clip.w() <= 1e-6f) return std::nullopt;
  const float x = clip.x() / clip.w(), y = clip.y() / clip.w();
  return Eigen::Vector2f((x * 0.5f + 0.5f) * static_cast<float>(width),
                         (0.5f - y * 0.5f) * static_cast<float>(height));
}

Eigen::Vector3f crowd_origin(int i, int n) {
  if (n <= 1) return Eigen::Vector3f::Zero();
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<float>(n))));
  const float spacing = 1.3f, half = 0.5f * spacing * static_cast<float>(side - 1);
  return Eigen::Vector3f(static_cast<float>(i / side) * spacing - half,
                         static_cast<float>(i % side) * spacing - half, 0);
}

}  // namespace mocap::viewer
