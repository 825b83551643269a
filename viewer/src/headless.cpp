// Headless mode: render --frames frames offscreen at a fixed 60 Hz animation clock and write the
// last one as a PNG (for tests and documentation). With an X (or Wayland) display through a
// hidden GLFW window; without one through EGL on Mesa's surfaceless platform (llvmpipe).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "mocap/viewer/control_client.hpp"
#include "mocap/viewer/egl_context.hpp"
#include "mocap/viewer/gl_util.hpp"
#include "mocap/viewer/offscreen.hpp"
#include "viewer_options.hpp"

namespace mocap::viewer {

namespace {

/// Renders --frames frames into an offscreen framebuffer of the current GL context and writes
/// the PNG; returns the exit code.
int render_screenshot(const ViewerOptions& o, PoseSource* source) {
  int rc = 0;
  {
    Offscreen target(o.width, o.height);
    View view(source->dimensions() ? *source->dimensions()
                                   : body_dimensions_from_height(o.height_m));
    view.settings = o.settings;
    view.camera = OrbitCamera::framing(o.avatars);
    const auto start = std::chrono::steady_clock::now();
    auto wall_s = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    // Live sources (daemon, network) run on the wall clock and get a few seconds to deliver a
    // first pose; the synthetic and file sources step a fixed 60 Hz clock (reproducible images).
    const bool live = o.source == "shm" || o.source == "connect";
    if (live) {
      while (!source->poll(wall_s(), view.frames) && wall_s() < o.wait_s)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    // A live daemon's calibration prompt, as the window shows it.
    if (live)
      view.hud.calibration_prompt = fetch_calibration_prompt(
          o.control_socket.empty() ? default_control_socket_path() : o.control_socket);
    bool any_pose = !view.frames.empty();
    for (int i = 0; i < o.frames; ++i) {
      source->poll(live ? wall_s() : static_cast<double>(i) / 60.0, view.frames);
      any_pose = any_pose || !view.frames.empty();
      view.hud.fps = wall_s() > 0 ? i / wall_s() : 0;
      view.hud.source = source->status();
      target.bind();
      view.render(o.width, o.height);
    }
    write_png(o.screenshot, target.read());
    if (!any_pose) {
      std::fprintf(stderr, "mocap-viewer: no pose received from %s; the image shows no avatar\n",
                   source->status().c_str());
      rc = 3;
    }
  }
  return rc;
}

/// No X or Wayland display to open a window on.
bool no_display() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (!x || !*x) && (!w || !*w);
}

}  // namespace

int run_screenshot(const ViewerOptions& o) {
  auto source = make_source(o);
  if (no_display()) {  // EGL on Mesa's surfaceless platform: no display server needed
    EglContext egl;
    return render_screenshot(o, source.get());
  }
  GlfwSession glfw;
  GLFWwindow* window = create_gl_window(64, 64, false, "mocap-viewer (headless)");
  const int rc = render_screenshot(o, source.get());
  glfwDestroyWindow(window);
  return rc;
}

}  // namespace mocap::viewer
