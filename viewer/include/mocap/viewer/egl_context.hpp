// An OpenGL 3.3 core context without any display server: EGL on Mesa's surfaceless platform
// (EGL_MESA_platform_surfaceless, llvmpipe when there is no GPU), current on the calling thread,
// for rendering into an Offscreen framebuffer (`mocap-viewer --screenshot` without X).
#pragma once

#include <EGL/egl.h>

namespace mocap::viewer {

class EglContext {
 public:
  /// Throws std::runtime_error naming the EGL step that failed.
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace mocap::viewer
