// End to end: `mocap gyro-scale` on a real session file and on an interchange CSV holding the
// virtual sensors' table spins (sim::table_spin_samples, the consumer-MEMS error model): the
// printed gyr_scale lines are each sensor's drawn scale and parse as config; a sensor that was
// never spun gets no line and is named, with a non-zero exit.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "mocap/daemon/config.hpp"
#include "mocap/session/session_writer.hpp"
#include "mocap/sim/csv_writers.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/sim/table_spin.hpp"

namespace fs = std::filesystem;

namespace mocap {
namespace {

const std::string kMocap = std::string(MOCAP_BINARY_DIR) + "/bin/mocap";

struct ToolRun {
  int exit_code = -1;
  std::string out, err;
};

ToolRun run_tool(const std::string& file, const fs::path& dir) {
  const fs::path err = dir / "stderr.txt";
  const std::string cmd = kMocap + " gyro-scale '" + file + "' 2>'" + err.string() + "'";
  ToolRun r;
  std::FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0)
    r.out.append(buf, n);
  const int st = pclose(p);
  r.exit_code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::FILE* e = std::fopen(err.c_str(), "r");
  while (e && (n = std::fread(buf, 1, sizeof buf, e)) > 0)
    r.err.append(buf, n);
  if (e) std::fclose(e);
  return r;
}

/// The gyr_scale line printed after `# in the [[sensor]] table with name = "NAME":`.
std::string scale_line(const std::string& out, const std::string& name) {
  const std::string marker = "name = \"" + name + "\":\n";
  const size_t at = out.find(marker);
  if (at == std::string::npos) return "";
  const size_t begin = at + marker.size();
  return out.substr(begin, out.find('\n', begin) - begin);
}

/// Three sensors' samples in time order: "a" spun (seed 1), "b" spun and put back 25 deg
/// turned (seed 2), "c" lying still as long.
struct Spins {
  sim::SensorErrorModel a{sim::SensorModelParams{}, 100, 1}, b{sim::SensorModelParams{}, 100, 2};
  std::vector<ImuSample> samples;
  Spins() {
    auto sa = sim::table_spin_samples(a, sim::MagneticFieldParams{}, 100);
    auto sb = sim::table_spin_samples(b, sim::MagneticFieldParams{}, 100, 3, 25);
    sim::SensorErrorModel still(sim::SensorModelParams{}, 100, 3);
    std::vector<ImuSample> sc;
    for (const ImuSample& s : sa) {
      sim::SensorKinematics k;
      ImuSample c;
      still.measure(k, sim::MagneticFieldParams{}.earth_field_uT(), 0.01, c);
      c.t_host_ns = c.t_device_ns = s.t_host_ns;
      sc.push_back(c);
    }
    for (ImuSample& s : sb)
      s.sensor_id = 1;
    for (ImuSample& s : sc)
      s.sensor_id = 2;
    samples = sa;
    samples.insert(samples.end(), sb.begin(), sb.end());
    samples.insert(samples.end(), sc.begin(), sc.end());
    std::stable_sort(samples.begin(), samples.end(), [](const ImuSample& x, const ImuSample& y) {
      return x.t_host_ns < y.t_host_ns;
    });
  }
};

void expect_scale(const std::string& line, const Eigen::Vector3d& truth) {
  daemon::ConfigErrors errs;
  const auto cfg = daemon::parse_config(
      "[[sensor]]\nname = \"x\"\ndriver = \"witmotion\"\nport = \"/dev/null\"\n" + line + "\n",
      "printed.toml", {}, errs);
  ASSERT_TRUE(cfg) << errs.to_string() << line;
  ASSERT_TRUE(cfg->sensors[0].gyr_scale) << line;
  for (int ax = 0; ax < 3; ++ax)
    EXPECT_NEAR((*cfg->sensors[0].gyr_scale)[ax], truth[ax], 1e-3) << line << " axis " << ax;
}

TEST(GyroScaleTool, SessionFileGivesEachSensorsScaleAndNamesTheUnspunOne) {
  const fs::path dir = fs::path(testing::TempDir()) / "gyro_scale_session";
  fs::create_directories(dir);
  const Spins spins;
  session::SessionHeader h;
  for (const char* name : {"a", "b", "c"})
    h.sensors.push_back({name, "witmotion", -1, 0});
  std::string error;
  const std::string path = (dir / "spins.mocapses").string();
  auto w = SessionWriter::create(path, h, {}, &error);
  ASSERT_TRUE(w) << error;
  for (const ImuSample& s : spins.samples)
    ASSERT_TRUE(w->append_sample(s));
  ASSERT_TRUE(w->close());

  const ToolRun r = run_tool(path, dir);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;  // "c" was never spun
  expect_scale(scale_line(r.out, "a"), spins.a.gyr_scale());
  expect_scale(scale_line(r.out, "b"), spins.b.gyr_scale());
  EXPECT_EQ(scale_line(r.out, "c"), "");  // no line: it stays uncalibrated
  EXPECT_NE(r.out.find("# c: not calibrated (no clean spin about x, y, z)"), std::string::npos)
      << r.out;
  EXPECT_NE(r.err.find("c: no clean spin about x, y, z: spin it again"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("a: no clean spin"), std::string::npos) << r.err;
}

TEST(GyroScaleTool, InterchangeCsvWithEverySensorSpunExitsZero) {
  const fs::path dir = fs::path(testing::TempDir()) / "gyro_scale_csv";
  fs::create_directories(dir);
  const Spins spins;
  const std::string path = (dir / "spins.csv").string();
  {
    sim::ImuCsvWriter csv(path, {"a", "b", "c"}, 0);
    for (const ImuSample& s : spins.samples)
      if (s.sensor_id < 2) csv.write(s);
    csv.close();
  }
  const ToolRun r = run_tool(path, dir);
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  expect_scale(scale_line(r.out, "a"), spins.a.gyr_scale());
  expect_scale(scale_line(r.out, "b"), spins.b.gyr_scale());
  // A file that is neither gives an error naming the problem.
  std::FILE* f = std::fopen((dir / "junk.csv").c_str(), "w");
  std::fputs("hello,world\n1,2\n", f);
  std::fclose(f);
  const ToolRun bad = run_tool((dir / "junk.csv").string(), dir);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("junk.csv"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace mocap
