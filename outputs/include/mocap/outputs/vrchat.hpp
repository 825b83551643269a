// VRChat OSC trackers sender (OSC over UDP): up to 8 body segments as VRChat's OSC trackers
// (/tracking/trackers/1..8/position and /rotation) plus the head for alignment
// (/tracking/trackers/head/...), in Unity's left-handed Y-up world frame with Euler angles in
// degrees in Unity's order (Z, then X, then Y). docs/streaming.md section 3.
#pragma once

#include "mocap/outputs/osc.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "mocap/outputs/output.hpp"
#include "mocap/outputs/registry.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::outputs {

inline constexpr int kVrchatTrackerSlots = 8;

/// Unity Euler angles (degrees) of a rotation given as a Unity quaternion x, y, z, w: the
/// angles (x, y, z) with q = AngleAxis(y, up) * AngleAxis(x, right) * AngleAxis(z, forward),
/// i.e. Unity's Quaternion.Euler(x, y, z) (z applied first, then x, then y). x in [-90, 90],
/// y and z in (-180, 180]; at x = +-90 (gimbal lock) z is 0.
std::array<float, 3> unity_euler_deg(const std::array<double, 4>& q_unity_xyzw) noexcept;

/// One tracker as VRChat receives it: Unity world position (metres) and Euler angles (degrees).
struct VrchatTracker {
  std::array<float, 3> p{};
  std::array<float, 3> euler_deg{};
};

/// Converts segment s of a frame: our ENU position and orientation to Unity's frame
/// (x right = -y, y up = z, z forward = x; determinant -1), position times scale. False if the
/// frame holds a non-finite value for it.
bool vrchat_tracker_from_frame(const PoseFrame& frame, int segment, double scale,
                               VrchatTracker& out) noexcept;

class VrchatSender final : public Output {
 public:
  /// host: VRChat's (a Quest on the LAN); 9000 is VRChat's OSC input port.
  struct Options : osc::SenderOptions<9000> {
    /// Segment index per tracker slot 1..8; -1 leaves the slot unsent.
    std::array<int, kVrchatTrackerSlots> slots{
        index(Segment::pelvis),    index(Segment::torso),    index(Segment::foot_l),
        index(Segment::foot_r),    index(Segment::shank_l),  index(Segment::shank_r),
        index(Segment::forearm_l), index(Segment::forearm_r)};
    bool head = true;    ///< also send /tracking/trackers/head/position|rotation
    double scale = 1.0;  ///< positions are multiplied by this (user height / model height)
  };
  /// send_errors counts messages.
  struct Stats : osc::FrameStats {
    uint64_t messages_sent = 0;  ///< one UDP datagram per OSC message
  };

  /// Creates the UDP socket to VRChat (not copyable: it owns it). False with a message if
  /// the address is invalid.
  bool open(const Options& options, std::string* error);
  /// Pipeline thread: encodes and sends one frame, each OSC message as its own datagram
  /// (non-blocking sendto, no allocation). The frame time drives the rate limit.
  bool publish(const PoseFrame& frame) noexcept;
  void on_frame(const PoseFrame& frame) override { publish(frame); }
  const Stats& stats() const { return stats_; }

 private:
  Options options_;
  osc::FrameTarget target_;
  uint8_t message_[128];
  Stats stats_;
};

/// The [outputs.vrchat] output: an open VrchatSender (registry factory).
std::unique_ptr<Output> make_vrchat(const OutputsConfig& cfg, const OutputContext& ctx);

}  // namespace mocap::outputs
