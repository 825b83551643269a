// OpenGL context on EGL's surfaceless platform (mocap/viewer/egl_context.hpp).
#include "mocap/viewer/egl_context.hpp"

#include <EGL/eglext.h>

#include <cstdio>
#include <stdexcept>
#include <string>

namespace mocap::viewer {
namespace {

[[noreturn]] void fail(const char* step) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", static_cast<unsigned>(eglGetError()));
  throw std::runtime_error(std::string("offscreen OpenGL without a display: ") + step +
                           " failed (EGL error " + code +
                           "); run under an X server instead, e.g. xvfb-run -a mocap-viewer ...");
}

}  // namespace

EglContext::EglContext() {
  const auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_display) fail("eglGetPlatformDisplayEXT");
  display_ = get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display_ == EGL_NO_DISPLAY) fail("the surfaceless EGL display (Mesa's libegl-mesa0)");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display_, &major, &minor)) fail("eglInitialize");
  if (!eglBindAPI(EGL_OPENGL_API)) fail("eglBindAPI(OpenGL)");
  const EGLint config_attrs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  // Surfaceless: no window or pbuffer surface; any OpenGL-capable config (or none, where
  // EGL_KHR_no_config_context allows it).
  if (!eglChooseConfig(display_, config_attrs, &config, 1, &configs) || configs < 1)
    config = nullptr;
  const EGLint context_attrs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  3,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  3,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_NONE};
  context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, context_attrs);
  if (context_ == EGL_NO_CONTEXT) fail("eglCreateContext (OpenGL 3.3 core)");
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
    fail("eglMakeCurrent (surfaceless)");
}

EglContext::~EglContext() {
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
  if (display_ != EGL_NO_DISPLAY) eglTerminate(display_);
}

}  // namespace mocap::viewer
