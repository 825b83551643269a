// OpenGL plumbing for the viewer: the GLFW window/context (3.3 core), shader programs with
// readable compile errors, per-instance vertex attributes.
#pragma once

#include <GLFW/glfw3.h>

#include <cstddef>
#include <string>

namespace mocap::viewer {

/// Initialises GLFW once per GlfwSession lifetime; throws std::runtime_error if there is no
/// display ("no display: run under xvfb-run or set DISPLAY").
class GlfwSession {
 public:
  GlfwSession();
  ~GlfwSession();
  GlfwSession(const GlfwSession&) = delete;
  GlfwSession& operator=(const GlfwSession&) = delete;
};

/// An OpenGL 3.3 core window, made current. `visible` false for headless rendering.
GLFWwindow* create_gl_window(int width, int height, bool visible, const char* title);

/// Compiles and links a program; throws std::runtime_error with the info log on failure.
GLuint make_program(const char* vertex_src, const char* fragment_src, const char* what);

/// A per-instance float attribute (divisor 1) of `size` components at `offset` bytes into
/// records of `stride` bytes in the bound GL_ARRAY_BUFFER, enabled.
void instance_attribute(GLuint index, GLint size, GLsizei stride, std::size_t offset);

/// "Mesa/llvmpipe (LLVM 15.0.6, 256 bits)", for reports.
std::string gl_renderer_name();

}  // namespace mocap::viewer
