// An offscreen framebuffer (RGBA8 + depth/stencil) for screenshots and benchmarks, read back as
// an RgbImage.
#pragma once

#include <GLFW/glfw3.h>

#include "mocap/viewer/png_io.hpp"

namespace mocap::viewer {

class Offscreen {
 public:
  Offscreen(int width, int height);  ///< needs a current GL context; throws if incomplete
  ~Offscreen();
  Offscreen(const Offscreen&) = delete;
  Offscreen& operator=(const Offscreen&) = delete;

  void bind() const;
  /// Waits for rendering and copies the pixels, top row first.
  RgbImage read() const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int width_, height_;
  GLuint fbo_ = 0, color_ = 0, depth_ = 0;
};

}  // namespace mocap::viewer
