// The options of each output, as the [outputs.*] sections of the daemon's configuration hold
// them: one struct per output with each key's value and its default. The keys' names, ranges,
// units and help text are declared once, in the daemon's key table (daemon/src/config_keys.cpp),
// which reads the configuration into these structs.
#pragma once

#include <string>
#include <vector>

namespace mocap::outputs {

/// [outputs.json]: the pose JSON stream (json_stream.hpp).
struct JsonOutputConfig {
  bool enabled = true;
  std::string bind = "127.0.0.1";
  int port = 7301;
  int max_clients = 32;  ///< further connections are closed at once
  /// Private stream: serve it on this Unix socket (mode 0600, only the daemon's user) instead of
  /// TCP (bind/port unused). "" = TCP.
  std::string unix_socket;
};

/// [outputs.vmc]: VMC over OSC/UDP (vmc.hpp).
struct VmcOutputConfig {
  bool enabled = false;
  std::string host = "127.0.0.1";
  int port = 39539;
};

/// [outputs.vrchat]: VRChat OSC trackers (vrchat.hpp, docs/streaming.md section 3).
struct VrchatOutputConfig {
  bool enabled = false;
  std::string host = "127.0.0.1";
  int port = 9000;
  /// Segment sent as tracker 1..8 (1 to 8 names; a slot named "" is not sent).
  std::vector<std::string> trackers = {"pelvis",  "torso",   "foot_l",    "foot_r",
                                       "shank_l", "shank_r", "forearm_l", "forearm_r"};
  bool head = true;     ///< also send the head (/tracking/trackers/head/...) for alignment
  double height_m = 0;  ///< the user's height as VRChat knows it; 0 = the body model's height
};

/// [outputs.posture]: the shared posture for the viewer (posture_output.hpp).
struct PostureOutputConfig {
  bool enabled = true;
  std::string shm_name;  ///< "" = "/mocap-posture-<uid>"
};

/// Every output's options (the daemon's Config::outputs).
struct OutputsConfig {
  JsonOutputConfig json;
  VmcOutputConfig vmc;
  VrchatOutputConfig vrchat;
  PostureOutputConfig posture;
};

/// [recording]: the session recorder (recorder.hpp), started and stopped by the control socket.
struct RecordingConfig {
  std::string directory = ".";  ///< where relative file names of `record start` go
  bool raw = true;              ///< store raw device bytes (bit-exact replay through drivers)
  bool samples = true;          ///< store decoded samples
  bool poses = true;            ///< store published pose frames
  std::string auto_start;       ///< file to start recording into at startup ("" = none)
  // Block compression on the recorder's writer thread (docs/session-format.md).
  std::string compression = "none";  ///< "none" | "zstd"
  int compression_level = 3;         ///< zstd level 1..19
};

}  // namespace mocap::outputs
