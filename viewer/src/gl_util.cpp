// GLFW initialisation, window creation, shader compilation and instance attributes.
#include "mocap/viewer/gl_util.hpp"

#include <cstdio>
#include <stdexcept>
#include <string>

namespace mocap::viewer {
namespace {

void print_glfw_error(int code, const char* description) {
  std::fprintf(stderr, "mocap-viewer: GLFW error %d: %s\n", code, description);
}

/// Throws "<what>: <info log>" if the shader's or program's `status` is false, deleting it
/// first (get_iv, get_log, destroy: glGetShaderiv, glGetShaderInfoLog, glDeleteShader or the
/// program ones).
template <class GetIv, class GetLog, class Destroy>
void throw_unless(GLuint object, GLenum status, GetIv get_iv, GetLog get_log, Destroy destroy,
                  const std::string& what) {
  GLint ok = 0;
  get_iv(object, status, &ok);
  if (ok) return;
  char log[2048] = {};
  get_log(object, sizeof log, nullptr, log);
  destroy(object);
  throw std::runtime_error(what + ": " + log);
}

GLuint compile(GLenum type, const char* src, const char* what) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  throw_unless(
      s, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, glDeleteShader,
      std::string(what) + (type == GL_VERTEX_SHADER ? " vertex" : " fragment") + " shader");
  return s;
}

}  // namespace

GlfwSession::GlfwSession() {
  glfwSetErrorCallback(print_glfw_error);
  if (!glfwInit())
    throw std::runtime_error(
        "cannot initialise GLFW (no display? run under xvfb-run or set DISPLAY)");
}

GlfwSession::~GlfwSession() {
  glfwTerminate();
}

GLFWwindow* create_gl_window(int width, int height, bool visible, const char* title) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  glfwWindowHint(GLFW_STENCIL_BITS, 8);
  GLFWwindow* w = glfwCreateWindow(width, height, title, nullptr, nullptr);
  if (!w) throw std::runtime_error("cannot create an OpenGL 3.3 core window");
  glfwMakeContextCurrent(w);
  return w;
}

GLuint make_program(const char* vertex_src, const char* fragment_src, const char* what) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex_src, what);
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment_src, what);
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  throw_unless(p, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, glDeleteProgram,
               std::string(what) + " program link");
  return p;
}

void instance_attribute(GLuint index, GLint size, GLsizei stride, std::size_t offset) {
  glVertexAttribPointer(index, size, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offset));
  glEnableVertexAttribArray(index);
  glVertexAttribDivisor(index, 1);
}

std::string gl_renderer_name() {
  const auto* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return r ? r : "unknown";
}

}  // namespace mocap::viewer
