// ffd_lattice: free-form deformation with a tricubic Bézier lattice (Sederberg & Parry 1986). A 4×4×4 lattice is
// fitted around the character's head and chest and bound once; every frame only its control points move (a slow
// wave through the top layers) and only the evaluation runs over the bound vertices, with Jacobian normals.
//
// The evaluation runs on the CPU (LatticeEvaluateJob) or, with `--gpu` or the G key, in a compute shader that writes
// straight into the vertex buffer that draws (deform::GpuBezierLattice, OpenGL 4.3): then the CPU evaluates nothing and
// uploads only the 64 control points. The lattice is bound over the render vertices (each point gathered by
// vertex_point) so that both paths write the buffer's vertices directly.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/io/lattice_json.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/gpu/lattice.hpp"
#include "sample_app.hpp"  // epoxy before any other GL header

#include <GLFW/glfw3.h>

int main(int argc, char** argv) {
  std::vector<char*> args;  // argv without --gpu, for run_sample
  bool use_gpu = false;
  for (int i = 0; i < argc; ++i) {
    if (i > 0 && std::string(argv[i]) == "--gpu") use_gpu = true;
    else args.push_back(argv[i]);
  }

  const deform::Model model = deform::builtin_character();
  const deform::Mesh& mesh = model.mesh;
  const deform::LatticeFrame frame = deform::LatticeFrame::axis_aligned({-0.35f, 1.15f, -0.25f}, {0.7f, 0.7f, 0.5f});
  deform::BezierLattice lattice(frame, glm::ivec3(3));
  std::vector<glm::vec3> rest_positions(mesh.vertex_count());  // per render vertex
  for (std::size_t r = 0; r < rest_positions.size(); ++r) rest_positions[r] = mesh.positions[mesh.vertex_point[r]];
  const deform::LatticeBinding binding =
      deform::bind_lattice(lattice, rest_positions);  // once: each vertex's (u, v, w)
  std::vector<glm::vec3> positions = rest_positions, normals = mesh.vertex_normals;
  sample::MeshRenderer renderer;
  deform::GpuBezierLattice gpu;
  bool gpu_created = false, g_was_down = false;

  const auto set_mode = [&](bool want_gpu) {
    if (want_gpu && !gpu_created) {
      const deform::Status created = gpu.create(binding, mesh.vertex_normals);
      gpu_created = created.ok();
      if (!gpu_created) {
        std::fprintf(stderr, "ffd_lattice: no GPU lattice: %s; evaluating on the CPU\n", created.reason());
        want_gpu = false;
      }
    }
    // The buffer must hold every vertex's current state: the GPU path rewrites only the bound ones.
    if (want_gpu) renderer.upload(positions, normals);
    std::printf("ffd_lattice: evaluating on the %s\n", want_gpu ? "GPU" : "CPU");
    use_gpu = want_gpu;
    glfwSetWindowTitle(glfwGetCurrentContext(), use_gpu ? "libdeform: Bezier lattice (GPU, G toggles)"
                                                        : "libdeform: Bezier lattice (CPU, G toggles)");
  };

  return sample::run_sample(
      int(args.size()), args.data(), "libdeform: Bezier lattice",
      [&] {
        renderer.create(mesh);
        renderer.upload(positions, normals);
        set_mode(use_gpu);
      },
      [&](const sample::Frame& f) {
        const bool g_down = glfwGetKey(glfwGetCurrentContext(), GLFW_KEY_G) == GLFW_PRESS;
        if (g_down && !g_was_down) set_mode(!use_gpu);
        g_was_down = g_down;

        const glm::ivec3 n = lattice.point_counts();
        for (int k = 0; k < n.z; ++k)
          for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
              const float height = float(j) / float(n.y - 1);  // the top layers sway most
              const glm::vec3 sway(0.18f * std::sin(f.time * 1.7f + float(k)), 0.0f, 0.12f * std::cos(f.time * 1.3f));
              lattice.control_points()[lattice.index(i, j, k)] = lattice.rest_point(i, j, k) + height * height * sway;
            }
        if (use_gpu) {
          gpu.evaluate_into(lattice.control_points(), renderer.vertex_buffer());
        } else {
          deform::LatticeEvaluateJob job;
          job.binding = &binding;
          job.control_points = lattice.control_points();
          job.positions = positions;
          job.normals_in = mesh.vertex_normals;
          job.normals_out = normals;
          job.run();
          renderer.upload(positions, normals);
        }
        renderer.draw(glm::mat4(1.0f), f.view, f.projection, f.eye);

        for (int k = 0; k < n.z; ++k)
          for (int j = 0; j < n.y; ++j)
            for (int i = 0; i < n.x; ++i) {
              const glm::vec3 p = lattice.control_points()[lattice.index(i, j, k)];
              f.overlay->point(p, glm::vec3(0.3f, 0.8f, 1.0f), 6.0f);
              if (i + 1 < n.x)
                f.overlay->line(p, lattice.control_points()[lattice.index(i + 1, j, k)], glm::vec3(0.3f, 0.6f, 0.9f));
              if (j + 1 < n.y)
                f.overlay->line(p, lattice.control_points()[lattice.index(i, j + 1, k)], glm::vec3(0.3f, 0.6f, 0.9f));
              if (k + 1 < n.z)
                f.overlay->line(p, lattice.control_points()[lattice.index(i, j, k + 1)], glm::vec3(0.3f, 0.6f, 0.9f));
            }
      },
      [&] { gpu.release(); });  // while the context lives
}
