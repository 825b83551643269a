// Command-line options of mocap-viewer and the entry points of its three modes.
#pragma once

#include <memory>
#include <string>

#include "mocap/viewer/pose_source.hpp"
#include "mocap/viewer/view.hpp"

namespace mocap::viewer {

struct ViewerOptions {
  std::string source = "shm";  ///< shm | synthetic | connect | play
  std::string shm_name;        ///< default_posture_shm_name() if empty
  std::string connect;         ///< HOST:PORT
  std::string play;            ///< file
  std::string control_socket;  ///< default_control_socket_path() if empty
  int avatars = 1;
  double height_m = 1.75;
  int width = 1280, height = 720;
  std::string screenshot;  ///< PNG path: headless mode
  int frames = 30;         ///< frames rendered before the screenshot
  double wait_s = 5;       ///< headless: how long to wait for a live source's first pose
  bool bench = false;
  double bench_seconds = 3;
  bool vsync = true;
  ViewSettings settings;
};

/// The pose source the options ask for; throws std::runtime_error naming the problem.
std::unique_ptr<PoseSource> make_source(const ViewerOptions& o);

int run_window(const ViewerOptions& o);
int run_screenshot(const ViewerOptions& o);
int run_bench(const ViewerOptions& o);

}  // namespace mocap::viewer
