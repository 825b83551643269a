// Interactive mode: the window, mouse orbit/pan/zoom, keys, and the render loop.
#include <chrono>
#include <cstdio>

#include "mocap/viewer/control_client.hpp"
#include "mocap/viewer/control_worker.hpp"
#include "mocap/viewer/gl_util.hpp"
#include "viewer_options.hpp"

namespace mocap::viewer {
namespace {

struct App {
  const ViewerOptions* options = nullptr;
  View* view = nullptr;
  PoseSource* source = nullptr;
  ControlWorker* control_worker = nullptr;
  bool paused = false;
  bool dragging = false, panning = false;
  double last_x = 0, last_y = 0;

  /// Sent off the render thread; the outcome replaces "...: SENT" when the daemon answers.
  void control(const std::string& request, const char* what) {
    view->hud.message = std::string(what) + ": SENT";
    control_worker->request(request, what);
  }
};

App& app_of(GLFWwindow* w) {
  return *static_cast<App*>(glfwGetWindowUserPointer(w));
}

void on_key(GLFWwindow* w, int key, int /*scancode*/, int action, int mods) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  App& a = app_of(w);
  ViewSettings& s = a.view->settings;
  const double seek_s = (mods & GLFW_MOD_SHIFT) ? 10.0 : 1.0;
  switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q:
      glfwSetWindowShouldClose(w, GLFW_TRUE);
      break;
    case GLFW_KEY_R:
      a.view->camera = OrbitCamera::framing(a.options->avatars);
      break;
    case GLFW_KEY_F:
      s.follow = !s.follow;
      break;
    case GLFW_KEY_S:
      s.style.stick = !s.style.stick;
      break;
    case GLFW_KEY_A:
      s.style.sensor_axes = !s.style.sensor_axes;
      break;
    case GLFW_KEY_E:
      s.earth_axes = !s.earth_axes;
      break;
    case GLFW_KEY_L:
      s.labels = !s.labels;
      break;
    case GLFW_KEY_F1:
      s.hud = !s.hud;
      break;
    case GLFW_KEY_SPACE:
      a.paused = !a.paused;
      a.source->set_paused(a.paused);
      a.view->hud.paused = a.paused;
      break;
    case GLFW_KEY_LEFT:
      a.source->seek_by(-seek_s);
      break;
    case GLFW_KEY_RIGHT:
      a.source->seek_by(seek_s);
      break;
    case GLFW_KEY_N:
      a.view->hud.calibration_pose = "N-POSE";
      a.control(calibrate_request("npose"), "N-POSE CALIBRATION");
      break;
    case GLFW_KEY_T:
      a.view->hud.calibration_pose = "T-POSE";
      a.control(calibrate_request("tpose"), "T-POSE CALIBRATION");
      break;
    case GLFW_KEY_M:
      a.view->hud.calibration_pose = "N-POSE, THEN BOW AND BEND THE KNEES TWICE";
      a.control(calibrate_request("mounting"), "MOUNTING CALIBRATION");
      break;
    case GLFW_KEY_H:
      a.control(heading_reset_request(), "HEADING RESET");
      break;
    default:
      break;
  }
}

void on_button(GLFWwindow* w, int button, int action, int /*mods*/) {
  App& a = app_of(w);
  glfwGetCursorPos(w, &a.last_x, &a.last_y);
  if (button == GLFW_MOUSE_BUTTON_LEFT) a.dragging = action == GLFW_PRESS;
  if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE)
    a.panning = action == GLFW_PRESS;
}

void on_cursor(GLFWwindow* w, double x, double y) {
  App& a = app_of(w);
  const auto dx = static_cast<float>(x - a.last_x), dy = static_cast<float>(y - a.last_y);
  a.last_x = x;
  a.last_y = y;
  int fw = 0, fh = 0;
  glfwGetWindowSize(w, &fw, &fh);
  if (a.dragging) a.view->camera.orbit(dx, dy);
  if (a.panning) {
    a.view->settings.follow = false;
    a.view->camera.pan(dx, dy, fh);
  }
}

void on_scroll(GLFWwindow* w, double /*dx*/, double dy) {
  app_of(w).view->camera.zoom(static_cast<float>(dy));
}

}  // namespace

int run_window(const ViewerOptions& o) {
  auto source = make_source(o);
  GlfwSession glfw;
  GLFWwindow* window = create_gl_window(o.width, o.height, true, "mocap-viewer");
  glfwSwapInterval(o.vsync ? 1 : 0);
  {
    View view(source->dimensions() ? *source->dimensions()
                                   : body_dimensions_from_height(o.height_m));
    view.settings = o.settings;
    view.camera = OrbitCamera::framing(o.avatars);
    // A live daemon: what its calibration still needs (the moves, or a refusal's reason), asked
    // once a second by the worker.
    ControlWorker control(
        o.control_socket.empty() ? default_control_socket_path() : o.control_socket,
        !source->seekable());
    App app;
    app.options = &o;
    app.view = &view;
    app.source = source.get();
    app.control_worker = &control;
    glfwSetWindowUserPointer(window, &app);
    glfwSetKeyCallback(window, on_key);
    glfwSetMouseButtonCallback(window, on_button);
    glfwSetCursorPosCallback(window, on_cursor);
    glfwSetScrollCallback(window, on_scroll);

    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    auto fps_window_start = start;
    int fps_frames = 0;
    while (!glfwWindowShouldClose(window)) {
      glfwPollEvents();
      const auto now = clock::now();
      view.hud.calibration_prompt = control.prompt();
      if (auto m = control.take_message()) view.hud.message = std::move(*m);
      source->poll(std::chrono::duration<double>(now - start).count(), view.frames);
      view.hud.source = source->status();
      if (++fps_frames, now - fps_window_start > std::chrono::milliseconds(500)) {
        view.hud.fps = fps_frames / std::chrono::duration<double>(now - fps_window_start).count();
        fps_frames = 0;
        fps_window_start = now;
      }
      int fw = 0, fh = 0;
      glfwGetFramebufferSize(window, &fw, &fh);
      if (fw > 0 && fh > 0) view.render(fw, fh);
      glfwSwapBuffers(window);
    }
  }
  glfwDestroyWindow(window);
  return 0;
}

}  // namespace mocap::viewer
