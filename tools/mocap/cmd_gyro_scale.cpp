// mocap gyro-scale: the one-time gyro scale calibration of each sensor from a recording of table
// spins (estimate_gyro_scale: each axis vertical in turn, whole turns, rests between) ->
// the `gyr_scale = [x, y, z]` line of each sensor's [[sensor]] table.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/daemon/sample_csv.hpp"
#include "mocap/filter/gyro_scale.hpp"
#include "mocap/session/session_reader.hpp"

namespace mocap::cmd {

namespace {

constexpr const char* kUsage =
    "A consumer gyro's scale is off by ~0.5 % per axis, which turns every sensor's heading by a\n"
    "different degree or two in each half turn of the body. Measure it once per sensor: record\n"
    "(`mocapctl record start spins.mocapses`) while each sensor lies on a table with one axis up,\n"
    "is turned whole turns by hand (3 are plenty, 10 without a magnetometer; up to ~300 deg/s)\n"
    "and put down again, for each of its three axes, with ~2 s still before and after every\n"
    "spin; putting it back turned is fine (the magnetometer measures the net turn; without one,\n"
    "put it back against an edge exactly as it lay). Several sensors may be spun together.\n"
    "Prints each sensor's gyr_scale line for its [[sensor]] table.\n";

/// Samples per sensor of a recording, with the sensors' names.
struct Recording {
  std::vector<std::string> names;
  std::vector<std::vector<ImuSample>> samples;
  void add(const ImuSample& s) {
    if (samples.size() <= s.sensor_id) samples.resize(s.sensor_id + 1);
    samples[s.sensor_id].push_back(s);
  }
};

bool is_session(const std::string& path) {
  char magic[sizeof session::kMagic] = {};
  std::ifstream in(path, std::ios::binary);
  return in.read(magic, sizeof magic) && std::memcmp(magic, session::kMagic, sizeof magic) == 0;
}

bool read_session(const std::string& path, Recording& rec, std::string& error) {
  SessionReader r;
  if (!r.open(path, &error)) return false;
  for (const auto& d : r.header().sensors)
    rec.names.push_back(d.name);
  SessionReader::Block b;
  while (r.next(b))
    if (b.type == session::BlockType::sample && b.sample.sensor_id < rec.names.size())
      rec.add(b.sample);
  if (r.end() != SessionReader::End::clean)
    std::fprintf(stderr, "mocap gyro-scale: %s: %s (read up to there)\n", path.c_str(),
                 r.tail_reason().c_str());
  return true;
}

bool read_csv(const std::string& path, Recording& rec, std::string& error) {
  std::ifstream in(path);
  if (!in) {
    error = "cannot open " + path;
    return false;
  }
  daemon::SampleCsvParser parser(path);
  std::string line;
  ImuSample s;
  while (std::getline(in, line)) {
    const int r = parser.feed_line(line, s);
    if (r < 0) {
      error = parser.error();
      return false;
    }
    if (r > 0) rec.add(s);
  }
  rec.names = parser.sensors();
  return true;
}

int run_gyro_scale(const std::string& path) {
  Recording rec;
  std::string error;
  if (!(is_session(path) ? read_session(path, rec, error) : read_csv(path, rec, error))) {
    std::fprintf(stderr, "mocap gyro-scale: %s\n", error.c_str());
    return 1;
  }
  if (rec.samples.empty()) {
    std::fprintf(stderr, "mocap gyro-scale: %s holds no samples\n", path.c_str());
    return 1;
  }
  int missing = 0;
  for (size_t i = 0; i < rec.samples.size(); ++i) {
    if (rec.samples[i].empty()) continue;
    const std::string& name = rec.names[i];
    const GyroScaleResult r = estimate_gyro_scale(rec.samples[i]);
    std::printf("# %s: %d rests, spins about x/y/z %d/%d/%d, %d motions not a clean spin\n",
                name.c_str(), r.rests, r.axis[0].spins, r.axis[1].spins, r.axis[2].spins,
                r.rejected_spins);
    std::string unspun;
    for (int ax = 0; ax < 3; ++ax)
      if (r.axis[ax].spins == 0) unspun += std::string(unspun.empty() ? "" : ", ") + "xyz"[ax];
    if (!unspun.empty()) {
      // A partial calibration would tell the daemon the gyro is calibrated when it is not.
      std::printf("# %s: not calibrated (no clean spin about %s)\n", name.c_str(), unspun.c_str());
      std::fprintf(stderr, "mocap gyro-scale: %s: no clean spin about %s: spin it again\n",
                   name.c_str(), unspun.c_str());
      ++missing;
      continue;
    }
    std::printf("# in the [[sensor]] table with name = \"%s\":\n", name.c_str());
    std::printf("gyr_scale = [%.6f, %.6f, %.6f]\n", r.axis[0].scale, r.axis[1].scale,
                r.axis[2].scale);
  }
  return missing ? 1 : 0;
}

}  // namespace

void add_gyro_scale(CLI::App& app, int& exit_code) {
  auto path = std::make_shared<std::string>();
  CLI::App* c = cli::add_command(
      app, "gyro-scale", "each sensor's gyro scale from table spins (a one-time calibration)");
  c->footer(kUsage);
  c->add_option("RECORDING", *path, "a session file, or an interchange CSV t,sensor,gyr_x..mag_z")
      ->required();
  c->callback([path, &exit_code] { exit_code = run_gyro_scale(*path); });
}

}  // namespace mocap::cmd
