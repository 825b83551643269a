// Pose frames as CSV (`mocap replay --poses`): one line per segment per frame,
//   t,segment,w,x,y,z,px,py,pz
// t in seconds from the first sample of the input; q_earth_segment (w,x,y,z); p_earth_segment_m.
#pragma once

#include <cstdio>
#include <string>

#include "mocap/outputs/output.hpp"

namespace mocap::outputs {

class PosesCsvSink final : public Output {
 public:
  /// Opens (truncates) the file and writes the header. Throws std::runtime_error on failure.
  PosesCsvSink(const std::string& path, int64_t t0_ns);
  ~PosesCsvSink() override;
  void set_t0(int64_t t0_ns) { t0_ns_ = t0_ns; }
  void on_frame(const PoseFrame& f) override;
  /// Flushes and closes; throws std::runtime_error if a write failed.
  void close();

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
  int64_t t0_ns_;
};

}  // namespace mocap::outputs
