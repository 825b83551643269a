// mocap-viewer: command line, pose source selection, then the window, screenshot or bench mode.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>

#include "mocap/core/cli.hpp"
#include "mocap/outputs/posture_shm.hpp"
#include "mocap/viewer/bvh_source.hpp"
#include "mocap/viewer/net_source.hpp"
#include "mocap/viewer/session_source.hpp"
#include "mocap/viewer/shm_source.hpp"
#include "mocap/viewer/synthetic_source.hpp"
#include "viewer_options.hpp"

namespace mocap::viewer {
namespace {

bool file_starts_with(const std::string& path, const char* prefix, std::size_t n) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;  // the source's own open reports why
  char head[16] = {};
  const std::size_t got = std::fread(head, 1, std::min(n, sizeof head), f);
  std::fclose(f);
  return got == n && std::memcmp(head, prefix, n) == 0;
}

}  // namespace

std::unique_ptr<PoseSource> make_source(const ViewerOptions& o) {
  const BodyDimensions dims = body_dimensions_from_height(o.height_m);
  if (o.source == "synthetic") return std::make_unique<SyntheticSource>(o.avatars, dims);
  if (o.source == "shm")
    return std::make_unique<ShmSource>(o.shm_name.empty() ? outputs::default_posture_shm_name()
                                                          : o.shm_name);
  if (o.source == "connect") return std::make_unique<NetSource>(o.connect);
  if (o.source == "play") {
    // By content, not by name: a session starts with its signature, a BVH with HIERARCHY.
    if (file_starts_with(o.play, session::kMagic, sizeof session::kMagic))
      return std::make_unique<SessionSource>(o.play);
    return std::make_unique<BvhSource>(o.play);
  }
  throw std::runtime_error("unknown --source '" + o.source + "' (shm, synthetic)");
}

namespace {

bool parse_size(const std::string& s, int& w, int& h) {
  return std::sscanf(s.c_str(), "%dx%d", &w, &h) == 2 && w >= 16 && h >= 16 && w <= 8192 &&
         h <= 8192;
}

/// mocap-viewer's command line: every option declared here, into ViewerOptions and the flags
/// below (turned into ViewSettings after parsing).
struct Flags {
  bool no_vsync = false, stick = false, sensor_axes = false, no_earth_axes = false, no_hud = false,
       no_labels = false, no_shadows = false, follow = false;
  std::string size = "1280x720", control_alias;
};

void declare_options(CLI::App& app, ViewerOptions& o, Flags& f) {
  app.footer("Keys: see docs/viewer.md.");
  CLI::Option* source =
      app.add_option("--source", o.source,
                     "shm (the local daemon's shared posture) or synthetic (a virtual performer)")
          ->check(CLI::IsMember({"shm", "synthetic"}));
  app.add_option("--shm", o.shm_name, "shared posture name (default /mocap-posture-<uid>)");
  CLI::Option* connect = app.add_option(
      "--connect", o.connect,
      "HOST:PORT of a remote daemon's JSON stream (one source: not with --play or --source)");
  CLI::Option* play = app.add_option(
      "--play", o.play,
      "SESSION or BVH file to play back (one source: not with --connect or --source)");
  connect->excludes(source)->excludes(play);
  play->excludes(source);
  app.add_option("--avatars", o.avatars, "number of avatars for the synthetic source (crowd)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--body-height", o.height_m, "body height in metres for the avatar's proportions")
      ->check(CLI::Range(0.5, 2.6));
  app.add_option("--size", f.size, "window or image size WxH (16..8192)")
      ->check(CLI::Validator(
          [](std::string& s) {
            int w = 0, h = 0;
            return parse_size(s, w, h) ? std::string() : "'" + s + "' is not WxH (16..8192)";
          },
          "WxH"));
  CLI::Option* shot = app.add_option(
      "--screenshot", o.screenshot,
      "render offscreen and write this PNG, then exit (no display needed: without X, EGL "
      "on Mesa's surfaceless platform)");
  app.add_option("--frames", o.frames, "frames to render before the screenshot")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--wait", o.wait_s, "screenshot: seconds to wait for a live source's first pose")
      ->check(CLI::NonNegativeNumber);
  cli::add_deprecated_alias(
      app, "--bench-seconds", o.bench_seconds,
      app.add_option("--bench-duration", o.bench_seconds, "seconds per benchmark case (--bench)")
          ->check(CLI::PositiveNumber));
  CLI::Option* socket = app.add_option(
      "--socket", o.control_socket, "daemon control socket (default $XDG_RUNTIME_DIR/mocapd.sock)");
  cli::add_deprecated_alias(app, "--control", f.control_alias, socket);
  app.add_flag("--bench", o.bench,
               "measure frame rates (1 and 150 avatars) in a window and print JSON (not with "
               "--screenshot)")
      ->excludes(shot);
  app.add_flag("--no-vsync", f.no_vsync, "do not wait for the display's refresh");
  app.add_flag("--stick", f.stick, "stick figure instead of solid capsules");
  app.add_flag("--sensor-axes", f.sensor_axes, "draw each segment's x/y/z axes");
  app.add_flag("--no-earth-axes", f.no_earth_axes, "hide the earth axes at the origin");
  app.add_flag("--no-hud", f.no_hud, "hide the heads-up display");
  app.add_flag("--no-labels", f.no_labels, "do not label flagged segments");
  app.add_flag("--no-shadows", f.no_shadows, "no shadows on the floor");
  app.add_flag("--follow", f.follow,
               "keep the camera over the pelvis (always when playing a file)");
}

}  // namespace
}  // namespace mocap::viewer

int main(int argc, char** argv) {
  using namespace mocap;
  using namespace mocap::viewer;
  CLI::App app{
      "mocap-viewer: shows the avatar of the local daemon (shared posture), a remote stream, a "
      "file, or a synthetic performer",
      "mocap-viewer"};
  cli::setup_program(app);
  ViewerOptions o;
  Flags f;
  declare_options(app, o, f);
  if (auto done = cli::parse(app, argc, argv)) return *done;
  if (!o.connect.empty()) o.source = "connect";
  if (!o.play.empty()) o.source = "play";
  if (!f.control_alias.empty()) o.control_socket = f.control_alias;
  parse_size(f.size, o.width, o.height);
  o.vsync = !f.no_vsync;
  o.settings.style.stick = f.stick;
  o.settings.style.sensor_axes = f.sensor_axes;
  o.settings.earth_axes = !f.no_earth_axes;
  o.settings.hud = !f.no_hud;
  o.settings.labels = !f.no_labels;
  o.settings.shadows = !f.no_shadows;
  o.settings.follow = f.follow || o.source == "play";  // files walk off anywhere

  try {
    if (o.bench) return run_bench(o);
    if (!o.screenshot.empty()) return run_screenshot(o);
    return run_window(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap-viewer: %s\n", e.what());
    return 1;
  }
}
