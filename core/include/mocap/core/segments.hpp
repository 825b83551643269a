// The 16 body segments and 15 joints of the thesis body model (Usta 1999): names used in config,
// streams and CSV, the parent tree in depth-first order, and which joints are hinges.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace mocap {

/// Segments in depth-first order: parent index < child index, pelvis is the root.
/// A joint is identified by its child segment (the "torso" joint is the waist).
enum class Segment : uint8_t {
  pelvis,
  torso,
  neck,
  head,
  upper_arm_l,
  forearm_l,
  hand_l,
  upper_arm_r,
  forearm_r,
  hand_r,
  thigh_l,
  shank_l,
  foot_l,
  thigh_r,
  shank_r,
  foot_r,
};

inline constexpr int kSegmentCount = 16;
inline constexpr int kNoParent = -1;

inline constexpr std::array<std::string_view, kSegmentCount> kSegmentNames = {
    "pelvis", "torso",       "neck",      "head",   "upper_arm_l", "forearm_l",
    "hand_l", "upper_arm_r", "forearm_r", "hand_r", "thigh_l",     "shank_l",
    "foot_l", "thigh_r",     "shank_r",   "foot_r"};

/// Parent segment of each segment (kNoParent for the pelvis).
inline constexpr std::array<int8_t, kSegmentCount> kSegmentParent = {
    kNoParent, 0,  1,  2,  // pelvis, torso, neck, head
    1,         4,  5,      // left arm hangs off the torso
    1,         7,  8,      // right arm
    0,         10, 11,     // left leg hangs off the pelvis
    0,         13, 14};    // right leg

/// Name of the joint whose child is the given segment (for humans reading reports).
inline constexpr std::array<std::string_view, kSegmentCount> kJointNames = {
    "root",    "waist",      "neck_base", "neck_head", "shoulder_l", "elbow_l",
    "wrist_l", "shoulder_r", "elbow_r",   "wrist_r",   "hip_l",      "knee_l",
    "ankle_l", "hip_r",      "knee_r",    "ankle_r"};

/// Hinge joints (1 DOF in the thesis model): knees and elbows.
inline constexpr bool is_hinge(Segment s) {
  return s == Segment::forearm_l || s == Segment::forearm_r || s == Segment::shank_l ||
         s == Segment::shank_r;
}

inline constexpr int index(Segment s) {
  return static_cast<int>(s);
}
inline constexpr std::string_view name(Segment s) {
  return kSegmentNames[index(s)];
}

inline std::optional<Segment> segment_from_name(std::string_view n) {
  for (int i = 0; i < kSegmentCount; ++i)
    if (kSegmentNames[i] == n) return static_cast<Segment>(i);
  return std::nullopt;
}

}  // namespace mocap
