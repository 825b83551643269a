// Bitmap-font text rendering: one atlas texture, one instanced quad per glyph.
#include "mocap/viewer/text_renderer.hpp"

#include "mocap/viewer/hud_layout.hpp"

#include <cstddef>

#include "mocap/viewer/bitmap_font.hpp"
#include "mocap/viewer/gl_util.hpp"

namespace mocap::viewer {
namespace {

const char* kVs = R"(#version 330 core
layout(location = 0) in vec4 rect;   // x, y, w, h in pixels, origin top-left
layout(location = 1) in float cell;  // atlas cell
layout(location = 2) in vec4 color;
uniform vec2 viewport;
uniform vec2 atlas_cells;  // cell count, 1
out vec2 v_uv;
out vec4 v_color;
void main() {
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  vec2 px = rect.xy + corner * rect.zw;
  v_uv = vec2((cell + corner.x) / atlas_cells.x, corner.y);
  v_color = color;
  gl_Position = vec4(px.x / viewport.x * 2.0 - 1.0, 1.0 - px.y / viewport.y * 2.0, 0.0, 1.0);
}
)";

const char* kFs = R"(#version 330 core
in vec2 v_uv;
in vec4 v_color;
uniform sampler2D atlas;
out vec4 frag;
void main() {
  float ink = texture(atlas, v_uv).r;
  if (ink < 0.5) discard;
  frag = v_color;
}
)";

constexpr size_t kMaxGlyphs = 16384;

}  // namespace

TextRenderer::TextRenderer() {
  program_ = make_program(kVs, kFs, "text");
  glyphs_.reserve(kMaxGlyphs);
  const FontAtlas atlas = make_font_atlas();
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R8, atlas.width, atlas.height, 0, GL_RED, GL_UNSIGNED_BYTE,
               atlas.coverage.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(kMaxGlyphs * sizeof(Glyph)), nullptr,
               GL_STREAM_DRAW);
  const GLsizei stride = sizeof(Glyph);
  instance_attribute(0, 4, stride, offsetof(Glyph, x));
  instance_attribute(1, 1, stride, offsetof(Glyph, cell));
  instance_attribute(2, 4, stride, offsetof(Glyph, rgba));
  glBindVertexArray(0);
}

TextRenderer::~TextRenderer() {
  glDeleteTextures(1, &texture_);
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void TextRenderer::begin(int width, int height) {
  width_ = width;
  height_ = height;
  glyphs_.clear();
}

void TextRenderer::text(float x, float y, int scale, std::string_view s, const Rgba& rgba) {
  const float sc = static_cast<float>(scale);
  float cx = x;
  for (char c : s) {
    if (c == '\n') {
      cx = x;
      y += line_height(scale);
      continue;
    }
    if (c != ' ' && glyphs_.size() < kMaxGlyphs)
      glyphs_.push_back(
          {cx, y, kCellW * sc, kCellH * sc, static_cast<float>(glyph_index(c)), {}, rgba});
    cx += kCellW * sc;
  }
}

void TextRenderer::rect(float x, float y, float w, float h, const Rgba& rgba) {
  if (glyphs_.size() < kMaxGlyphs)
    glyphs_.push_back({x, y, w, h, static_cast<float>(glyph_index(kSolidBlock)), {}, rgba});
}

float TextRenderer::text_width(std::string_view s, int scale) {
  return hud_text_width(s, scale);
}

float TextRenderer::line_height(int scale) {
  return static_cast<float>(kCellH * scale);
}

void TextRenderer::flush() {
  if (glyphs_.empty()) return;
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glViewport(0, 0, width_, height_);
  glUseProgram(program_);
  glUniform2f(glGetUniformLocation(program_, "viewport"), static_cast<float>(width_),
              static_cast<float>(height_));
  glUniform2f(glGetUniformLocation(program_, "atlas_cells"), static_cast<float>(kGlyphCount), 1);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glUniform1i(glGetUniformLocation(program_, "atlas"), 0);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(kMaxGlyphs * sizeof(Glyph)), nullptr,
               GL_STREAM_DRAW);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(glyphs_.size() * sizeof(Glyph)),
                  glyphs_.data());
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(glyphs_.size()));
  glBindVertexArray(0);
  glDisable(GL_BLEND);
  glyphs_.clear();
}

}  // namespace mocap::viewer
