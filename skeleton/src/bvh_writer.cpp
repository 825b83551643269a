// BVH writer: our skeleton as standard bones, streaming frames, frame count patched on close.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "mocap/core/fixed_chars.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

namespace {
constexpr int kFramesFieldWidth = 12;
// Segments whose bone ends in an End Site.
bool is_leaf(int s) {
  for (int c = s + 1; c < kSegmentCount; ++c)
    if (kSegmentParent[c] == s) return false;
  return true;
}
}  // namespace

Eigen::Quaterniond q_bvh_body() {
  Eigen::Matrix3d c;
  c << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  return Eigen::Quaterniond(c);
}

Eigen::Vector3d zxy_degrees_from_rotation(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
  const double sx = std::clamp(r(2, 1), -1.0, 1.0);
  const double x = std::asin(sx);
  double z, y;
  if (std::abs(sx) < 1.0 - 1e-12) {
    y = std::atan2(-r(2, 0), r(2, 2));
    z = std::atan2(-r(0, 1), r(1, 1));
  } else {  // gimbal lock: put everything in z
    y = 0;
    z = std::atan2(r(1, 0), r(0, 0));
  }
  return Eigen::Vector3d(z, x, y) * kDegPerRad;
}

Eigen::Quaterniond rotation_from_zxy_degrees(double z_deg, double x_deg, double y_deg) {
  return axis_rotation(2, z_deg * kRadPerDeg) * axis_rotation(0, x_deg * kRadPerDeg) *
         axis_rotation(1, y_deg * kRadPerDeg);
}

std::string bvh_hierarchy(const BodyModel& model, double upm) {
  const Eigen::Quaterniond c = q_bvh_body();
  std::ostringstream os;
  char buf[128];
  auto vec = [&](const Eigen::Vector3d& v_m) {
    const Eigen::Vector3d b = c * v_m * upm;
    std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f", b.x(), b.y(), b.z());
    return std::string(buf);
  };
  // Recursive emission over our fixed tree.
  auto emit = [&](auto&& self, int s, int depth) -> void {
    const std::string ind(static_cast<size_t>(depth) * 2, ' ');
    if (s == 0) {
      os << "ROOT " << kBvhBoneNames[s] << "\n{\n";
      os << "  OFFSET 0.000000 0.000000 0.000000\n";
      os << "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
    } else {
      os << ind << "JOINT " << kBvhBoneNames[s] << "\n" << ind << "{\n";
      os << ind << "  OFFSET " << vec(model.joint_offset_m(s)) << "\n";
      os << ind << "  CHANNELS 3 Zrotation Xrotation Yrotation\n";
    }
    for (int ch = s + 1; ch < kSegmentCount; ++ch)
      if (kSegmentParent[ch] == s) self(self, ch, depth + 1);
    if (is_leaf(s)) {
      os << ind << "  End Site\n" << ind << "  {\n";
      os << ind << "    OFFSET " << vec(model.end_offset_m(s)) << "\n" << ind << "  }\n";
    }
    os << ind << "}\n";
  };
  os << "HIERARCHY\n";
  emit(emit, 0, 0);
  return os.str();
}

BvhWriter::BvhWriter(const std::string& path, const BodyModel& model, BvhWriterOptions options)
    : opt_(options), path_(path) {
  if (!(opt_.frame_time_s > 0) || !(opt_.units_per_m > 0))
    throw std::invalid_argument("BvhWriter: frame time and units must be positive");
  f_ = std::fopen(path.c_str(), "wb");
  if (!f_) throw std::runtime_error(path + ": cannot open for writing");
  const std::string h = bvh_hierarchy(model, opt_.units_per_m);
  std::fputs(h.c_str(), f_);
  std::fputs("MOTION\nFrames: ", f_);
  frames_pos_ = std::ftell(f_);
  std::fprintf(f_, "%-*d\nFrame Time: %.9f\n", kFramesFieldWidth, 0, opt_.frame_time_s);
  if (std::ferror(f_)) throw std::runtime_error(path + ": write failed");
}

BvhWriter::~BvhWriter() {
  try {
    close();
  } catch (...) {
  }
}

void BvhWriter::write_frame(const PoseFrame& fr) {
  if (!f_) throw std::runtime_error(path_ + ": BVH writer is closed");
  const Eigen::Quaterniond c = q_bvh_body();
  const Eigen::Quaterniond ci = c.conjugate();
  const auto& p = fr.p_earth_segment_m[0];
  const Eigen::Vector3d root = c * Eigen::Vector3d(p[0], p[1], p[2]) * opt_.units_per_m;
  // One line per frame, formatted with to_chars_fixed (std::to_chars' digits, the same as
  // printf "%.Nf", several times faster: the numbers dominate long offline exports) and written
  // with a single fwrite.
  // 51 values of at most 24 characters; to_chars_fixed takes its fast path only with room for
  // its longest result (sign, 19 digits, point, decimals), so each value gets 32 to write into.
  constexpr int kShare = 24, kRoom = 32;
  char line[(kSegmentCount * 3 + 3 - 1) * kShare + kRoom + 8];
  char* out = line;
  auto put = [&](double v, int precision, bool space) {
    if (space) *out++ = ' ';
    // A value too long for its 24-character share (|v| >= 1e15) is not a body pose.
    const auto r = to_chars_fixed(out, out + kRoom - 1, v, precision);
    if (r.ec != std::errc{} || r.ptr - out > kShare - 1)
      throw std::runtime_error(path_ + ": value out of range for BVH");
    out = r.ptr;
  };
  put(root.x(), 5, false);
  put(root.y(), 5, true);
  put(root.z(), 5, true);
  for (int s = 0; s < kSegmentCount; ++s) {
    const std::array<float, 4>& wxyz = s == 0 ? fr.q_earth_segment[0] : fr.q_parent_segment[s];
    LastRotation& last = last_[s];
    if (last.length > 0 && std::memcmp(last.wxyz.data(), wxyz.data(), sizeof wxyz) == 0) {
      std::memcpy(out, last.text, static_cast<std::size_t>(last.length));
      out += last.length;
      continue;
    }
    char* const begin = out;
    const Eigen::Quaterniond q = from_wxyz(wxyz);
    const Eigen::Vector3d e = zxy_degrees_from_rotation(c * q.normalized() * ci);
    for (int k = 0; k < 3; ++k)
      put(e[k], 6, true);
    last.wxyz = wxyz;
    last.length = static_cast<int>(out - begin);
    std::memcpy(last.text, begin, static_cast<std::size_t>(last.length));
  }
  *out++ = '\n';
  std::fwrite(line, 1, static_cast<std::size_t>(out - line), f_);
  if (std::ferror(f_)) throw std::runtime_error(path_ + ": write failed");
  ++frames_;
}

void BvhWriter::close() {
  if (!f_) return;
  std::FILE* f = f_;
  f_ = nullptr;
  bool ok = std::fseek(f, frames_pos_, SEEK_SET) == 0;
  ok = ok && std::fprintf(f, "%-*d", kFramesFieldWidth, frames_) > 0;
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) throw std::runtime_error(path_ + ": failed to finish BVH file");
}

}  // namespace mocap
