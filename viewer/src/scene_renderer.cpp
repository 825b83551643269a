// Scene rendering: capsule impostor-free instancing (a unit capsule mesh whose two hemispheres
// are moved to each instance's end points in the vertex shader), procedural floor grid, shadows.
#include "mocap/viewer/scene_renderer.hpp"

#include <Eigen/Core>
#include <cmath>
#include <cstddef>

#include "mocap/viewer/gl_util.hpp"

namespace mocap::viewer {
namespace {

const char* kCapsuleVs = R"(#version 330 core
layout(location = 0) in vec3 dir;        // unit-sphere direction, z along the capsule axis
layout(location = 1) in float end_b;     // 0: hemisphere at a, 1: at b
layout(location = 2) in vec4 a_radius;   // per instance
layout(location = 3) in vec4 b_pad;
layout(location = 4) in vec4 color;
uniform mat4 view_proj;
uniform vec3 light_dir;   // towards the light
uniform int shadow;       // 1: flatten onto the floor along light_dir
out vec3 v_normal;
out vec3 v_pos;
out vec4 v_color;
void main() {
  vec3 a = a_radius.xyz, b = b_pad.xyz;
  vec3 axis = b - a;
  float len = length(axis);
  vec3 z = len > 1e-6 ? axis / len : vec3(0.0, 0.0, 1.0);
  vec3 x = normalize(abs(z.z) < 0.9 ? cross(z, vec3(0.0, 0.0, 1.0)) : cross(z, vec3(1.0, 0.0, 0.0)));
  vec3 y = cross(z, x);
  vec3 n = x * dir.x + y * dir.y + z * dir.z;
  vec3 p = mix(a, b, end_b) + a_radius.w * n;
  if (shadow == 1) {
    p = p - light_dir * (p.z / light_dir.z);
    p.z = 0.002;
  }
  v_normal = n;
  v_pos = p;
  v_color = color;
  gl_Position = view_proj * vec4(p, 1.0);
}
)";

const char* kCapsuleFs = R"(#version 330 core
in vec3 v_normal;
in vec3 v_pos;
in vec4 v_color;
uniform vec3 light_dir;
uniform vec3 eye;
uniform vec3 background;
uniform int shadow;
out vec4 frag;
void main() {
  if (shadow == 1) { frag = vec4(0.0, 0.0, 0.0, 0.35); return; }
  vec3 n = normalize(v_normal);
  vec3 v = normalize(eye - v_pos);
  float hemi = 0.5 + 0.5 * n.z;
  vec3 ambient = mix(vec3(0.20, 0.19, 0.18), vec3(0.48, 0.52, 0.58), hemi);
  float diffuse = max(dot(n, light_dir), 0.0);
  vec3 h = normalize(light_dir + v);
  float spec = 0.18 * pow(max(dot(n, h), 0.0), 24.0);
  float rim = 0.12 * pow(1.0 - max(dot(n, v), 0.0), 3.0);
  float occlusion = mix(0.7, 1.0, clamp(v_pos.z / 0.4, 0.0, 1.0));
  vec3 c = v_color.rgb * (ambient + 0.72 * diffuse) * occlusion + vec3(spec + rim);
  float fog = clamp((length(eye - v_pos) - 25.0) / 40.0, 0.0, 1.0);
  frag = vec4(mix(c, background, fog), 1.0);
}
)";

const char* kFloorVs = R"(#version 330 core
uniform mat4 view_proj;
uniform vec2 centre;
out vec2 v_xy;
void main() {
  const vec2 corners[4] = vec2[4](vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0), vec2(1.0, 1.0));
  v_xy = centre + 60.0 * corners[gl_VertexID];
  gl_Position = view_proj * vec4(v_xy, 0.0, 1.0);
}
)";

const char* kFloorFs = R"(#version 330 core
in vec2 v_xy;
uniform vec3 eye;
uniform vec3 background;
out vec4 frag;
float grid(vec2 p, float spacing) {
  vec2 q = p / spacing;
  vec2 d = abs(fract(q - 0.5) - 0.5) / fwidth(q);
  return 1.0 - min(min(d.x, d.y), 1.0);
}
void main() {
  vec3 c = vec3(0.25, 0.255, 0.26);
  c = mix(c, vec3(0.31), 0.6 * grid(v_xy, 0.25));
  c = mix(c, vec3(0.40), grid(v_xy, 1.0));
  float dist = length(vec3(v_xy, 0.0) - eye);
  float fog = clamp((dist - 8.0) / 40.0, 0.0, 1.0);
  frag = vec4(mix(c, background, fog), 1.0);
}
)";

Eigen::Vector3f light_direction() {
  return Eigen::Vector3f(0.45f, 0.35f, 0.82f).normalized();
}

}  // namespace

SceneRenderer::SceneRenderer() {
  capsule_program_ = make_program(kCapsuleVs, kCapsuleFs, "capsule");
  floor_program_ = make_program(kFloorVs, kFloorFs, "floor");
  glGenBuffers(1, &instance_vbo_);
  high_ = make_capsule_mesh(20, 7);
  low_ = make_capsule_mesh(6, 2);
  glGenVertexArrays(1, &floor_vao_);
}

SceneRenderer::~SceneRenderer() {
  for (Mesh* m : {&high_, &low_}) {
    glDeleteVertexArrays(1, &m->vao);
    glDeleteBuffers(1, &m->vbo);
    glDeleteBuffers(1, &m->ibo);
  }
  glDeleteVertexArrays(1, &floor_vao_);
  glDeleteBuffers(1, &instance_vbo_);
  glDeleteProgram(capsule_program_);
  glDeleteProgram(floor_program_);
}

SceneRenderer::Mesh SceneRenderer::make_capsule_mesh(int slices, int rings) {
  // Rows of latitude from the bottom pole to the equator (hemisphere a), then from the
  // equator to the top pole (hemisphere b); the two equator rows form the cylinder.
  std::vector<float> vertices;  // dir.xyz, end_b
  const float pi = 3.14159265f;
  const int rows = 2 * (rings + 1);
  for (int r = 0; r < rows; ++r) {
    const bool top = r > rings;
    const int k = top ? r - (rings + 1) : r;
    const float lat =
        top ? 0.5f * pi * static_cast<float>(k) / static_cast<float>(rings)
            : -0.5f * pi + 0.5f * pi * static_cast<float>(k) / static_cast<float>(rings);
    for (int j = 0; j < slices; ++j) {
      const float lon = 2 * pi * static_cast<float>(j) / static_cast<float>(slices);
      vertices.insert(vertices.end(), {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                                       std::sin(lat), top ? 1.0f : 0.0f});
    }
  }
  std::vector<unsigned> indices;
  for (int r = 0; r + 1 < rows; ++r) {
    for (int j = 0; j < slices; ++j) {
      const auto v = [&](int row, int col) {
        return static_cast<unsigned>(row * slices + (col % slices));
      };
      indices.insert(indices.end(), {v(r, j), v(r, j + 1), v(r + 1, j + 1), v(r, j),
                                     v(r + 1, j + 1), v(r + 1, j)});
    }
  }
  Mesh m;
  m.index_count = static_cast<GLsizei>(indices.size());
  glGenVertexArrays(1, &m.vao);
  glBindVertexArray(m.vao);
  glGenBuffers(1, &m.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
               vertices.data(), GL_STATIC_DRAW);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 4 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, 4 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(1);
  glGenBuffers(1, &m.ibo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ibo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(unsigned)),
               indices.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, instance_vbo_);
  const GLsizei stride = sizeof(CapsuleInstance);
  instance_attribute(2, 4, stride, offsetof(CapsuleInstance, a_m));
  instance_attribute(3, 4, stride, offsetof(CapsuleInstance, b_m));
  instance_attribute(4, 4, stride, offsetof(CapsuleInstance, rgba));
  glBindVertexArray(0);
  return m;
}

void SceneRenderer::draw(const OrbitCamera& camera, int width, int height,
                         const std::vector<CapsuleInstance>& capsules, const Options& options) {
  glViewport(0, 0, width, height);
  glClearColor(kBackgroundRgb[0], kBackgroundRgb[1], kBackgroundRgb[2], 1);
  glClearStencil(0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
  const Eigen::Matrix4f view_proj =
      camera.projection(static_cast<float>(width) / static_cast<float>(std::max(1, height))) *
      camera.view();
  const Eigen::Vector3f eye = camera.eye_m(), light = light_direction();

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);

  // Floor, centred under the camera target so the grid never ends in view.
  glUseProgram(floor_program_);
  glUniformMatrix4fv(glGetUniformLocation(floor_program_, "view_proj"), 1, GL_FALSE,
                     view_proj.data());
  glUniform2f(glGetUniformLocation(floor_program_, "centre"), std::round(camera.target_m.x()),
              std::round(camera.target_m.y()));
  glUniform3fv(glGetUniformLocation(floor_program_, "eye"), 1, eye.data());
  glUniform3fv(glGetUniformLocation(floor_program_, "background"), 1, kBackgroundRgb);
  glBindVertexArray(floor_vao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);

  if (capsules.empty()) return;
  glBindBuffer(GL_ARRAY_BUFFER, instance_vbo_);
  const size_t bytes = capsules.size() * sizeof(CapsuleInstance);
  if (capsules.size() > instance_capacity_) instance_capacity_ = capsules.size() * 2;
  // Orphan the previous contents so the upload never waits for the last frame's draw.
  glBufferData(GL_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(instance_capacity_ * sizeof(CapsuleInstance)), nullptr,
               GL_STREAM_DRAW);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(bytes), capsules.data());

  const Mesh& mesh = options.low_detail ? low_ : high_;
  glUseProgram(capsule_program_);
  glUniformMatrix4fv(glGetUniformLocation(capsule_program_, "view_proj"), 1, GL_FALSE,
                     view_proj.data());
  glUniform3fv(glGetUniformLocation(capsule_program_, "light_dir"), 1, light.data());
  glUniform3fv(glGetUniformLocation(capsule_program_, "eye"), 1, eye.data());
  glUniform3fv(glGetUniformLocation(capsule_program_, "background"), 1, kBackgroundRgb);
  const GLint shadow = glGetUniformLocation(capsule_program_, "shadow");
  glBindVertexArray(mesh.vao);
  const auto count = static_cast<GLsizei>(capsules.size());

  if (options.shadows) {
    // Each floor pixel is darkened once however many capsules cover it (stencil).
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_EQUAL, 0, 0xff);
    glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
    glDepthMask(GL_FALSE);
    glUniform1i(shadow, 1);
    glDrawElementsInstanced(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr, count);
    glDepthMask(GL_TRUE);
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_BLEND);
  }
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CCW);
  glUniform1i(shadow, 0);
  glDrawElementsInstanced(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr, count);
  glDisable(GL_CULL_FACE);
  glBindVertexArray(0);
}

}  // namespace mocap::viewer
