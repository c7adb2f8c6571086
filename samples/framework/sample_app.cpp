#include "sample_app.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace sample {

int run_sample(int argc, char** argv, const char* title, const std::function<void()>& setup,
               const std::function<void(const Frame&)>& frame, const std::function<void()>& teardown) {
  std::string screenshot;
  int frames = 90;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--screenshot" && i + 1 < argc) screenshot = argv[++i];
    else if (a == "--frames" && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: %s [--screenshot OUT.png [--frames N]]\n", argv[0]);
      return 2;
    }
  }
  const bool headless = !screenshot.empty();
  Window window;
  if (!window.open({title, 1024, 700, headless})) {
    std::fprintf(stderr, "%s: cannot open an OpenGL 3.3 window (no display? try xvfb-run)\n", argv[0]);
    return 1;
  }
  OrbitCamera camera;
  camera.target = glm::vec3(0.0f, 1.1f, 0.0f);
  camera.distance = 4.2f;
  camera.yaw = 0.0f;
  camera.pitch = 0.1f;
  OverlayRenderer overlay;
  overlay.create();
  setup();
  const auto start = std::chrono::steady_clock::now();
  float last = 0.0f;
  for (int f = 0; headless ? f < frames : !window.should_close(); ++f) {
    window.begin_frame();
    camera.handle(window.input(), window.framebuffer_size());
    Frame fr;
    fr.time =
        headless ? float(f) / 60.0f : std::chrono::duration<float>(std::chrono::steady_clock::now() - start).count();
    fr.dt = headless ? 1.0f / 60.0f : std::min(0.1f, fr.time - last);
    last = fr.time;
    fr.view = camera.view();
    fr.projection = camera.projection(window.aspect());
    fr.eye = camera.eye();
    fr.overlay = &overlay;
    frame(fr);
    overlay.flush(fr.projection * fr.view, true);
    const bool saved = !(headless && f + 1 == frames) || window.save_png(screenshot);
    window.end_frame();
    if (!saved) {
      if (teardown) teardown();
      return 1;
    }
  }
  if (teardown) teardown();
  if (headless) std::printf("%s\n", screenshot.c_str());
  return 0;
}

void PointMeshRenderer::create(const deform::Mesh& mesh) {
  mesh_ = &mesh;
  renderer_.create(mesh);
  positions_.resize(mesh.vertex_count());
  normals_.resize(mesh.vertex_count());
  vertex_normals_ = deform::bind_vertex_normals(mesh);
  normals_scratch_.resize(vertex_normals_.scratch_size());
}

void PointMeshRenderer::draw(std::span<const glm::vec3> points, const Frame& frame, glm::mat4 model, glm::vec3 tint) {
  for (std::size_t v = 0; v < positions_.size(); ++v) positions_[v] = points[mesh_->vertex_point[v]];
  deform::VertexNormalsJob normals_job;
  normals_job.binding = &vertex_normals_;
  normals_job.positions = points;
  normals_job.normals = normals_;
  normals_job.scratch = normals_scratch_;
  normals_job.run();
  renderer_.upload(positions_, normals_);
  renderer_.draw(model, frame.view, frame.projection, frame.eye, tint);
}

}  // namespace sample
