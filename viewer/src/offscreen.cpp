// Offscreen framebuffer object and pixel read-back.
#include "mocap/viewer/offscreen.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace mocap::viewer {

Offscreen::Offscreen(int width, int height) : width_(width), height_(height) {
  glGenFramebuffers(1, &fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glGenRenderbuffers(1, &color_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
  glGenRenderbuffers(1, &depth_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, width, height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, depth_);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("offscreen framebuffer " + std::to_string(width) + "x" +
                             std::to_string(height) + " incomplete (status " +
                             std::to_string(status) + ")");
}

Offscreen::~Offscreen() {
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteRenderbuffers(1, &depth_);
  glDeleteRenderbuffers(1, &color_);
  glDeleteFramebuffers(1, &fbo_);
}

void Offscreen::bind() const {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
}

RgbImage Offscreen::read() const {
  RgbImage img;
  img.width = width_;
  img.height = height_;
  const size_t row = static_cast<size_t>(width_) * 3;
  std::vector<uint8_t> gl_rows(row * static_cast<size_t>(height_));
  bind();
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGB, GL_UNSIGNED_BYTE, gl_rows.data());
  img.rgb.resize(gl_rows.size());
  for (int y = 0; y < height_; ++y)  // OpenGL's first row is the bottom one
    std::copy_n(&gl_rows[row * static_cast<size_t>(height_ - 1 - y)], row,
                &img.rgb[row * static_cast<size_t>(y)]);
  return img;
}

}  // namespace mocap::viewer
