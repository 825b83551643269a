// OpenSim/OpenSense orientations table: the file parses by OpenSense's rules (header keys up to
// `endheader`, a `time` column then one tab-separated column per IMU with OpenSim's names,
// `w,x,y,z` cells of unit norm) and a known rotation arrives in OpenSim's Y-up frame.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "mocap/skeleton/opensim.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap {
namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string part;
  std::istringstream in(s);
  while (std::getline(in, part, sep))
    out.push_back(part);
  return out;
}

struct StoTable {
  std::map<std::string, std::string> header;
  std::vector<std::string> columns;
  std::vector<double> time;
  std::vector<std::vector<Eigen::Quaterniond>> rows;
};

/// Reads a .sto orientations file the way OpenSim's STOFileAdapter does: key=value lines up to
/// `endheader`, a tab-separated column-label line starting with `time`, then rows.
StoTable read_sto(const std::string& path) {
  StoTable t;
  std::ifstream in(path);
  std::string line;
  bool ended = false;
  while (std::getline(in, line)) {
    if (line == "endheader") {
      ended = true;
      break;
    }
    const auto eq = line.find('=');
    EXPECT_NE(eq, std::string::npos) << "header line without '=': " << line;
    t.header[line.substr(0, eq)] = line.substr(eq + 1);
  }
  EXPECT_TRUE(ended) << "no endheader";
  std::getline(in, line);
  t.columns = split(line, '\t');
  while (std::getline(in, line)) {
    const auto cells = split(line, '\t');
    EXPECT_EQ(cells.size(), t.columns.size()) << line;
    t.time.push_back(std::stod(cells.at(0)));
    std::vector<Eigen::Quaterniond> row;
    for (std::size_t c = 1; c < cells.size(); ++c) {
      const auto v = split(cells[c], ',');
      EXPECT_EQ(v.size(), 4u) << cells[c];
      if (v.size() != 4) continue;
      row.emplace_back(std::stod(v[0]), std::stod(v[1]), std::stod(v[2]), std::stod(v[3]));
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

void set_q(PoseFrame& f, Segment s, const Eigen::Quaterniond& q) {
  f.q_earth_segment[index(s)] = {float(q.w()), float(q.x()), float(q.y()), float(q.z())};
}

}  // namespace

TEST(OpenSim, OrientationsTableParsesWithOpenSimNamesAndYUpQuaternions) {
  const std::string path = std::string(MOCAP_BINARY_DIR) + "/test_opensim.sto";
  {
    OpenSimWriter w(path, {.rate_hz = 50});
    PoseFrame f;
    reset_pose(f);
    f.segment_flags[index(Segment::head)] = kSegTracked;
    w.write_frame(f);  // N-pose facing +x: identity everywhere
    // Turned 90 degrees left (about our up); right forearm rotated 30 degrees about our +y.
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
    for (int s = 0; s < kSegmentCount; ++s)
      set_q(f, static_cast<Segment>(s), turn);
    set_q(f, Segment::forearm_r,
          Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitY())));
    w.write_frame(f);
    for (int k = 0; k < 3; ++k)
      w.write_frame(f);
    EXPECT_EQ(w.frames(), 5);
  }
  const StoTable t = read_sto(path);
  EXPECT_EQ(t.header.at("DataRate"), "50.000000");
  EXPECT_EQ(t.header.at("DataType"), "Quaternion");
  EXPECT_EQ(t.header.at("version"), "3");
  EXPECT_EQ(t.header.at("OpenSimVersion"), "4.1");
  const std::vector<std::string> expect = {
      "time",          "pelvis_imu",   "torso_imu",  "femur_r_imu", "tibia_r_imu", "calcn_r_imu",
      "humerus_r_imu", "radius_r_imu", "hand_r_imu", "femur_l_imu", "tibia_l_imu", "calcn_l_imu",
      "humerus_l_imu", "radius_l_imu", "hand_l_imu", "head_imu"};
  ASSERT_EQ(t.columns, expect);
  ASSERT_EQ(t.rows.size(), 5u);
  for (std::size_t k = 0; k < t.rows.size(); ++k) {
    EXPECT_NEAR(t.time[k], 0.02 * k, 1e-9);
    ASSERT_EQ(t.rows[k].size(), expect.size() - 1);
    for (const auto& q : t.rows[k])
      EXPECT_NEAR(q.norm(), 1.0, 1e-6);
  }
  for (const auto& q : t.rows[0])
    EXPECT_LT(angle_between_deg(q, Eigen::Quaterniond::Identity()), 1e-4);
  // Turning left about up is +90 degrees about OpenSim's y (up): w = cos 45, y = sin 45.
  const Eigen::Quaterniond yaw_left(std::sqrt(0.5), 0, std::sqrt(0.5), 0);
  EXPECT_LT(angle_between_deg(t.rows[1][0], yaw_left), 1e-4);  // pelvis_imu
  EXPECT_NEAR(t.rows[1][0].w(), std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(t.rows[1][0].y(), std::sqrt(0.5), 1e-6);
  // Our +y (left) is OpenSim's -z (z points right): 30 degrees about -z.
  const Eigen::Quaterniond forearm(std::cos(M_PI / 12), 0, 0, -std::sin(M_PI / 12));
  EXPECT_LT(angle_between_deg(t.rows[1][6], forearm), 1e-4);  // radius_r_imu
  // A vector rotated by the exported quaternion equals ours mapped to OpenSim's axes.
  const Eigen::Vector3d ours_forward_turned(0, 1, 0);  // +x turned left: +y (left)
  const Eigen::Vector3d opensim = t.rows[1][0] * Eigen::Vector3d::UnitX();
  EXPECT_LT((opensim - Eigen::Vector3d(ours_forward_turned.x(), ours_forward_turned.z(),
                                       -ours_forward_turned.y()))
                .norm(),
            1e-6);
}

TEST(OpenSim, NoHeadColumnWithoutAHeadSensor) {
  const std::string path = std::string(MOCAP_BINARY_DIR) + "/test_opensim_nohead.sto";
  {
    OpenSimWriter w(path, {.rate_hz = 120});
    PoseFrame f;
    reset_pose(f);
    w.write_frame(f);
  }
  const StoTable t = read_sto(path);
  EXPECT_EQ(t.columns.size(), 15u);
  EXPECT_EQ(t.columns.back(), "hand_l_imu");
  EXPECT_EQ(t.header.at("DataRate"), "120.000000");
}

}  // namespace mocap
