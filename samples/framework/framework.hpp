#pragma once
// The thin framework every native libdeform sample shares: a GLFW window with an OpenGL 3.3 core context (4.3 when the
// driver offers it, for compute shaders), Dear ImGui and offscreen PNG screenshots for headless runs, over the drawing
// of render.hpp (camera, mesh and overlay renderers), which the browser viewer (samples/web) shares too.
// All OpenGL of the project lives here, in render.cpp and in deform::gpu (libdeform/src/gpu), which the GPU paths use.
#include <string>

#include "render.hpp"  // epoxy before any other GL header

#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
struct GLFWwindow;

namespace sample {

struct WindowOptions {
  std::string title = "libdeform";
  int width = 1280;
  int height = 800;
  bool hidden = false;  // headless runs: an invisible window, rendering into an offscreen framebuffer
};

class Window {
 public:
  ~Window();
  // Opens the window and context and initialises ImGui. Returns false (with a message on stderr) on failure,
  // for example when there is no display.
  bool open(const WindowOptions& options);
  bool should_close() const;
  // Polls events and starts an ImGui frame; binds the offscreen framebuffer when hidden.
  void begin_frame();
  // Renders ImGui and swaps buffers.
  void end_frame();
  // Writes the current frame (before end_frame) as an RGB PNG; false on failure.
  bool save_png(const std::string& path) const;

  glm::ivec2 framebuffer_size() const { return size_; }
  float aspect() const { return size_.y > 0 ? float(size_.x) / float(size_.y) : 1.0f; }
  const Input& input() const { return input_; }
  // True when the context is OpenGL 4.3 or newer (compute shaders available).
  bool has_compute() const { return gl_version_ >= 43; }
  const std::string& renderer_name() const { return renderer_; }

 private:
  GLFWwindow* window_ = nullptr;
  bool hidden_ = false;
  GLuint fbo_ = 0, color_ = 0, depth_ = 0;
  glm::ivec2 size_{0};
  glm::vec2 last_mouse_{0.0f};
  float scroll_accum_ = 0.0f;
  int key_accum_ = 0;
  bool was_left_down_ = false;
  Input input_;
  int gl_version_ = 0;
  std::string renderer_;
  static void on_scroll(GLFWwindow*, double, double);
  static void on_key(GLFWwindow*, int, int, int, int);
};

}  // namespace sample
