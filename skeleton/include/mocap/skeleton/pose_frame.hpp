// PoseFrame: one published posture of the whole body, the record that flows from the pipeline
// to the viewer, the streams and the recorder, and that sits in shared memory. Fixed layout,
// no pointers, floats; a multiple of 8 bytes so it can be copied word by word under a seqlock.
#pragma once

#include <array>
#include <cstdint>
#include <type_traits>

#include "mocap/core/segments.hpp"

namespace mocap {

inline constexpr int kMaxSensors = 32;

/// Per-segment state bits (PoseFrame::segment_flags).
enum SegmentFlag : uint32_t {
  kSegTracked = 1u << 0,        ///< orientation comes from this segment's own sensor
  kSegInferred = 1u << 1,       ///< no sensor: follows its parent or is interpolated
  kSegStale = 1u << 2,          ///< its sensor is silent (last sample too old)
  kSegMagDisturbed = 1u << 3,   ///< its sensor's magnetometer is rejected as disturbed
  kSegLimitViolated = 1u << 4,  ///< its joint (to the parent) is outside the limits
  // 1u << 5 is free (it meant "clamped" while joint limits could be imposed).
  kSegAtRest = 1u << 6,  ///< its sensor is at rest
  kSegStance = 1u << 7,  ///< foot segments: this foot is the stance foot
  /// Its sensor's filter has not accepted a reference field yet (start-up): the heading follows
  /// the magnetometer provisionally. Not the same as kSegMagDisturbed (field rejected).
  kSegMagNoReference = 1u << 8,
  kSegCalibrated = 1u << 9,  ///< its sensor has a sensor-to-segment calibration
};

/// Whole-frame state bits (PoseFrame::flags).
enum FrameFlag : uint32_t {
  kFrameCalibrated = 1u << 0,   ///< a calibration is applied
  kFrameCalibrating = 1u << 1,  ///< a calibration countdown or capture is under way
  kFrameRecording = 1u << 2,    ///< a session is being recorded
  kFrameReplay = 1u << 3,       ///< frames come from a replayed session
  kFrameDemo = 1u << 4,         ///< frames come from the virtual performer
};

/// Per-sensor health, as the daemon sees it.
struct SensorStatus {
  char name[24] = {};   ///< sensor name from the rig, NUL-terminated
  int8_t segment = -1;  ///< Segment index it drives, -1 if none
  uint8_t state = 0;    ///< 0 absent, 1 connecting, 2 streaming, 3 stale, 4 error, 5 disconnected
  uint16_t flags =
      0;              ///< SegmentFlag bits of its health (rig::SensorHealth::segment_flags) + stale
  float rate_hz = 0;  ///< measured sample rate
  float last_age_ms = 0;        ///< age of the newest sample when the frame was built
  uint32_t drops = 0;           ///< samples lost (counter gaps + full queues)
  uint32_t errors = 0;          ///< checksum failures and resyncs
  float gyro_bias_dps = 0;      ///< norm of the filter's bias estimate, deg/s
  float heading_sigma_deg = 0;  ///< filter's heading uncertainty
  /// The newest sample taken (the one a per-sample frame was published for), as its device
  /// stamped it: ImuSample::seq and ImuSample::t_device_ns. A client can tell from them which
  /// sample a frame shows (mocap bench latency matches its writes by them).
  uint32_t seq = 0;
  int64_t t_device_ns = 0;
};
static_assert(sizeof(SensorStatus) % 8 == 0);

struct PoseFrame {
  uint64_t frame = 0;           ///< frame number, increasing
  int64_t t_ns = 0;             ///< host monotonic time the pose refers to (newest sample), ns
  uint32_t flags = 0;           ///< FrameFlag bits
  uint32_t sensor_count = 0;    ///< valid entries in sensors
  float calib_countdown_s = 0;  ///< seconds until calibration capture (while calibrating)
  float reserved = 0;
  /// Wall-clock time of t_ns: UTC ns since 1970 (CLOCK_REALTIME sampled beside the monotonic
  /// clock live, the recorded offset in a replay); 0 = unknown (e.g. a CSV replay). Not stored
  /// in session pose blocks (sessions keep the offset in their header and clock blocks).
  int64_t t_unix_ns = 0;
  /// Earth-frame (ENU) orientation of each segment, w, x, y, z: maps segment-frame vectors into
  /// the earth frame; identity for a segment in the reference pose facing +x (east).
  std::array<std::array<float, 4>, kSegmentCount> q_earth_segment{};
  /// Earth-frame position of each segment's joint (origin), metres; floor at z = 0.
  std::array<std::array<float, 3>, kSegmentCount> p_earth_segment_m{};
  /// Joint rotation: child segment relative to its parent (w, x, y, z); pelvis = q_earth_pelvis.
  std::array<std::array<float, 4>, kSegmentCount> q_parent_segment{};
  /// How far each joint is outside its limits, degrees (0 inside).
  std::array<float, kSegmentCount> joint_violation_deg{};
  std::array<uint32_t, kSegmentCount> segment_flags{};
  std::array<SensorStatus, kMaxSensors> sensors{};
};
static_assert(std::is_trivially_copyable_v<PoseFrame>);
static_assert(sizeof(PoseFrame) % 8 == 0);

/// Sets every segment to the identity orientation at the origin (a valid "empty" pose).
inline void reset_pose(PoseFrame& f) {
  f = PoseFrame{};
  for (auto& q : f.q_earth_segment)
    q = {1, 0, 0, 0};
  for (auto& q : f.q_parent_segment)
    q = {1, 0, 0, 0};
}

}  // namespace mocap
