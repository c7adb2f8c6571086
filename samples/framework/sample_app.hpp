#pragma once
// The loop every small sample shares: a window (or, with --screenshot OUT.png [--frames N], a hidden one whose last
// frame is written as PNG), an orbit camera framed on the built-in character, and a per-frame callback.
#include <functional>
#include <span>
#include <vector>

#include "framework.hpp"

namespace sample {

struct Frame {
  float time = 0.0f;  // seconds since start (fixed 60 Hz steps when headless)
  float dt = 0.0f;
  glm::mat4 view{1.0f}, projection{1.0f};
  glm::vec3 eye{0.0f};
  OverlayRenderer* overlay = nullptr;  // add lines/points; flushed on top after the callback
};

// Runs `frame` until the window closes (or N frames headless). `setup` runs once after the GL context exists;
// `teardown`, when given, once after the last frame while the context is still current (to release GL objects that
// outlive run_sample, such as a deform::GpuBezierLattice).
int run_sample(int argc, char** argv, const char* title, const std::function<void()>& setup,
               const std::function<void(const Frame&)>& frame, const std::function<void()>& teardown = {});

// Draws a deforming deform::Mesh given per-point positions: gathers them to render vertices and recomputes normals.
class PointMeshRenderer {
 public:
  void create(const deform::Mesh& mesh);
  void draw(std::span<const glm::vec3> points, const Frame& frame, glm::mat4 model = glm::mat4(1.0f),
            glm::vec3 tint = glm::vec3(1.0f));

 private:
  const deform::Mesh* mesh_ = nullptr;
  MeshRenderer renderer_;
  std::vector<glm::vec3> positions_, normals_;
  std::vector<glm::vec4> normals_scratch_;
  deform::VertexNormalsBinding vertex_normals_;
};

}  // namespace sample
