// The rig file `mocap setup` writes: the sections the example rigs in config/ start with, then
// one [[sensor]] table per assigned sensor in the segments' order (named after its segment,
// with the port or USB ids and the driver settings that gave samples), and as comments the
// sensors heard but left out, the devices that sent nothing, and the segments left without a
// sensor.
#pragma once

#include <string>
#include <vector>

#include "mocap/daemon/config.hpp"

namespace mocap::setup {

struct RigPlan {
  std::vector<daemon::SensorConfig> sensors;  ///< named, with their segments
  std::vector<std::string> left_out;          ///< sensors heard, never moved alone
  std::vector<std::string> silent;            ///< devices found that sent nothing
  std::vector<std::string> no_sensor;         ///< segments asked for and skipped
  bool use_mag = true;                        ///< false: some sensor has no magnetometer (6D rig)
  std::string calibration_file;
};

/// The TOML text (mocapd --check-config accepts it; tests/setup checks that).
std::string rig_toml(const RigPlan& plan);

}  // namespace mocap::setup
