// Orbit camera over the earth frame (ENU, z up): yaw/pitch/distance around a target point, with
// pan and zoom, perspective projection, and projection of earth points to pixels.
#pragma once

#include <Eigen/Core>
#include <optional>

namespace mocap::viewer {

class OrbitCamera {
 public:
  Eigen::Vector3f target_m{0, 0, 0.9f};
  float yaw_deg = 30;    ///< azimuth of the eye around the target, from +x (east) towards +y
  float pitch_deg = 12;  ///< elevation of the eye above the target
  float distance_m = 4.2f;
  float fov_y_deg = 45;

  /// Default view framing `avatars` avatars laid out by crowd_origin().
  static OrbitCamera framing(int avatars);

  Eigen::Vector3f eye_m() const;
  Eigen::Matrix4f view() const;
  Eigen::Matrix4f projection(float aspect) const;
  /// Mouse drag: orbit by pixel deltas.
  void orbit(float dx_px, float dy_px);
  /// Mouse drag with the right button: move the target in the view plane.
  void pan(float dx_px, float dy_px, int viewport_h);
  /// Scroll: zoom in (steps > 0) or out.
  void zoom(float steps);
  /// Pixel (x right, y down, origin top-left) of an earth point, nullopt if behind the eye.
  std::optional<Eigen::Vector2f> project(const Eigen::Vector3f& p_earth_m, int width,
                                         int height) const;
};

/// Where avatar i of n stands in the crowd (a square grid centred on the origin, 1.3 m apart);
/// the origin for a single avatar.
Eigen::Vector3f crowd_origin(int i, int n);

}  // namespace mocap::viewer
