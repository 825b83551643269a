// mocap-viewer --bench: frame rates at the window size with one avatar and with a crowd of 150
// (synthetic poses, instanced), rendered to the window with vsync off; and the cost of the
// daemon's posture publish with and without a viewer reading at full speed (wait-free writer).
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>

#include "mocap/outputs/posture_shm.hpp"
#include "mocap/viewer/gl_util.hpp"
#include "mocap/viewer/offscreen.hpp"
#include "mocap/viewer/synthetic_source.hpp"
#include "viewer_options.hpp"

namespace mocap::viewer {
namespace {

using clock_type = std::chrono::steady_clock;

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);  // all threads, llvmpipe's rasteriser threads included
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct FpsResult {
  double fps = 0;
  double frames_per_cpu_s = 0;  ///< frames per CPU-second of this process: load-independent
  int frames = 0;
  size_t capsules = 0;
};

/// Frames per second rendering `avatars` synthetic avatars with the HUD, either to the window
/// (swap buffers, vsync off: what a user sees) or to an offscreen framebuffer (glFinish per
/// frame: rendering alone, without presenting through the X server).
FpsResult measure_fps(GLFWwindow* window, const ViewerOptions& o, int avatars, bool offscreen) {
  View view(body_dimensions_from_height(o.height_m));
  view.settings = o.settings;
  view.camera = OrbitCamera::framing(avatars);
  SyntheticSource source(avatars, view.dims());
  Offscreen target(o.width, o.height);
  auto frame = [&](int i) {
    source.poll(i / 60.0, view.frames);
    view.hud.source = source.status();
    if (offscreen) {
      target.bind();
      view.render(o.width, o.height);
      glFinish();
    } else {
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      view.render(o.width, o.height);
      glfwSwapBuffers(window);
    }
  };
  for (int i = 0; i < 10; ++i)
    frame(i);  // warm up (shader compilation, buffers)
  glFinish();
  FpsResult r;
  const double cpu0 = process_cpu_s();
  const auto start = clock_type::now();
  double elapsed = 0;
  while (elapsed < o.bench_seconds) {
    frame(++r.frames);
    elapsed = std::chrono::duration<double>(clock_type::now() - start).count();
  }
  glFinish();
  elapsed = std::chrono::duration<double>(clock_type::now() - start).count();
  r.fps = r.frames / elapsed;
  r.frames_per_cpu_s = r.frames / std::max(1e-9, process_cpu_s() - cpu0);
  r.capsules = view.capsule_count();
  return r;
}

/// Mean time of PostureWriter::publish over `n` frames, ns, optionally with a reader thread
/// copying frames as fast as it can (what a viewer does, only harder).
/// `reader_period_us` 0: the reader copies frames back to back; > 0: it sleeps that long between
/// copies (a viewer at 1000 frames/s).
double publish_ns(const std::string& name, int n, bool with_reader, long& reads,
                  int reader_period_us = 0) {
  outputs::PostureWriter writer(name);
  outputs::PostureReader reader(name);
  std::atomic<bool> stop{false};
  std::atomic<long> read_count{0};
  std::thread t;
  if (with_reader) {
    t = std::thread([&] {
      PoseFrame f;
      while (!stop.load(std::memory_order_relaxed)) {
        if (reader.read(f)) read_count.fetch_add(1, std::memory_order_relaxed);
        if (reader_period_us > 0)
          std::this_thread::sleep_for(std::chrono::microseconds(reader_period_us));
      }
    });
  }
  PoseFrame first;
  reset_pose(first);
  writer.publish(first);
  // Time the writer only once the reader is really copying frames.
  while (with_reader && read_count.load() < 1000)
    std::this_thread::yield();
  PoseFrame f;
  reset_pose(f);
  const auto start = clock_type::now();
  for (int i = 0; i < n; ++i) {
    f.frame = static_cast<uint64_t>(i);
    writer.publish(f);
  }
  const double ns = std::chrono::duration<double, std::nano>(clock_type::now() - start).count();
  stop = true;
  if (t.joinable()) t.join();
  reads = read_count;
  return ns / n;
}

}  // namespace

int run_bench(const ViewerOptions& o) {
  GlfwSession glfw;
  GLFWwindow* window = create_gl_window(o.width, o.height, true, "mocap-viewer bench");
  glfwSwapInterval(0);
  const std::string renderer = gl_renderer_name();
  const int crowd_n = o.avatars > 1 ? o.avatars : 150;
  const FpsResult one = measure_fps(window, o, 1, false);
  const FpsResult crowd = measure_fps(window, o, crowd_n, false);
  const FpsResult one_off = measure_fps(window, o, 1, true);
  const FpsResult crowd_off = measure_fps(window, o, crowd_n, true);
  glfwDestroyWindow(window);

  const std::string shm = "/mocap-viewer-bench-" + std::to_string(getpid());
  long reads_alone = 0, reads = 0;
  const int n = 200000;
  const double alone_ns = publish_ns(shm, n, false, reads_alone);
  const double shared_ns = publish_ns(shm, n, true, reads);
  long viewer_reads = 0;
  const double viewer_ns = publish_ns(shm, n, true, viewer_reads, 1000);
  std::printf(
      "{\"renderer\": \"%s\", \"width\": %d, \"height\": %d, \"vsync\": false,\n"
      " \"one_avatar\": {\"fps\": %.1f, \"offscreen_fps\": %.1f, \"offscreen_frames_per_cpu_s\": "
      "%.1f, \"capsules\": %zu, "
      "\"goal_fps\": 120},\n"
      " \"crowd\": {\"avatars\": %d, \"fps\": %.1f, \"offscreen_fps\": %.1f, "
      "\"offscreen_frames_per_cpu_s\": %.1f, \"capsules\": %zu, "
      "\"goal_fps\": 30},\n"
      " \"posture_publish\": {\"frames\": %d, \"ns_alone\": %.1f, \"ns_with_reader\": %.1f, "
      "\"ratio\": %.2f, \"reader_frames\": %ld,\n"
      "  \"ns_with_1khz_reader\": %.1f, \"ratio_1khz\": %.2f}}\n",
      renderer.c_str(), o.width, o.height, one.fps, one_off.fps, one_off.frames_per_cpu_s,
      one.capsules, crowd_n, crowd.fps, crowd_off.fps, crowd_off.frames_per_cpu_s, crowd.capsules,
      n, alone_ns, shared_ns, shared_ns / alone_ns, reads, viewer_ns, viewer_ns / alone_ns);
  return 0;
}

}  // namespace mocap::viewer
