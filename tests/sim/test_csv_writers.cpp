// CSV writers: headers, one row per sample / per segment, values that parse back.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "mocap/sim/csv_writers.hpp"
#include "mocap/sim/performer.hpp"

namespace mocap::sim {
namespace {

std::vector<std::string> read_lines(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(f, l);)
    lines.push_back(l);
  return lines;
}

TEST(CsvWriters, ImuAndTruthFilesRoundTrip) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("mocap_sim_csv_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  PerformerParams p;
  p.t0_ns = 5'000'000'000;
  Performer perf(p);
  std::vector<std::string> names;
  for (int i = 0; i < Performer::kSensorCount; ++i)
    names.emplace_back(Performer::sensor_name(i));
  ImuCsvWriter imu((dir / "imu.csv").string(), names, p.t0_ns);
  TruthCsvWriter truth((dir / "truth.csv").string());
  std::vector<ImuSample> out;
  perf.step_to(p.t0_ns + 50'000'000, out);
  for (const auto& s : out)
    imu.write(s);
  truth.write(perf.truth());
  imu.close();
  truth.close();

  const auto imu_lines = read_lines((dir / "imu.csv").string());
  ASSERT_EQ(imu_lines.size(), out.size() + 1);
  EXPECT_EQ(imu_lines[0], ImuCsvWriter::kHeader);
  std::stringstream row(imu_lines[1]);
  std::string cell;
  std::vector<std::string> cells;
  while (std::getline(row, cell, ','))
    cells.push_back(cell);
  ASSERT_EQ(cells.size(), 11u);
  EXPECT_NEAR(std::stod(cells[0]), (out[0].t_host_ns - p.t0_ns) * 1e-9, 1e-9);
  EXPECT_EQ(cells[1], names[out[0].sensor_id]);
  EXPECT_NEAR(std::stod(cells[7]), out[0].acc_m_s2.z(), 1e-6);

  const auto truth_lines = read_lines((dir / "truth.csv").string());
  ASSERT_EQ(truth_lines.size(), 1u + kSegmentCount);
  EXPECT_EQ(truth_lines[0], TruthCsvWriter::kHeader);
  EXPECT_EQ(truth_lines[1].substr(0, 19), "0.050000000,pelvis,");
  std::filesystem::remove_all(dir);
}

TEST(CsvWriters, UnwritablePathNamesThePath) {
  try {
    ImuCsvWriter w("/nonexistent-dir/imu.csv", {}, 0);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/imu.csv"), std::string::npos);
  }
}

}  // namespace
}  // namespace mocap::sim
