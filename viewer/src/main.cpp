// mocap-viewer: command line, pose source selection, then the window, screenshot or bench mode.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>

#include "mocap/core/cli_args.hpp"
#include "mocap/skeleton/posture_shm.hpp"
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
    return std::make_unique<ShmSource>(o.shm_name.empty() ? default_posture_shm_name()
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

int usage(const CliArgs& cli, const char* error) {
  if (error) std::fprintf(stderr, "mocap-viewer: %s\n\n", error);
  std::fprintf(error ? stderr : stdout,
               "usage: mocap-viewer [options]\n"
               "Shows the avatar of the local daemon (shared posture), a remote stream, a file,\n"
               "or a synthetic performer. Keys: see docs/viewer.md.\n\n%s",
               cli.help().c_str());
  return error ? 2 : 0;
}

}  // namespace
}  // namespace mocap::viewer

int main(int argc, char** argv) {
  using namespace mocap;
  using namespace mocap::viewer;
  CliArgs cli;
  cli.option("source", "shm (default: the local daemon's shared posture) or synthetic")
      .option("shm", "shared posture name (default /mocap-posture-<uid>)")
      .option("connect", "HOST:PORT of a remote daemon's JSON stream")
      .option("play", "SESSION or BVH file to play back")
      .option("avatars", "number of avatars for the synthetic source (crowd), default 1")
      .option("body-height", "body height in metres for the avatar's proportions (1.75)")
      .option("size", "window or image size WxH (1280x720)")
      .option("screenshot", "render headless and write this PNG, then exit")
      .option("frames", "frames to render before the screenshot (30)")
      .option("wait", "headless: seconds to wait for a live source's first pose (5)")
      .option("bench-seconds", "seconds per benchmark case (3)")
      .option("control", "daemon control socket (default $XDG_RUNTIME_DIR/mocapd.sock)")
      .flag("bench", "measure frame rates (1 and 150 avatars) and print JSON")
      .flag("no-vsync", "do not wait for the display's refresh")
      .flag("stick", "stick figure instead of solid capsules")
      .flag("sensor-axes", "draw each segment's x/y/z axes")
      .flag("no-earth-axes", "hide the earth axes at the origin")
      .flag("no-hud", "hide the heads-up display")
      .flag("no-labels", "do not label flagged segments")
      .flag("no-shadows", "no shadows on the floor")
      .flag("follow", "keep the camera over the pelvis")
      .flag("help", "this text");
  if (!cli.parse(argc, argv)) return usage(cli, cli.error().c_str());
  if (cli.has("help")) return usage(cli, nullptr);
  if (!cli.positional().empty())
    return usage(cli, ("unexpected argument '" + cli.positional()[0] + "'").c_str());

  ViewerOptions o;
  o.source = cli.get_or("source", "shm");
  o.shm_name = cli.get_or("shm", "");
  if (auto c = cli.get("connect")) o.source = "connect", o.connect = *c;
  if (auto p = cli.get("play")) o.source = "play", o.play = *p;
  o.control_socket = cli.get_or("control", "");
  long n = 1;
  if (!cli.get_int("avatars", n) || n < 1 || n > 10000)
    return usage(cli, "--avatars must be an integer in 1..10000");
  o.avatars = static_cast<int>(n);
  if (!cli.get_double("body-height", o.height_m) || !(o.height_m > 0.5 && o.height_m < 2.6))
    return usage(cli, "--body-height must be a height in metres (0.5..2.6)");
  if (auto s = cli.get("size"); s && !parse_size(*s, o.width, o.height))
    return usage(cli, ("--size '" + *s + "' is not WxH (16..8192)").c_str());
  o.screenshot = cli.get_or("screenshot", "");
  long frames = o.frames;
  if (!cli.get_int("frames", frames) || frames < 1 || frames > 1000000)
    return usage(cli, "--frames must be a positive integer");
  o.frames = static_cast<int>(frames);
  if (!cli.get_double("wait", o.wait_s) || !(o.wait_s >= 0))
    return usage(cli, "--wait must be a number of seconds");
  if (!cli.get_double("bench-seconds", o.bench_seconds) || !(o.bench_seconds > 0))
    return usage(cli, "--bench-seconds must be positive");
  o.bench = cli.has("bench");
  o.vsync = !cli.has("no-vsync");
  o.settings.style.stick = cli.has("stick");
  o.settings.style.sensor_axes = cli.has("sensor-axes");
  o.settings.earth_axes = !cli.has("no-earth-axes");
  o.settings.hud = !cli.has("no-hud");
  o.settings.labels = !cli.has("no-labels");
  o.settings.shadows = !cli.has("no-shadows");
  o.settings.follow = cli.has("follow") || o.source == "play";  // files walk off anywhere

  try {
    if (o.bench) return run_bench(o);
    if (!o.screenshot.empty()) return run_screenshot(o);
    return run_window(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap-viewer: %s\n", e.what());
    return 1;
  }
}
