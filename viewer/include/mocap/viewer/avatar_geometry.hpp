// Avatar geometry: turns PoseFrames into the capsules the renderer draws (one instance each),
// in the earth frame. Pure data, no OpenGL, so it is tested without a display.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::viewer {

/// One capsule: the segment between a and b (earth frame, metres) swept by a sphere of `radius`.
/// a == b draws a sphere. Layout matches the renderer's per-instance vertex attributes.
struct CapsuleInstance {
  std::array<float, 3> a_m{};
  float radius_m = 0;
  std::array<float, 3> b_m{};
  float pad = 0;
  std::array<float, 4> rgba{};
};
static_assert(sizeof(CapsuleInstance) == 48);

struct AvatarStyle {
  bool stick = false;        ///< thin bones and joint spheres instead of solid capsules
  bool sensor_axes = false;  ///< x/y/z axes of every segment frame (red/green/blue)
};

/// Colours of the segment states; the first matching flag wins (see segment_rgb()).
inline constexpr std::array<float, 3> kRgbLimitViolated = {0.92f, 0.12f, 0.10f};
inline constexpr std::array<float, 3> kRgbStale = {0.42f, 0.42f, 0.44f};
inline constexpr std::array<float, 3> kRgbMagDisturbed = {0.95f, 0.80f, 0.10f};

/// Base colour of a segment (trunk, left side, right side) tinted by its flags.
std::array<float, 3> segment_rgb(int segment, uint32_t segment_flags);

/// Short label for the most important flag of a segment ("LIMIT 12 DEG", "STALE", "MAG"),
/// empty if the segment needs no label. Writes into `out` (no allocation).
void segment_label(const PoseFrame& f, int segment, std::array<char, 32>& out);

/// Appends the capsules of one avatar. Segments whose pose contains NaN are skipped.
void append_avatar(const PoseFrame& f, const BodyDimensions& dims, const AvatarStyle& style,
                   std::vector<CapsuleInstance>& out);

/// Appends the earth axes at the origin (x east red, y north green, z up blue).
void append_earth_axes(float length_m, std::vector<CapsuleInstance>& out);

/// Mid-point of a segment's bone (joint to end) in the earth frame, for labels and tests.
Eigen::Vector3f segment_midpoint(const PoseFrame& f, const BodyDimensions& dims, int segment);

/// True if every quaternion and position of the frame is finite.
bool pose_is_finite(const PoseFrame& f);

}  // namespace mocap::viewer
