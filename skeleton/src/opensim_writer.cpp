// OpenSense orientations table writer: header, column names, one w,x,y,z cell per virtual IMU.
#include <stdexcept>

#include "mocap/skeleton/opensim.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

Eigen::Quaterniond q_opensim_body() {
  Eigen::Matrix3d c;
  c << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // rows: x_o = x, y_o = z, z_o = -y
  return Eigen::Quaterniond(c);
}

OpenSimWriter::OpenSimWriter(const std::string& path, OpenSimWriterOptions options)
    : path_(path), opt_(options) {
  if (!(opt_.rate_hz > 0)) throw std::invalid_argument("OpenSimWriter: rate must be positive");
  f_ = std::fopen(path.c_str(), "wb");
  if (!f_) throw std::runtime_error(path + ": cannot open for writing");
}

OpenSimWriter::~OpenSimWriter() {
  try {
    close();
  } catch (...) {
  }
}

void OpenSimWriter::write_frame(const PoseFrame& fr) {
  if (!f_) throw std::runtime_error(path_ + ": OpenSim writer is closed");
  if (frames_ == 0) {
    // Order: pelvis, torso, right leg, right arm, left leg, left arm, head (OpenSense examples
    // list the right side first; the order carries no meaning to OpenSense).
    static constexpr Segment kOrder[] = {Segment::pelvis,    Segment::torso,  Segment::thigh_r,
                                         Segment::shank_r,   Segment::foot_r, Segment::upper_arm_r,
                                         Segment::forearm_r, Segment::hand_r, Segment::thigh_l,
                                         Segment::shank_l,   Segment::foot_l, Segment::upper_arm_l,
                                         Segment::forearm_l, Segment::hand_l};
    for (Segment s : kOrder)
      columns_.push_back(index(s));
    if (fr.segment_flags[index(Segment::head)] & kSegTracked)
      columns_.push_back(index(Segment::head));
    std::fprintf(f_,
                 "DataRate=%.6f\nDataType=Quaternion\nversion=3\nOpenSimVersion=4.1\nendheader\n",
                 opt_.rate_hz);
    std::fputs("time", f_);
    for (int s : columns_)
      std::fprintf(f_, "\t%.*s", static_cast<int>(kOpenSimImuNames[s].size()),
                   kOpenSimImuNames[s].data());
    std::fputc('\n', f_);
  }
  const Eigen::Quaterniond c = q_opensim_body();
  const Eigen::Quaterniond ci = c.conjugate();
  std::fprintf(f_, "%.6f", frames_ / opt_.rate_hz);
  for (int s : columns_) {
    Eigen::Quaterniond q = c * from_wxyz(fr.q_earth_segment[s]).normalized() * ci;
    if (q.w() < 0) q.coeffs() *= -1;
    std::fprintf(f_, "\t%.8f,%.8f,%.8f,%.8f", q.w(), q.x(), q.y(), q.z());
  }
  std::fputc('\n', f_);
  if (std::ferror(f_)) throw std::runtime_error(path_ + ": write failed");
  ++frames_;
}

void OpenSimWriter::close() {
  if (!f_) return;
  std::FILE* f = f_;
  f_ = nullptr;
  const bool ok = !std::ferror(f);
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error(path_ + ": failed to finish .sto file");
}

}  // namespace mocap
