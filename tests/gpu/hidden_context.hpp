#pragma once
// The OpenGL context the deform::gpu checks run in: a hidden GLFW window (deform::gpu makes no contexts; the caller
// does). Asks for 4.3 core (compute shaders), else 3.3 so that the check can say it skipped. Under xvfb-run, Mesa's
// llvmpipe gives 4.5. GPU objects must be destroyed before this.
#include <epoxy/gl.h>  // first: epoxy must precede every other GL header

#include <cstdio>
#include <string>
#include <utility>

#include <GLFW/glfw3.h>

#include "deform/gpu/lattice.hpp"

namespace gpu_test {

class HiddenContext {
 public:
  HiddenContext() {
    if (!glfwInit()) return;
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    for (const auto& [major, minor] : {std::pair{4, 3}, std::pair{3, 3}}) {
      glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, major);
      glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, minor);
      window_ = glfwCreateWindow(64, 64, "deform::gpu check", nullptr, nullptr);
      if (window_) break;
    }
    if (!window_) return;
    glfwMakeContextCurrent(window_);
    renderer_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  }
  ~HiddenContext() {
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
  }
  HiddenContext(const HiddenContext&) = delete;
  HiddenContext& operator=(const HiddenContext&) = delete;

  bool open() const { return window_ != nullptr; }
  const std::string& renderer() const { return renderer_; }

 private:
  GLFWwindow* window_ = nullptr;
  std::string renderer_;
};

// A check's main(): opens the context and returns run()'s exit status (0 passed, 1 failed), printing "all passed" or
// "FAILED" when `report`; 1 when no window opens (no display), 0 with "skipped" when the context lacks OpenGL 4.3.
template <class Run>
int run_in_context(const char* program, Run&& run, bool report = true) {
  const HiddenContext context;
  if (!context.open()) {
    std::fprintf(stderr, "%s: cannot open an OpenGL window (no display? try xvfb-run)\n", program);
    return 1;
  }
  if (!deform::GpuBezierLattice::supported()) {
    std::printf("skipped: no OpenGL 4.3 (compute shaders) in this context (%s)\n", context.renderer().c_str());
    return 0;
  }
  std::printf("renderer: %s\n", context.renderer().c_str());
  const int status = run();
  if (report) std::printf("%s\n", status == 0 ? "all passed" : "FAILED");
  return status;
}

}  // namespace gpu_test
