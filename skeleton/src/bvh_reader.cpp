// BVH reader: tokenising parser with line numbers and limits, global pose evaluation.
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

namespace {

constexpr int kMaxJoints = 1024;
constexpr int kMaxDepth = 128;

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

class Tokens {
 public:
  Tokens(std::string_view text, std::string_view source) : t_(text), src_(source) {}

  bool next(std::string_view& tok) {
    while (pos_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[pos_]))) {
      if (t_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= t_.size()) return false;
    const size_t b = pos_;
    while (pos_ < t_.size() && !std::isspace(static_cast<unsigned char>(t_[pos_])))
      ++pos_;
    tok = t_.substr(b, pos_ - b);
    return true;
  }
  std::string_view need(std::string_view what) {
    std::string_view tok;
    if (!next(tok)) fail("unexpected end of file, expected " + std::string(what));
    return tok;
  }
  void expect(std::string_view word) {
    const std::string_view tok = need(word);
    if (!iequals(tok, word))
      fail("expected '" + std::string(word) + "', found '" + std::string(tok.substr(0, 40)) + "'");
  }
  double number(std::string_view what) {
    const std::string_view tok = need(what);
    double v = 0;
    const char* b = tok.data();
    if (!tok.empty() && *b == '+') ++b;
    const auto r = std::from_chars(b, tok.data() + tok.size(), v);
    if (r.ec != std::errc() || r.ptr != tok.data() + tok.size() || !std::isfinite(v))
      fail("expected a number for " + std::string(what) + ", found '" +
           std::string(tok.substr(0, 40)) + "'");
    return v;
  }
  long integer(std::string_view what, long lo, long hi) {
    const std::string_view tok = need(what);
    long v = 0;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (r.ec != std::errc() || r.ptr != tok.data() + tok.size() || v < lo || v > hi)
      fail(std::string(what) + " must be an integer in " + std::to_string(lo) + ".." +
           std::to_string(hi) + ", found '" + std::string(tok.substr(0, 40)) + "'");
    return v;
  }
  [[noreturn]] void fail(const std::string& what) const {
    std::ostringstream os;
    os << src_ << ":" << line_ << ": " << what;
    throw std::runtime_error(os.str());
  }
  bool at_end() {
    std::string_view tok;
    const size_t p = pos_;
    const int l = line_;
    const bool any = next(tok);
    pos_ = p;
    line_ = l;
    return !any;
  }

 private:
  std::string_view t_, src_;
  size_t pos_ = 0;
  int line_ = 1;
};

bool channel_from(std::string_view n, BvhChannel& c) {
  static constexpr std::pair<std::string_view, BvhChannel> kNames[] = {
      {"Xposition", BvhChannel::xpos}, {"Yposition", BvhChannel::ypos},
      {"Zposition", BvhChannel::zpos}, {"Xrotation", BvhChannel::xrot},
      {"Yrotation", BvhChannel::yrot}, {"Zrotation", BvhChannel::zrot}};
  for (const auto& [name, ch] : kNames)
    if (iequals(n, name)) {
      c = ch;
      return true;
    }
  return false;
}

void parse_joint(Tokens& tk, BvhClip& clip, int parent, int depth) {
  if (depth > kMaxDepth) tk.fail("hierarchy nested too deeply");
  if (static_cast<int>(clip.joints.size()) >= kMaxJoints) tk.fail("too many joints");
  BvhJoint j;
  j.name = std::string(tk.need("joint name"));
  j.parent = parent;
  if (j.name == "{") tk.fail("joint without a name");
  const int me = static_cast<int>(clip.joints.size());
  clip.joints.push_back(j);
  tk.expect("{");
  bool have_offset = false, have_channels = false;
  for (;;) {
    const std::string_view tok = tk.need("OFFSET, CHANNELS, JOINT, End Site or }");
    if (iequals(tok, "OFFSET")) {
      if (have_offset) tk.fail("joint '" + clip.joints[me].name + "' has two OFFSETs");
      for (int i = 0; i < 3; ++i)
        clip.joints[me].offset[i] = tk.number("OFFSET");
      have_offset = true;
    } else if (iequals(tok, "CHANNELS")) {
      if (have_channels) tk.fail("joint '" + clip.joints[me].name + "' has two CHANNELS");
      const long n = tk.integer("CHANNELS count", 0, 6);
      clip.joints[me].first_channel = clip.channel_count;
      for (long i = 0; i < n; ++i) {
        BvhChannel c;
        const std::string_view cn = tk.need("channel name");
        if (!channel_from(cn, c))
          tk.fail("unknown channel '" + std::string(cn.substr(0, 40)) + "'");
        clip.joints[me].channels.push_back(c);
      }
      clip.channel_count += static_cast<int>(n);
      have_channels = true;
    } else if (iequals(tok, "JOINT")) {
      parse_joint(tk, clip, me, depth + 1);
    } else if (iequals(tok, "End")) {
      tk.expect("Site");
      tk.expect("{");
      tk.expect("OFFSET");
      for (int i = 0; i < 3; ++i)
        clip.joints[me].end_site[i] = tk.number("End Site OFFSET");
      clip.joints[me].has_end_site = true;
      tk.expect("}");
    } else if (tok == "}") {
      if (!have_offset) tk.fail("joint '" + clip.joints[me].name + "' lacks OFFSET");
      return;
    } else {
      tk.fail("unexpected '" + std::string(tok.substr(0, 40)) + "' in joint '" +
              clip.joints[me].name + "'");
    }
  }
}

}  // namespace

int BvhClip::find(std::string_view name) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (iequals(joints[i].name, name)) return static_cast<int>(i);
  return -1;
}

void BvhClip::global_pose(int k, std::vector<Eigen::Quaterniond>& q,
                          std::vector<Eigen::Vector3d>& p) const {
  q.resize(joints.size());
  p.resize(joints.size());
  const double* v = frame_count > 0 ? frame(k) : nullptr;
  for (size_t i = 0; i < joints.size(); ++i) {
    const BvhJoint& j = joints[i];
    Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
    Eigen::Vector3d t = j.offset;
    for (size_t c = 0; c < j.channels.size() && v; ++c) {
      const double x = v[j.first_channel + static_cast<int>(c)];
      switch (j.channels[c]) {
        case BvhChannel::xpos:
          t.x() = x;
          break;
        case BvhChannel::ypos:
          t.y() = x;
          break;
        case BvhChannel::zpos:
          t.z() = x;
          break;
        case BvhChannel::xrot:
          r = r * axis_rotation(0, x * kRadPerDeg);
          break;
        case BvhChannel::yrot:
          r = r * axis_rotation(1, x * kRadPerDeg);
          break;
        case BvhChannel::zrot:
          r = r * axis_rotation(2, x * kRadPerDeg);
          break;
      }
    }
    if (j.parent < 0) {
      q[i] = r;
      p[i] = t;
    } else {
      q[i] = q[j.parent] * r;
      p[i] = p[j.parent] + q[j.parent] * t;
    }
  }
}

BvhClip parse_bvh(std::string_view text, std::string_view source) {
  Tokens tk(text, source);
  BvhClip clip;
  tk.expect("HIERARCHY");
  tk.expect("ROOT");
  parse_joint(tk, clip, -1, 0);
  const std::string_view tok = tk.need("MOTION");
  if (iequals(tok, "ROOT")) tk.fail("only one ROOT is supported");
  if (!iequals(tok, "MOTION"))
    tk.fail("expected 'MOTION', found '" + std::string(tok.substr(0, 40)) + "'");
  tk.expect("Frames:");
  const long frames = tk.integer("Frames", 0, 100'000'000);
  tk.expect("Frame");
  tk.expect("Time:");
  clip.frame_time_s = tk.number("Frame Time");
  if (!(clip.frame_time_s > 0)) tk.fail("Frame Time must be positive");
  clip.values.reserve(
      std::min<size_t>(static_cast<size_t>(frames) * clip.channel_count, text.size() / 2 + 1));
  while (!tk.at_end())
    clip.values.push_back(tk.number("frame value"));
  const size_t n = clip.values.size();
  const size_t cc = static_cast<size_t>(clip.channel_count);
  if (cc == 0) {
    if (n != 0) tk.fail("frame values given but no CHANNELS declared");
    clip.frame_count = static_cast<int>(frames);
    return clip;
  }
  if (n % cc != 0)
    tk.fail("frame data is not a whole number of frames (" + std::to_string(n) + " values, " +
            std::to_string(cc) + " channels per frame)");
  const size_t actual = n / cc;
  // A header count of 0 is what an interrupted streaming writer leaves: trust the data then.
  if (frames != 0 && static_cast<size_t>(frames) != actual)
    tk.fail("Frames says " + std::to_string(frames) + " but the data holds " +
            std::to_string(actual));
  clip.frame_count = static_cast<int>(actual);
  return clip;
}

BvhClip load_bvh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open BVH file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_bvh(ss.str(), path);
}

}  // namespace mocap
