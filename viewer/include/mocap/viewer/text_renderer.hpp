// Screen-space text and panels with the built-in bitmap font: glyphs are collected per frame
// into a preallocated buffer and drawn in one instanced call.
#pragma once

#include <GLFW/glfw3.h>

#include <array>
#include <string_view>
#include <vector>

namespace mocap::viewer {

using Rgba = std::array<float, 4>;

class TextRenderer {
 public:
  TextRenderer();  ///< needs a current GL context
  ~TextRenderer();
  TextRenderer(const TextRenderer&) = delete;
  TextRenderer& operator=(const TextRenderer&) = delete;

  /// Starts a frame of the given framebuffer size (pixels, origin top-left).
  void begin(int width, int height);
  /// Text whose top-left corner is at (x, y); `scale` integer pixels per font pixel.
  void text(float x, float y, int scale, std::string_view s, const Rgba& rgba);
  /// A filled rectangle (panels, indicators).
  void rect(float x, float y, float w, float h, const Rgba& rgba);
  /// Draws everything collected since begin() over the current framebuffer.
  void flush();

  static float text_width(std::string_view s, int scale);
  static float line_height(int scale);

 private:
  struct Glyph {
    float x, y, w, h;
    float cell;
    float pad[3];
    Rgba rgba;
  };
  std::vector<Glyph> glyphs_;
  int width_ = 1, height_ = 1;
  GLuint program_ = 0, vao_ = 0, vbo_ = 0, texture_ = 0;
};

}  // namespace mocap::viewer
