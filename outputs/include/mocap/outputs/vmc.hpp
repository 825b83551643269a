// VMC protocol sender (OSC over UDP): drives a VTuber/game avatar (VSeeFace, Warudo, VNyan,
// Unity/Unreal VMC receivers) from our PoseFrame. Maps our 16 segments to Unity HumanBodyBones,
// converts to Unity's left-handed Y-up frame with local rotations relative to a VRM T-pose rest,
// and sends Root/Pos, Bone/Pos, OK and T in bundles of at most 1500 bytes (docs/streaming.md).
#pragma once

#include "mocap/outputs/osc.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "mocap/outputs/output.hpp"
#include "mocap/outputs/registry.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::outputs {

/// One humanoid bone as VMC sends it: Unity frame, local to the parent bone.
struct VmcBone {
  std::string_view name;               ///< Unity HumanBodyBones name
  std::array<float, 3> p{};            ///< localPosition, metres (x right, y up, z forward)
  std::array<float, 4> q{0, 0, 0, 1};  ///< localRotation x, y, z, w (left-handed)
};

inline constexpr int kVmcBoneCount = 20;

/// The avatar pose of one frame: the root transform and the bones in parent-first order.
struct VmcPose {
  std::array<float, 3> root_p{};
  std::array<float, 4> root_q{0, 0, 0, 1};
  std::array<VmcBone, kVmcBoneCount> bones{};
};

/// Converts a frame to VMC bones. Root: the pelvis' ground position (Unity x, 0, z), identity
/// rotation. Hips: local position (0, pelvis height, 0), rotation = pelvis in the world.
/// Others: rotation relative to the parent bone, where the rest (identity) is the VRM T-pose
/// (our N-pose arms are rotated 90 degrees down from it). Chest, UpperChest and the shoulders,
/// which we do not measure, are identity. Returns false if the frame holds a non-finite value.
bool vmc_pose_from_frame(const PoseFrame& frame, VmcPose& out) noexcept;

class VmcSender final : public Output {
 public:
  /// host: the receiver (Marionette); VMC receivers listen on 39539 by convention.
  struct Options : osc::SenderOptions<39539> {
    std::size_t max_datagram = 1500;  ///< bundle size limit (VMC spec)
  };
  /// send_errors counts datagrams.
  struct Stats : osc::FrameStats {
    uint64_t datagrams_sent = 0;
    std::size_t max_datagram_bytes = 0;
  };

  /// Creates the UDP socket to the VMC receiver (not copyable: it owns it). False with a message if
  /// the address is invalid.
  bool open(const Options& options, std::string* error);
  /// Pipeline thread: encodes and sends one frame (non-blocking sendto, no allocation).
  /// Frame time (t_ns) drives the rate limit and /VMC/Ext/T.
  bool publish(const PoseFrame& frame) noexcept;
  void on_frame(const PoseFrame& frame) override { publish(frame); }
  const Stats& stats() const { return stats_; }

 private:
  Options options_;
  osc::FrameTarget target_;
  int64_t first_t_ns_ = 0;
  uint8_t bundle_[1500];
  uint8_t message_[256];
  std::size_t bundle_cap_ = sizeof bundle_;
  Stats stats_;
};

/// The [outputs.vmc] output: an open VmcSender (registry factory).
std::unique_ptr<Output> make_vmc(const OutputsConfig& cfg, const OutputContext& ctx);

}  // namespace mocap::outputs
