#pragma once
// The drawing every libdeform sample shares, on OpenGL 3.3 core (desktop, through epoxy) and on OpenGL ES 3.0 /
// WebGL2 (the browser viewer, samples/web, compiled with emscripten): an orbit camera, a renderer for a deforming mesh
// streamed as one interleaved buffer (position, normal, UV) and line/point overlays. The shaders are written once in
// the GLSL both read; compile() puts the version line of the context in front (gl.hpp).
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "gl.hpp"  // the GL header of the platform, before any other

#include <glm/glm.hpp>

#include "deform/runtime/mesh.hpp"

namespace sample {

// Mouse and keyboard state of the current frame, the scene's only: the native window leaves out what ImGui's panel
// takes; in the browser the panel is HTML beside the canvas.
struct Input {
  glm::vec2 mouse{0.0f};  // pixels, origin top-left
  glm::vec2 mouse_delta{0.0f};
  float scroll = 0.0f;
  bool left_down = false, left_pressed = false, left_released = false;
  bool right_down = false, middle_down = false;
  bool shift = false;
  int key_pressed = 0;  // last GLFW key pressed this frame (0 if none)
};

// Orbit camera: right drag orbits, middle drag (or shift + right) pans, wheel zooms.
struct OrbitCamera {
  glm::vec3 target{0.0f, 1.0f, 0.0f};
  float distance = 3.5f;
  float yaw = 0.5f;     // radians about +Y
  float pitch = 0.15f;  // radians above the horizon
  float fov_y = 0.8f;   // radians
  // Lens shift: the view's centre drawn this far right of the window's, in half window widths (NDC), so that a
  // panel over the left of the window leaves the target in the middle of what remains. 0: centred.
  float shift_x = 0.0f;
  // The height (world y) the eye and target stay above: handle() lowers the pitch no further than keeps the eye
  // there (a scene with a floor is never seen from under it) and pans the target no lower. -inf: no floor.
  float floor = -std::numeric_limits<float>::infinity();

  void handle(const Input& input, glm::ivec2 viewport);
  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;
};

// Draws a Mesh whose points move every frame. Topology, UVs and materials are uploaded once; each frame upload()
// streams positions and normals into the one interleaved buffer (T2F_N3F_V3F in spirit, §9.4.2 of the thesis).
class MeshRenderer {
 public:
  ~MeshRenderer();
  // `mesh` must outlive the renderer. Textures (map_Kd) are loaded with stb_image; a missing one falls back to Kd.
  // In the browser (no files) none is loaded: set_texture_rgb gives one from memory.
  void create(const deform::Mesh& mesh);
  // Replaces a material's texture with RGB pixels held in memory (row 0 = top), e.g. deform::builtin_texture().
  void set_texture_rgb(std::size_t material, int width, int height, const std::uint8_t* pixels);
  // Draws `triangles` (render vertex ids of the mesh, grouped by `submeshes`) instead of the mesh's own: a level of
  // detail's simplified mesh over the same vertex buffer. Empty: the mesh's own triangles again.
  void set_triangles(std::span<const std::uint32_t> triangles, std::span<const deform::Submesh> submeshes);
  // The triangles draw() draws.
  std::size_t triangle_count() const;
  // Per render vertex positions and normals (size = mesh.vertex_count()).
  void upload(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals);
  void draw(const glm::mat4& model, const glm::mat4& view, const glm::mat4& projection, glm::vec3 eye,
            glm::vec3 tint = glm::vec3(1.0f)) const;
  // Binds the interleaved VBO as a shader storage buffer (GPU paths write positions/normals into it directly).
  GLuint vertex_buffer() const { return vbo_; }
  static constexpr int floats_per_vertex = 8;  // u v, nx ny nz, x y z

 private:
  const deform::Mesh* mesh_ = nullptr;
  GLuint vao_ = 0, vbo_ = 0, ibo_ = 0, program_ = 0;
  std::vector<GLuint> textures_;            // per material (0 = none)
  std::vector<deform::Submesh> submeshes_;  // what draw() draws: the mesh's, or set_triangles'

  std::vector<float> interleaved_;
};

// Coloured lines and points in world space, rebuilt every frame (skeleton, lattices, targets, the floor grid).
class OverlayRenderer {
 public:
  ~OverlayRenderer();
  void create();
  void line(glm::vec3 a, glm::vec3 b, glm::vec3 colour);
  void point(glm::vec3 p, glm::vec3 colour, float size = 8.0f);
  // A triangle with a colour per corner, interpolated across it, unlit (a colour map painted on a surface: the
  // viewer's weight map shades its colours itself).
  void triangle(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 colour_a, glm::vec3 colour_b, glm::vec3 colour_c);
  // Draws and clears what was added (triangles, then lines, then points); `on_top` ignores depth (skeleton and
  // handles show through the skin).
  void flush(const glm::mat4& view_projection, bool on_top);

 private:
  GLuint vao_ = 0, vbo_ = 0, program_ = 0;
  std::vector<float> triangles_, lines_, points_;
};

// Compiles and links a program from sources; aborts with the GL log on failure (samples only).
GLuint build_program(const char* vertex_source, const char* fragment_source);

}  // namespace sample
