// PosesCsvSink: pose frames to CSV, fixed decimals (stable text for golden files).
#include "mocap/outputs/poses_csv.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "mocap/core/segments.hpp"

namespace mocap::outputs {

PosesCsvSink::PosesCsvSink(const std::string& path, int64_t t0_ns) : path_(path), t0_ns_(t0_ns) {
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) throw std::runtime_error(path + ": " + std::strerror(errno));
  std::fputs("t,segment,w,x,y,z,px,py,pz\n", f_);
}

PosesCsvSink::~PosesCsvSink() {
  if (f_) std::fclose(f_);
}

void PosesCsvSink::on_frame(const PoseFrame& f) {
  const double t = static_cast<double>(f.t_ns - t0_ns_) * 1e-9;
  for (int s = 0; s < kSegmentCount; ++s) {
    const auto& q = f.q_earth_segment[s];
    const auto& p = f.p_earth_segment_m[s];
    std::fprintf(f_, "%.6f,%s,%.6f,%.6f,%.6f,%.6f,%.5f,%.5f,%.5f\n", t, kSegmentNames[s].data(),
                 q[0], q[1], q[2], q[3], p[0], p[1], p[2]);
  }
}

void PosesCsvSink::close() {
  if (!f_) return;
  const bool bad = std::ferror(f_) != 0;
  const bool close_failed = std::fclose(f_) != 0;
  f_ = nullptr;
  if (bad || close_failed) throw std::runtime_error(path_ + ": write failed");
}

}  // namespace mocap::outputs
