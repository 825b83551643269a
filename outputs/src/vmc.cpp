// VMC sender: segment-to-HumanBodyBones mapping, conversion of our ENU/N-pose rotations to
// Unity left-handed local rotations about a VRM T-pose rest, and OSC bundles over UDP.
#include "mocap/outputs/vmc.hpp"

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

#include "mocap/outputs/osc.hpp"

namespace mocap::outputs {
namespace {

struct BoneDef {
  std::string_view name;
  int parent;   // index in kBones, -1 for Hips
  int segment;  // our Segment index, -1 for bones we do not measure (identity local rotation)
};

constexpr int seg(Segment s) {
  return index(s);
}

// Parent-first. Chest, UpperChest and the shoulders are not measured: they follow their parent.
constexpr std::array<BoneDef, kVmcBoneCount> kBones = {{
    {"Hips", -1, seg(Segment::pelvis)},
    {"Spine", 0, seg(Segment::torso)},
    {"Chest", 1, -1},
    {"UpperChest", 2, -1},
    {"Neck", 3, seg(Segment::neck)},
    {"Head", 4, seg(Segment::head)},
    {"LeftShoulder", 3, -1},
    {"LeftUpperArm", 6, seg(Segment::upper_arm_l)},
    {"LeftLowerArm", 7, seg(Segment::forearm_l)},
    {"LeftHand", 8, seg(Segment::hand_l)},
    {"RightShoulder", 3, -1},
    {"RightUpperArm", 10, seg(Segment::upper_arm_r)},
    {"RightLowerArm", 11, seg(Segment::forearm_r)},
    {"RightHand", 12, seg(Segment::hand_r)},
    {"LeftUpperLeg", 0, seg(Segment::thigh_l)},
    {"LeftLowerLeg", 14, seg(Segment::shank_l)},
    {"LeftFoot", 15, seg(Segment::foot_l)},
    {"RightUpperLeg", 0, seg(Segment::thigh_r)},
    {"RightLowerLeg", 17, seg(Segment::shank_r)},
    {"RightFoot", 18, seg(Segment::foot_r)},
}};

/// Rotation taking a segment from the VRM T-pose to our N-pose, in body axes (x forward,
/// y left, z up): the arms swing down 90 degrees about the forward axis; all else coincide.
Eigen::Quaterniond rest_tpose_to_npose(int segment) {
  const double h = std::sqrt(0.5);
  switch (static_cast<Segment>(segment)) {
    case Segment::upper_arm_l:
    case Segment::forearm_l:
    case Segment::hand_l:
      return Eigen::Quaterniond(h, -h, 0, 0);  // about +x by -90: +y (left) -> -z (down)
    case Segment::upper_arm_r:
    case Segment::forearm_r:
    case Segment::hand_r:
      return Eigen::Quaterniond(h, h, 0, 0);  // about +x by +90: -y (right) -> -z (down)
    default:
      return Eigen::Quaterniond::Identity();
  }
}

// Our body/earth axes -> Unity: x_u = -y (right), y_u = z (up), z_u = x (forward). The map has
// determinant -1 (right- to left-handed), so a quaternion's vector part becomes -M v.
std::array<float, 3> to_unity(const Eigen::Vector3d& p) {
  return {static_cast<float>(-p.y()), static_cast<float>(p.z()), static_cast<float>(p.x())};
}
std::array<float, 4> to_unity(const Eigen::Quaterniond& q) {
  return {static_cast<float>(q.y()), static_cast<float>(-q.z()), static_cast<float>(-q.x()),
          static_cast<float>(q.w())};
}

}  // namespace

bool vmc_pose_from_frame(const PoseFrame& f, VmcPose& out) noexcept {
  std::array<Eigen::Quaterniond, kVmcBoneCount> world;
  std::array<Eigen::Vector3d, kVmcBoneCount> pos;
  for (int b = 0; b < kVmcBoneCount; ++b) {
    const BoneDef& def = kBones[b];
    if (def.segment >= 0) {
      const auto& q = f.q_earth_segment[def.segment];
      const auto& p = f.p_earth_segment_m[def.segment];
      Eigen::Quaterniond qe(q[0], q[1], q[2], q[3]);
      const Eigen::Vector3d pe(p[0], p[1], p[2]);
      if (!qe.coeffs().allFinite() || !pe.allFinite() || qe.norm() < 1e-6) return false;
      world[b] = qe.normalized() * rest_tpose_to_npose(def.segment);
      pos[b] = pe;
    } else {
      world[b] = world[def.parent];
      pos[b] = pos[def.parent];
    }
    VmcBone& bone = out.bones[b];
    bone.name = def.name;
    if (def.parent < 0) {
      bone.q = to_unity(world[b]);
      bone.p = {0.f, static_cast<float>(pos[b].z()), 0.f};
    } else {
      const Eigen::Quaterniond inv_parent = world[def.parent].conjugate();
      Eigen::Quaterniond local = inv_parent * world[b];
      if (local.w() < 0) local.coeffs() *= -1;  // one canonical sign
      bone.q = to_unity(local);
      bone.p = to_unity(inv_parent * (pos[b] - pos[def.parent]));
    }
  }
  const Eigen::Vector3d ground(pos[0].x(), pos[0].y(), 0.0);
  out.root_p = to_unity(ground);
  out.root_q = {0, 0, 0, 1};
  return true;
}

bool VmcSender::open(const Options& options, std::string* error) {
  options_ = options;
  bundle_cap_ = std::clamp<std::size_t>(options.max_datagram, 256, sizeof bundle_);
  return target_.open(options, "VMC", error);
}

bool VmcSender::publish(const PoseFrame& frame) noexcept {
  if (!target_.due(frame.t_ns, stats_)) return false;
  VmcPose pose;
  if (!vmc_pose_from_frame(frame, pose)) {
    ++stats_.frames_invalid;
    return false;
  }
  if (!target_.sent_any()) first_t_ns_ = frame.t_ns;
  target_.sent(frame.t_ns);

  osc::BundleWriter bundle(bundle_, bundle_cap_);
  bundle.begin();
  bool ok = true;
  auto send = [&] {
    if (bundle.empty()) return;
    if (!target_.send(bundle.data(), bundle.size())) {
      ++stats_.send_errors;
      ok = false;
    } else {
      ++stats_.datagrams_sent;
      stats_.max_datagram_bytes = std::max(stats_.max_datagram_bytes, bundle.size());
    }
    bundle.begin();
  };
  auto add = [&](const osc::MessageWriter& m) {
    if (!m.ok()) return;
    if (!bundle.add(message_, m.size())) {
      send();
      bundle.add(message_, m.size());
    }
  };
  auto pose_message = [&](std::string_view address, std::string_view name,
                          const std::array<float, 3>& p, const std::array<float, 4>& q) {
    osc::MessageWriter m(message_, sizeof message_);
    m.address(address).tags(",sfffffff").str(name);
    for (float v : p)
      m.f32(v);
    for (float v : q)
      m.f32(v);
    add(m);
  };
  pose_message("/VMC/Ext/Root/Pos", "root", pose.root_p, pose.root_q);
  for (const VmcBone& b : pose.bones)
    pose_message("/VMC/Ext/Bone/Pos", b.name, b.p, b.q);
  {
    const int calib_state = (frame.flags & kFrameCalibrated)    ? 3
                            : (frame.flags & kFrameCalibrating) ? 2
                                                                : 0;
    osc::MessageWriter m(message_, sizeof message_);
    m.address("/VMC/Ext/OK").tags(",iii").i32(1).i32(calib_state).i32(0);
    add(m);
  }
  {
    osc::MessageWriter m(message_, sizeof message_);
    m.address("/VMC/Ext/T")
        .tags(",f")
        .f32(static_cast<float>(static_cast<double>(frame.t_ns - first_t_ns_) * 1e-9));
    add(m);
  }
  send();
  if (ok) ++stats_.frames_sent;
  return ok;
}

std::unique_ptr<Output> make_vmc(const OutputsConfig& cfg, const OutputContext& ctx) {
  const VmcOutputConfig& c = cfg.vmc;
  VmcSender::Options o;
  o.host = c.host;
  o.port = static_cast<uint16_t>(c.port);
  auto sender = std::make_unique<VmcSender>();
  std::string err;
  if (!sender->open(o, &err)) throw std::runtime_error(err);
  if (ctx.log) ctx.log->info("VMC to %s:%d", c.host.c_str(), c.port);
  return sender;
}

}  // namespace mocap::outputs
