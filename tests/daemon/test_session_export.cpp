// Tests of `mocap export`: the real command run on real session files (CSV values, a torn tail,
// a file of an unknown version, usage errors, BVH, glTF and OpenSim output).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <zlib.h>

#include <Eigen/Geometry>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "session_test_util.hpp"

using namespace mocap;
using namespace mocap::test;
using mocap::SessionWriter;

namespace {

const std::string kMocap = std::string(MOCAP_BINARY_DIR) + "/bin/mocap";

int run(const std::string& args, const std::string& err_file) {
  // Both streams: the summary (a JSON line on stdout) and the diagnostics (stderr).
  const int status = std::system((kMocap + " export " + args + " > " + err_file + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

void record(const std::string& path, int frames) {
  std::string err;
  auto w = SessionWriter::create(path, make_header(), {}, &err);
  ASSERT_TRUE(w) << err;
  for (int i = 0; i < frames; ++i) {
    ASSERT_TRUE(w->append_sample(make_sample(static_cast<uint32_t>(i))));
    ASSERT_TRUE(w->append_pose(make_pose(static_cast<uint64_t>(i))));
  }
  ASSERT_TRUE(w->close());
}

/// A session of `poses` alone.
void record_poses(const std::string& path, const session::SessionHeader& header,
                  const std::vector<PoseFrame>& poses) {
  std::string err;
  auto w = SessionWriter::create(path, header, {}, &err);
  ASSERT_TRUE(w) << err;
  for (const PoseFrame& f : poses)
    ASSERT_TRUE(w->append_pose(f));
  ASSERT_TRUE(w->close());
}

}  // namespace

TEST(SessionExport, CsvHasOneRowPerSegmentPerFrameWithTheRecordedValues) {
  TempDir dir;
  const std::string ses = dir.file("s.mocap"), csv = dir.file("s.csv"), err = dir.file("err");
  record(ses, 5);
  ASSERT_EQ(run(ses + " --csv " + csv, err), 0) << read_text(err);
  std::istringstream in(read_text(csv));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "t,segment,w,x,y,z,px,py,pz");
  int rows = 0;
  while (std::getline(in, line)) {
    const int frame = rows / kSegmentCount, s = rows % kSegmentCount;
    const PoseFrame f = make_pose(static_cast<uint64_t>(frame));
    std::istringstream ls(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ls, cell, ','))
      cells.push_back(cell);
    ASSERT_EQ(cells.size(), 9u) << line;
    EXPECT_NEAR(std::stod(cells[0]), (f.t_ns - make_header().t_start_host_ns) * 1e-9, 1e-6);
    EXPECT_EQ(cells[1], std::string(kSegmentNames[s]));
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(std::stod(cells[2 + k]), f.q_earth_segment[s][k], 1e-6);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(std::stod(cells[6 + k]), f.p_earth_segment_m[s][k], 1e-5);
    ++rows;
  }
  EXPECT_EQ(rows, 5 * kSegmentCount);
}

TEST(SessionExport, JsonLinesAreThePoseStreamsWithTheRecordedWallClock) {
  TempDir dir;
  const std::string ses = dir.file("j.mocap"), out = dir.file("j.jsonl"), err = dir.file("err");
  record(ses, 6);
  ASSERT_EQ(run(ses + " --json " + out, err), 0) << read_text(err);
  const session::SessionHeader h = make_header();
  std::istringstream in(read_text(out));
  std::string line;
  uint64_t frame = 0;
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line);
    const PoseFrame f = make_pose(frame);
    EXPECT_EQ(j["v"], 1);
    EXPECT_EQ(j["frame"].get<uint64_t>(), f.frame);
    EXPECT_EQ(j["t_ns"].get<int64_t>(), f.t_ns);
    // the wall clock of the recording: its header's offset (no clock blocks in this file)
    EXPECT_EQ(j["t_unix_ns"].get<int64_t>(), f.t_ns + (h.t_start_unix_ns - h.t_start_host_ns));
    ASSERT_EQ(j["segments"].size(), static_cast<std::size_t>(kSegmentCount));
    for (int s = 0; s < kSegmentCount; ++s) {
      EXPECT_EQ(j["segments"][s]["name"], std::string(kSegmentNames[s]));
      for (int k = 0; k < 4; ++k)
        EXPECT_NEAR(j["segments"][s]["q"][k].get<double>(), f.q_earth_segment[s][k], 1e-5);
    }
    ++frame;
  }
  EXPECT_EQ(frame, 6u);
}

TEST(SessionExport, TornTailIsReportedAndTheRestExported) {
  TempDir dir;
  const std::string ses = dir.file("t.mocap"), csv = dir.file("t.csv"), err = dir.file("err");
  record(ses, 4);
  std::filesystem::resize_file(ses, std::filesystem::file_size(ses) - 10);  // cut the last pose
  ASSERT_EQ(run(ses + " --csv " + csv, err), 0) << read_text(err);
  EXPECT_NE(read_text(err).find("ignored"), std::string::npos) << read_text(err);
  const std::string text = read_text(csv);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1 + 3 * kSegmentCount);
}

TEST(SessionExport, BadInputsGiveClearErrors) {
  TempDir dir;
  const std::string ses = dir.file("v.mocap"), err = dir.file("err");
  record(ses, 1);
  {  // a version-9 file: its header is intact (valid CRC), so it is not taken for damage
    std::fstream f(ses, std::ios::in | std::ios::out | std::ios::binary);
    std::vector<uint8_t> head(20);
    f.read(reinterpret_cast<char*>(head.data()), 20);
    head.resize(20 + mocap::session::get_u32(head.data() + 16));
    f.read(reinterpret_cast<char*>(head.data() + 20),
           static_cast<std::streamsize>(head.size() - 20));
    mocap::session::put_u32(head.data() + 8, 9);
    uint8_t crc[4];
    mocap::session::put_u32(
        crc, static_cast<uint32_t>(crc32(0L, head.data(), static_cast<uInt>(head.size()))));
    f.seekp(0);
    f.write(reinterpret_cast<const char*>(head.data()), static_cast<std::streamsize>(head.size()));
    f.write(reinterpret_cast<const char*>(crc), 4);
  }
  EXPECT_EQ(run(ses + " --csv " + dir.file("o.csv"), err), 1);
  EXPECT_NE(read_text(err).find("version 9 is not supported"), std::string::npos) << read_text(err);
  EXPECT_EQ(run(dir.file("missing.mocap") + " --csv " + dir.file("o.csv"), err), 1);
  EXPECT_NE(read_text(err).find("missing.mocap"), std::string::npos);
  EXPECT_EQ(run(ses, err), 2);  // neither --csv nor --bvh
  EXPECT_NE(read_text(err).find("give one output: --csv, --json, --bvh, --gltf or --opensim"),
            std::string::npos)
      << read_text(err);
}

namespace {

/// A pose whose joint rotations agree with its segment orientations (as the pipeline makes).
PoseFrame consistent_pose(uint64_t i, std::mt19937& rng) {
  PoseFrame f = make_pose(i);
  std::normal_distribution<double> n(0, 0.3);
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  for (int s = 0; s < kSegmentCount; ++s) {
    q[s] = Eigen::Quaterniond(1, n(rng), n(rng), n(rng)).normalized();
    f.q_earth_segment[s] = {float(q[s].w()), float(q[s].x()), float(q[s].y()), float(q[s].z())};
    const int parent = kSegmentParent[s];
    const Eigen::Quaterniond qp = parent < 0 ? q[s] : q[parent].conjugate() * q[s];
    f.q_parent_segment[s] = {float(qp.w()), float(qp.x()), float(qp.y()), float(qp.z())};
  }
  return f;
}

/// Six consistent poses (seeded) recorded as a 1.62 m body at 100 Hz; returns them.
std::vector<PoseFrame> record_consistent_take(const std::string& path, unsigned seed) {
  auto header = make_header();
  header.config_text = "[body]\nheight_m = 1.62\n[pipeline]\nrate_hz = 100\n";
  std::mt19937 rng(seed);
  std::vector<PoseFrame> poses;
  for (uint64_t i = 0; i < 6; ++i)
    poses.push_back(consistent_pose(i, rng));
  record_poses(path, header, poses);
  return poses;
}

}  // namespace

TEST(SessionExport, BvhReadsBackThroughTheSkeletonsReaderWithTheRecordedBody) {
  TempDir dir;
  const std::string ses = dir.file("b.mocap"), bvh = dir.file("b.bvh"), err = dir.file("err");
  std::vector<PoseFrame> poses;
  ASSERT_NO_FATAL_FAILURE(poses = record_consistent_take(ses, 3));
  ASSERT_EQ(run(ses + " --bvh " + bvh, err), 0) << read_text(err);
  EXPECT_EQ(read_text(err).find("warning"), std::string::npos) << read_text(err);
  const std::string text = read_text(bvh);
  const std::string hierarchy = bvh_hierarchy(BodyModel(body_dimensions_from_height(1.62)));
  EXPECT_EQ(text.substr(0, hierarchy.size()), hierarchy);
  const BvhClip clip = parse_bvh(text, bvh);
  ASSERT_EQ(clip.frame_count, 6);
  EXPECT_NEAR(clip.frame_time_s, 0.010,
              1e-9);  // the recorded rate; make_pose frames are 10 ms apart
  const BvhMotion motion(clip);
  for (int k = 0; k < 6; ++k) {
    std::array<Eigen::Quaterniond, kSegmentCount> q;
    Eigen::Vector3d root;
    motion.frame(k, q, root);
    for (int s = 0; s < kSegmentCount; ++s) {
      const auto& r = poses[k].q_earth_segment[s];
      const Eigen::Quaterniond expect(r[0], r[1], r[2], r[3]);
      EXPECT_GT(std::abs(q[s].normalized().dot(expect)), 1 - 1e-6) << "frame " << k << " " << s;
    }
    const auto& p = poses[k].p_earth_segment_m[0];
    EXPECT_NEAR((root - Eigen::Vector3d(p[0], p[1], p[2])).norm(), 0, 1e-5);
  }
}

// Export finishes the poses for animation tools: a sensor's 200 ms dropout (its segment held by
// the live pipeline, the sample age growing) comes out slerped across the gap, and --frame-rate
// resamples to one fixed frame time.
TEST(SessionExport, BridgesDropoutsAndResamples) {
  TempDir dir;
  const std::string ses = dir.file("d.mocap"), csv = dir.file("d.csv"), err = dir.file("err");
  constexpr int kNeck = 2;  // driven by make_pose's sensor 2
  std::vector<PoseFrame> poses;
  for (uint64_t i = 0; i < 60; ++i) {
    poses.push_back(make_pose(i));
    if (i >= 20 && i < 40) {  // silent: held at frame 19's orientation
      poses.back().q_earth_segment[kNeck] = make_pose(19).q_earth_segment[kNeck];
      poses.back().sensors[kNeck].last_age_ms = 10.0f * static_cast<float>(i - 19);
    }
  }
  ASSERT_NO_FATAL_FAILURE(record_poses(ses, make_header(), poses));
  ASSERT_EQ(run(ses + " --csv " + csv, err), 0) << read_text(err);
  for (const char* fact :
       {"\"frames\":60", "\"body_height_m\":1.75", "\"bridged_segment_frames\":20"})
    EXPECT_NE(read_text(err).find(fact), std::string::npos) << fact << "\n" << read_text(err);
  // Row of frame 30's neck: the orientation make_pose gives frame 30 (its angle is linear in
  // time, so the slerp across the gap reproduces it), not the held one.
  std::istringstream in(read_text(csv));
  std::string line;
  for (int row = 0; row <= 1 + 30 * kSegmentCount + kNeck; ++row)
    ASSERT_TRUE(std::getline(in, line));
  std::vector<double> v;
  std::istringstream ls(line.substr(line.find(",neck,") + 6));
  for (std::string cell; std::getline(ls, cell, ',');)
    v.push_back(std::stod(cell));
  ASSERT_EQ(v.size(), 7u) << line;
  const auto expect = make_pose(30).q_earth_segment[kNeck];
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(v[k], expect[k], 2e-6) << line;
  EXPECT_GT(std::abs(make_pose(19).q_earth_segment[kNeck][2] - expect[2]), 0.01);

  // 60 frames over 590 ms at 50 Hz: 30 frames, 20 ms apart.
  ASSERT_EQ(run(ses + " --bvh " + dir.file("d.bvh") + " --frame-rate 50", err), 0)
      << read_text(err);
  const BvhClip clip = parse_bvh(read_text(dir.file("d.bvh")), "d.bvh");
  EXPECT_EQ(clip.frame_count, 30);
  EXPECT_NEAR(clip.frame_time_s, 0.020, 1e-9);
  EXPECT_EQ(run(ses + " --bvh " + dir.file("d.bvh") + " --rate 0", err), 2);
}

TEST(SessionExport, GltfAndOpenSimFromTheRecordedTake) {
  TempDir dir;
  const std::string ses = dir.file("g.mocap"), err = dir.file("err");
  std::vector<PoseFrame> poses;
  ASSERT_NO_FATAL_FAILURE(poses = record_consistent_take(ses, 5));
  // glTF: the container and the time accessor's frame count and range.
  ASSERT_EQ(run(ses + " --gltf " + dir.file("g.glb"), err), 0) << read_text(err);
  const std::string glb = read_text(dir.file("g.glb"));
  ASSERT_GT(glb.size(), 20u);
  EXPECT_EQ(glb.substr(0, 4), "glTF");
  uint32_t json_len = 0;
  std::memcpy(&json_len, glb.data() + 12, 4);
  const auto j = nlohmann::json::parse(glb.substr(20, json_len));
  const auto& time = j["accessors"][j["animations"][0]["samplers"][0]["input"].get<int>()];
  EXPECT_EQ(time["count"], 6);
  EXPECT_NEAR(time["max"][0].get<double>(), 0.05, 1e-6);
  EXPECT_EQ(j["nodes"][0]["name"], "Hips");
  // OpenSim: header, 6 rows at the recorded rate, the pelvis in OpenSim's axes.
  ASSERT_EQ(run(ses + " --opensim " + dir.file("g.sto"), err), 0) << read_text(err);
  std::istringstream sto(read_text(dir.file("g.sto")));
  std::string line;
  std::getline(sto, line);
  EXPECT_EQ(line, "DataRate=100.000000");
  while (std::getline(sto, line) && line != "endheader") {
  }
  std::getline(sto, line);
  EXPECT_EQ(line.rfind("time\tpelvis_imu\ttorso_imu\tfemur_r_imu", 0), 0u) << line;
  int rows = 0;
  while (std::getline(sto, line)) {
    std::istringstream ls(line);
    double t = 0, w = 0, x = 0, y = 0, z = 0;
    char comma = 0;
    ls >> t >> w >> comma >> x >> comma >> y >> comma >> z;
    ASSERT_FALSE(ls.fail()) << line;
    EXPECT_NEAR(t, 0.01 * rows, 1e-9);
    const auto& q = poses[rows].q_earth_segment[0];
    // x_o = x, y_o = z, z_o = -y (a proper rotation: the vector part maps likewise).
    const Eigen::Quaterniond expect(q[0], q[1], q[3], -q[2]);
    EXPECT_GT(std::abs(expect.normalized().dot(Eigen::Quaterniond(w, x, y, z))), 1 - 1e-6);
    ++rows;
  }
  EXPECT_EQ(rows, 6);
  EXPECT_EQ(run(ses + " --gltf a.glb --bvh b.bvh", err), 2);  // one output at a time
}
