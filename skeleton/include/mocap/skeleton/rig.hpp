// Rig mapping: which sensor drives which body segment. Segments without a sensor are inferred
// by the skeleton (interpolated between tracked neighbours along their chain, or following the
// parent).
#pragma once

#include <array>

#include "mocap/core/segments.hpp"

namespace mocap {

struct RigMapping {
  /// Sensor id (rig index) on each segment, -1 if the segment has no sensor.
  std::array<int, kSegmentCount> sensor_for_segment{};

  bool tracked(int segment) const { return sensor_for_segment[segment] >= 0; }
  /// Segment driven by a sensor id, -1 if none.
  int segment_for_sensor(int sensor) const {
    for (int i = 0; i < kSegmentCount; ++i)
      if (sensor_for_segment[i] == sensor) return i;
    return -1;
  }
  /// Every segment has a sensor, sensor id = segment index (the full 16-sensor suit).
  static RigMapping full() {
    RigMapping r;
    for (int i = 0; i < kSegmentCount; ++i)
      r.sensor_for_segment[i] = i;
    return r;
  }
  /// No sensors at all.
  static RigMapping none() {
    RigMapping r;
    r.sensor_for_segment.fill(-1);
    return r;
  }
};

}  // namespace mocap
