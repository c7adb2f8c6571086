#include "framework.hpp"  // epoxy first: it must precede every other GL header

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>

#include <GLFW/glfw3.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <stb/stb_image_write.h>

namespace sample {

// ---------------------------------------------------------------------------------------------------------------
// Window

void Window::on_scroll(GLFWwindow* w, double, double dy) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  if (!ImGui::GetIO().WantCaptureMouse) self->scroll_accum_ += float(dy);
}

void Window::on_key(GLFWwindow* w, int key, int, int action, int) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  if (action == GLFW_PRESS && !ImGui::GetIO().WantCaptureKeyboard) self->key_accum_ = key;
}

bool Window::open(const WindowOptions& options) {
  glfwSetErrorCallback([](int code, const char* text) { std::fprintf(stderr, "GLFW error %d: %s\n", code, text); });
  if (!glfwInit()) return false;
  hidden_ = options.hidden;
  glfwWindowHint(GLFW_VISIBLE, hidden_ ? GLFW_FALSE : GLFW_TRUE);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_SAMPLES, hidden_ ? 0 : 4);
  // Ask for 4.3 (compute shaders); fall back to the 3.3 core profile the viewer needs.
  for (const auto [major, minor] : {std::pair{4, 3}, std::pair{3, 3}}) {
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, major);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, minor);
    window_ = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (window_) break;
  }
  if (!window_) return false;
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(hidden_ ? 0 : 1);
  glfwSetWindowUserPointer(window_, this);
  gl_version_ = epoxy_gl_version();
  renderer_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  // Our callbacks first: ImGui's backend installs its own and chains to these.
  glfwSetScrollCallback(window_, on_scroll);
  glfwSetKeyCallback(window_, on_key);
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");

  if (hidden_) {
    size_ = {options.width, options.height};
    glGenFramebuffers(1, &fbo_);
    glGenRenderbuffers(1, &color_);
    glGenRenderbuffers(1, &depth_);
    glBindRenderbuffer(GL_RENDERBUFFER, color_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, size_.x, size_.y);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, size_.x, size_.y);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      std::fprintf(stderr, "offscreen framebuffer is incomplete\n");
      return false;
    }
  }
  return true;
}

Window::~Window() {
  if (!window_) return;
  if (fbo_) glDeleteFramebuffers(1, &fbo_);
  if (color_) glDeleteRenderbuffers(1, &color_);
  if (depth_) glDeleteRenderbuffers(1, &depth_);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window_);
  glfwTerminate();
}

bool Window::should_close() const { return glfwWindowShouldClose(window_); }

void Window::begin_frame() {
  glfwPollEvents();
  if (!hidden_) glfwGetFramebufferSize(window_, &size_.x, &size_.y);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  if (hidden_) ImGui::GetIO().DisplaySize = ImVec2(float(size_.x), float(size_.y));
  ImGui::NewFrame();

  const bool captured = ImGui::GetIO().WantCaptureMouse;
  double x = 0, y = 0;
  glfwGetCursorPos(window_, &x, &y);
  // Cursor coordinates are in window units; scale them to framebuffer pixels (HiDPI).
  int ww = 1, wh = 1;
  glfwGetWindowSize(window_, &ww, &wh);
  const glm::vec2 mouse(float(x) * float(size_.x) / float(std::max(ww, 1)),
                        float(y) * float(size_.y) / float(std::max(wh, 1)));
  input_ = Input{};
  input_.mouse = mouse;
  input_.mouse_delta = captured ? glm::vec2(0.0f) : mouse - last_mouse_;
  last_mouse_ = mouse;
  const bool left = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  input_.left_down = left && !captured;
  input_.left_pressed = left && !was_left_down_ && !captured;
  input_.left_released = !left && was_left_down_;
  was_left_down_ = left && (was_left_down_ || !captured);
  input_.right_down = !captured && glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  input_.middle_down = !captured && glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  input_.shift = glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS;
  input_.scroll = scroll_accum_;
  input_.key_pressed = key_accum_;
  scroll_accum_ = 0.0f;
  key_accum_ = 0;

  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, size_.x, size_.y);
  glClearColor(0.16f, 0.18f, 0.22f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
}

void Window::end_frame() {
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  if (!hidden_) glfwSwapBuffers(window_);
  else glFinish();
}

bool Window::save_png(const std::string& path) const {
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  std::vector<std::uint8_t> rgb(std::size_t(size_.x) * std::size_t(size_.y) * 3);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, size_.x, size_.y, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  // GL's rows run bottom-up, PNG's top-down.
  const std::size_t row = std::size_t(size_.x) * 3;
  for (int y = 0; y < size_.y / 2; ++y)
    std::swap_ranges(rgb.begin() + std::ptrdiff_t(y * row), rgb.begin() + std::ptrdiff_t((y + 1) * row),
                     rgb.begin() + std::ptrdiff_t((size_.y - 1 - y) * row));
  const std::string temp = path + ".tmp";
  if (!stbi_write_png(temp.c_str(), size_.x, size_.y, 3, rgb.data(), int(row))) return false;
  return std::rename(temp.c_str(), path.c_str()) == 0;
}

}  // namespace sample
