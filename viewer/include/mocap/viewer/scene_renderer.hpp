// Draws the 3D scene into the bound framebuffer: a floor grid, the avatars' capsules (one
// instanced draw call for any number of avatars), and soft planar shadows on the floor.
#pragma once

#include <GLFW/glfw3.h>

#include <vector>

#include "mocap/viewer/avatar_geometry.hpp"
#include "mocap/viewer/camera.hpp"

namespace mocap::viewer {

inline constexpr float kBackgroundRgb[3] = {0.115f, 0.125f, 0.15f};

class SceneRenderer {
 public:
  /// Needs a current OpenGL 3.3 context; throws std::runtime_error on shader errors.
  SceneRenderer();
  ~SceneRenderer();
  SceneRenderer(const SceneRenderer&) = delete;
  SceneRenderer& operator=(const SceneRenderer&) = delete;

  struct Options {
    bool shadows = true;
    /// Fewer triangles per capsule (for crowds).
    bool low_detail = false;
  };
  /// Clears and draws. `capsules` may hold any number of avatars.
  void draw(const OrbitCamera& camera, int width, int height,
            const std::vector<CapsuleInstance>& capsules, const Options& options);

 private:
  struct Mesh {
    GLuint vao = 0, vbo = 0, ibo = 0;
    GLsizei index_count = 0;
  };
  Mesh make_capsule_mesh(int slices, int rings);
  GLuint capsule_program_ = 0, floor_program_ = 0;
  GLuint instance_vbo_ = 0, floor_vao_ = 0;
  size_t instance_capacity_ = 0;
  Mesh high_, low_;
};

}  // namespace mocap::viewer
