// glTF 2.0 binary writer: nodes, skin, one animation; the JSON with nlohmann, the buffer by hand
// (little-endian float32, every view 4-byte aligned), both in one .glb container.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/gltf.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {
namespace {

constexpr int kGltfFloat = 5126;  // componentType FLOAT

/// Appends floats to the binary buffer and describes them as a bufferView + accessor.
struct BufferBuilder {
  std::vector<uint8_t> bytes;
  nlohmann::json views = nlohmann::json::array();
  nlohmann::json accessors = nlohmann::json::array();

  int add(const float* data, std::size_t count, const char* type, int components,
          nlohmann::json extra = nlohmann::json::object()) {
    const std::size_t offset = bytes.size();  // always a multiple of 4
    bytes.resize(offset + count * sizeof(float));
    std::memcpy(bytes.data() + offset, data, count * sizeof(float));  // x86/ARM: little-endian
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", count * sizeof(float)}});
    nlohmann::json a = {{"bufferView", views.size() - 1},
                        {"componentType", kGltfFloat},
                        {"count", count / static_cast<std::size_t>(components)},
                        {"type", type}};
    a.update(extra);
    accessors.push_back(std::move(a));
    return static_cast<int>(accessors.size() - 1);
  }
};

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i)
    out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

}  // namespace

std::vector<uint8_t> gltf_binary(const BodyModel& model, const GltfWriterOptions& opt, int frames,
                                 const std::vector<float> (&rotations)[kSegmentCount],
                                 const std::vector<float>& root_translation) {
  static_assert(sizeof(float) == 4);
  const Eigen::Quaterniond c = q_bvh_body();  // our axes -> glTF (= BVH) axes
  const auto rest = reference_joint_positions(model.dimensions());
  BufferBuilder buf;

  nlohmann::json nodes = nlohmann::json::array();
  for (int s = 0; s < kSegmentCount; ++s) {
    const Eigen::Vector3d t =
        c * (s == 0 ? Eigen::Vector3d(0, 0, model.pelvis_height_m()) : model.joint_offset_m(s));
    nlohmann::json n = {{"name", std::string(kBvhBoneNames[s])},
                        {"translation", {t.x(), t.y(), t.z()}}};
    nlohmann::json children = nlohmann::json::array();
    for (int ch = s + 1; ch < kSegmentCount; ++ch)
      if (model.parent(ch) == s) children.push_back(ch);
    if (!children.empty()) n["children"] = std::move(children);
    nodes.push_back(std::move(n));
  }

  // Inverse bind matrices (column-major): the rest pose has identity rotations, so each is a
  // translation by minus the joint's rest position.
  std::vector<float> ibm;
  for (int s = 0; s < kSegmentCount; ++s) {
    const Eigen::Vector3d p = c * rest[s];
    const float m[16] = {
        1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float(-p.x()), float(-p.y()), float(-p.z()), 1};
    ibm.insert(ibm.end(), m, m + 16);
  }
  const int ibm_accessor = buf.add(ibm.data(), ibm.size(), "MAT4", 16);
  nlohmann::json joints = nlohmann::json::array();
  for (int s = 0; s < kSegmentCount; ++s)
    joints.push_back(s);

  nlohmann::json j = {
      {"asset", {{"version", "2.0"}, {"generator", "mocap export"}}},
      {"scene", 0},
      {"scenes", {{{"name", "mocap"}, {"nodes", {0}}}}},
      {"skins",
       {{{"name", "mocap"},
         {"joints", joints},
         {"skeleton", 0},
         {"inverseBindMatrices", ibm_accessor}}}},
  };

  if (frames > 0) {
    std::vector<float> times(static_cast<std::size_t>(frames));
    for (int k = 0; k < frames; ++k)
      times[k] = static_cast<float>(k * opt.frame_time_s);
    const int time_accessor = buf.add(times.data(), times.size(), "SCALAR", 1,
                                      {{"min", {times.front()}}, {"max", {times.back()}}});
    nlohmann::json samplers = nlohmann::json::array(), channels = nlohmann::json::array();
    auto channel = [&](int node, const char* path, int output) {
      samplers.push_back(
          {{"input", time_accessor}, {"output", output}, {"interpolation", "LINEAR"}});
      channels.push_back(
          {{"sampler", samplers.size() - 1}, {"target", {{"node", node}, {"path", path}}}});
    };
    channel(0, "translation", buf.add(root_translation.data(), root_translation.size(), "VEC3", 3));
    for (int s = 0; s < kSegmentCount; ++s)
      channel(s, "rotation", buf.add(rotations[s].data(), rotations[s].size(), "VEC4", 4));
    j["animations"] = {
        {{"name", opt.animation_name}, {"samplers", samplers}, {"channels", channels}}};
  }
  j["nodes"] = std::move(nodes);
  j["accessors"] = std::move(buf.accessors);
  j["bufferViews"] = std::move(buf.views);
  j["buffers"] = {{{"byteLength", buf.bytes.size()}}};

  std::string text = j.dump();
  while (text.size() % 4)
    text.push_back(' ');
  while (buf.bytes.size() % 4)
    buf.bytes.push_back(0);
  std::vector<uint8_t> out;
  const std::size_t total = 12 + 8 + text.size() + 8 + buf.bytes.size();
  out.reserve(total);
  put_u32(out, 0x46546C67);  // "glTF"
  put_u32(out, 2);
  put_u32(out, static_cast<uint32_t>(total));
  put_u32(out, static_cast<uint32_t>(text.size()));
  put_u32(out, 0x4E4F534A);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  put_u32(out, static_cast<uint32_t>(buf.bytes.size()));
  put_u32(out, 0x004E4942);  // "BIN\0"
  out.insert(out.end(), buf.bytes.begin(), buf.bytes.end());
  return out;
}

GltfWriter::GltfWriter(const std::string& path, const BodyModel& model, GltfWriterOptions options)
    : path_(path), model_(model), opt_(std::move(options)) {
  if (!(opt_.frame_time_s > 0))
    throw std::invalid_argument("GltfWriter: frame time must be positive");
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  std::fclose(f);
}

GltfWriter::~GltfWriter() {
  try {
    close();
  } catch (...) {
  }
}

void GltfWriter::write_frame(const PoseFrame& fr) {
  if (closed_) throw std::runtime_error(path_ + ": glTF writer is closed");
  const Eigen::Quaterniond c = q_bvh_body();
  const Eigen::Quaterniond ci = c.conjugate();
  const auto& p = fr.p_earth_segment_m[0];
  const Eigen::Vector3d root = c * Eigen::Vector3d(p[0], p[1], p[2]);
  root_translation_.insert(root_translation_.end(),
                           {float(root.x()), float(root.y()), float(root.z())});
  for (int s = 0; s < kSegmentCount; ++s) {
    Eigen::Quaterniond q =
        c * from_wxyz(s == 0 ? fr.q_earth_segment[0] : fr.q_parent_segment[s]).normalized() * ci;
    // Keep each track on one hemisphere so linear interpolation takes the short way.
    auto& r = rotations_[s];
    if (r.size() >= 4) {
      const std::size_t n = r.size();
      const double dot = r[n - 4] * q.x() + r[n - 3] * q.y() + r[n - 2] * q.z() + r[n - 1] * q.w();
      if (dot < 0) q.coeffs() *= -1;
    }
    r.insert(r.end(), {float(q.x()), float(q.y()), float(q.z()), float(q.w())});
  }
  ++frames_;
}

void GltfWriter::close() {
  if (closed_) return;
  closed_ = true;
  const std::vector<uint8_t> bytes =
      gltf_binary(model_, opt_, frames_, rotations_, root_translation_);
  std::FILE* f = std::fopen(path_.c_str(), "wb");
  if (!f) throw std::runtime_error(path_ + ": cannot open for writing");
  bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) throw std::runtime_error(path_ + ": failed to write glTF file");
}

}  // namespace mocap
