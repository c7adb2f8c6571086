// Checks deform::GpuBezierLattice (deform/gpu/lattice.hpp) against the CPU kernel (LatticeEvaluateJob):
// seeded random frames and control point displacements for several degrees, a few thousand random points inside and
// outside the box, positions and Jacobian normals through both outputs (read back, and written into an interleaved
// vertex buffer); and lattices collapsed to a point or onto a line, where both keep every input normal. Prints the
// largest differences; exits 1 when one exceeds 1e-4 (positions relative to the lattice's size) or anything outside
// the bound vertices changed, 0 with "skipped" when the context lacks OpenGL 4.3.
//
// gpu_lattice_check --bench prints indicative per-frame times of both paths instead (not a test: docs/gpu.md).
#include "hidden_context.hpp"  // epoxy first

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "deform/extras/builtin.hpp"
#include "deform/gpu/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/model.hpp"

namespace {

constexpr float tolerance = 1e-4f;

struct Case {
  glm::ivec3 degree;
  unsigned seed;
  enum Collapse { none, to_point, onto_line } collapse = none;  // collapsed lattices: no normal to give, both keep
};

bool same_bits(glm::vec3 a, glm::vec3 b) { return std::memcmp(&a, &b, sizeof a) == 0; }

glm::vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  for (;;) {
    const glm::vec3 n{g(rng), g(rng), g(rng)};
    if (glm::length(n) > 1e-3f) return glm::normalize(n);
  }
}

// A rotated, scaled and slightly sheared box somewhere near the origin (positive volume).
deform::LatticeFrame random_frame(std::mt19937& rng) {
  std::uniform_real_distribution<float> origin(-5.0f, 5.0f), scale(0.5f, 2.0f), shear(-0.2f, 0.2f);
  const glm::vec3 axis = random_unit(rng);
  const glm::mat3 rotation =
      glm::mat3_cast(glm::angleAxis(std::uniform_real_distribution<float>(0.0f, 6.28f)(rng), axis));
  glm::mat3 shape(1.0f);
  shape[1][0] = shear(rng), shape[2][0] = shear(rng), shape[2][1] = shear(rng);
  const glm::mat3 m = rotation * shape;
  deform::LatticeFrame f;
  f.origin = glm::vec3{origin(rng), origin(rng), origin(rng)};
  f.u_axis = m[0] * scale(rng);
  f.v_axis = m[1] * scale(rng);
  f.w_axis = m[2] * scale(rng);
  return f;
}

// Runs one case; returns false on a failure (printed).
bool check(const Case& c) {
  std::mt19937 rng(c.seed);
  const deform::LatticeFrame frame = random_frame(rng);
  deform::BezierLattice lattice(frame, c.degree);
  // Displacements of up to a quarter of a control point spacing along each axis keep the map one-to-one, so the
  // normals stay well conditioned and comparable.
  const float amplitude = 0.25f / float(std::max({c.degree.x, c.degree.y, c.degree.z}));
  std::uniform_real_distribution<float> jitter(-amplitude, amplitude);
  for (glm::vec3& p : lattice.control_points()) {
    const glm::vec3 step{jitter(rng), jitter(rng), jitter(rng)};
    p += step.x * frame.u_axis + step.y * frame.v_axis + step.z * frame.w_axis;
  }
  if (c.collapse != Case::none) {
    const glm::vec3 point = frame.to_world(glm::vec3(0.5f)), along = frame.u_axis + 0.5f * frame.v_axis;
    const std::span<glm::vec3> control = lattice.control_points();
    for (std::size_t n = 0; n < control.size(); ++n)
      control[n] = point + (c.collapse == Case::onto_line ? 0.2f * float(n % 5) * along : glm::vec3(0.0f));
  }

  // Random points in a box 25% larger than the lattice on every side, plus its 8 corners exactly.
  std::uniform_real_distribution<float> param(-0.25f, 1.25f);
  std::vector<glm::vec3> positions, normals;
  for (int i = 0; i < 4000; ++i) {
    positions.push_back(frame.to_world(glm::vec3{param(rng), param(rng), param(rng)}));
    normals.push_back(random_unit(rng));
  }
  for (int corner = 0; corner < 8; ++corner) {
    positions.push_back(frame.to_world(glm::vec3(float(corner & 1), float((corner >> 1) & 1), float(corner >> 2))));
    normals.push_back(random_unit(rng));
  }
  const deform::LatticeBinding binding = deform::bind_lattice(lattice, positions);
  std::vector<bool> bound(positions.size(), false);
  for (std::uint32_t v : binding.vertices)
    if (v != deform::LatticeBinding::no_vertex) bound[v] = true;
  const std::size_t outside = std::size_t(std::count(bound.begin(), bound.end(), false));

  std::vector<glm::vec3> cpu_positions = positions, cpu_normals = normals;
  deform::LatticeEvaluateJob job;
  job.binding = &binding;
  job.control_points = lattice.control_points();
  job.positions = cpu_positions;
  job.normals_in = normals;
  job.normals_out = cpu_normals;
  if (!job.run()) {
    std::printf("FAIL: the CPU job is invalid\n");
    return false;
  }

  deform::GpuBezierLattice gpu;
  if (!gpu.create(binding, normals) || !gpu.evaluate(lattice.control_points())) {
    std::printf("FAIL: the GPU lattice refused a valid binding\n");
    return false;
  }
  std::vector<glm::vec3> gpu_positions = positions, gpu_normals = normals;
  if (!gpu.read_back(gpu_positions, gpu_normals)) {
    std::printf("FAIL: read_back refused valid spans\n");
    return false;
  }

  // The draw path: an interleaved buffer (GpuVertexLayout's default: u v, nx ny nz, x y z) filled with a pattern that
  // must survive outside the written slots.
  constexpr int stride = 8;
  std::vector<float> pattern(positions.size() * stride);
  for (std::size_t i = 0; i < pattern.size(); ++i) pattern[i] = 1000.0f + 0.5f * float(i);
  GLuint buffer = 0;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(pattern.size() * sizeof(float)), pattern.data(), GL_STREAM_DRAW);
  const bool into = gpu.evaluate_into(lattice.control_points(), buffer).ok();
  std::vector<float> interleaved(pattern.size());
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glGetBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(interleaved.size() * sizeof(float)), interleaved.data());
  glDeleteBuffers(1, &buffer);
  if (!into) {
    std::printf("FAIL: evaluate_into refused a large enough buffer\n");
    return false;
  }

  const float size = std::max({glm::length(frame.u_axis), glm::length(frame.v_axis), glm::length(frame.w_axis)});
  float position_error = 0.0f, normal_error = 0.0f, into_error = 0.0f, kept_error = 0.0f;
  std::size_t changed_outside = 0;
  for (std::size_t p = 0; p < positions.size(); ++p) {
    const float* slot = interleaved.data() + p * stride;
    const glm::vec3 into_normal(slot[2], slot[3], slot[4]), into_position(slot[5], slot[6], slot[7]);
    if (!bound[p]) {
      changed_outside += !same_bits(gpu_positions[p], positions[p]) || !same_bits(gpu_normals[p], normals[p]) ||
                         !same_bits(cpu_positions[p], positions[p]);
      for (int f = 0; f < stride; ++f) changed_outside += slot[f] != pattern[p * stride + std::size_t(f)];
      continue;
    }
    changed_outside += slot[0] != pattern[p * stride] || slot[1] != pattern[p * stride + 1];  // the UVs
    if (c.collapse != Case::none) kept_error = std::max(kept_error, glm::length(cpu_normals[p] - normals[p]));
    position_error = std::max(position_error, glm::length(gpu_positions[p] - cpu_positions[p]) / size);
    normal_error = std::max(normal_error, glm::length(gpu_normals[p] - cpu_normals[p]));
    into_error = std::max(
        {into_error, glm::length(into_position - cpu_positions[p]) / size, glm::length(into_normal - cpu_normals[p])});
    if (!std::isfinite(gpu_positions[p].x + gpu_positions[p].y + gpu_positions[p].z)) position_error = INFINITY;
  }
  const bool ok = position_error <= tolerance && normal_error <= tolerance && into_error <= tolerance &&
                  changed_outside == 0 && binding.vertex_count > 1000 && outside > 1000 && kept_error == 0.0f;
  const char* collapse = c.collapse == Case::to_point    ? ", collapsed to a point"
                         : c.collapse == Case::onto_line ? ", collapsed onto a line"
                                                         : "";
  std::printf(
      "%s degree (%d,%d,%d) seed %u%s: %zu bound, %zu outside; max |GPU-CPU| position %.3g (of size), "
      "normal %.3g, vertex buffer %.3g; changed outside %zu; normals not kept %.3g\n",
      ok ? "ok  " : "FAIL", c.degree.x, c.degree.y, c.degree.z, c.seed, collapse, binding.vertex_count, outside,
      double(position_error), double(normal_error), double(into_error), changed_outside, double(kept_error));
  return ok;
}

// The contract's refusals: a B-spline binding, short normals, a wrong control point count, a short vertex buffer, a
// layout that does not fit its stride; and a moved lattice keeps working while the one moved from holds nothing.
bool check_refusals() {
  const deform::LatticeFrame frame = deform::LatticeFrame::axis_aligned(glm::vec3(0.0f), glm::vec3(1.0f));
  const std::vector<glm::vec3> points = {glm::vec3(0.5f), glm::vec3(0.25f), glm::vec3(2.0f)};
  const deform::BsplineLattice bspline(frame, glm::ivec3(5));
  const deform::BezierLattice bezier(frame, glm::ivec3(2));
  const deform::LatticeBinding bezier_binding = deform::bind_lattice(bezier, points);
  deform::GpuBezierLattice gpu;
  bool ok =
      !gpu.create(deform::bind_lattice(bspline, points)) && !gpu.create(bezier_binding, std::span(points).first(1));
  ok = ok && gpu.create(bezier_binding) && !gpu.evaluate(std::span(bezier.control_points()).first(26));
  GLuint buffer = 0;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, 8 * sizeof(float), nullptr, GL_STREAM_DRAW);  // one vertex; index 1 is bound
  ok = ok && !gpu.evaluate_into(bezier.control_points(), buffer);
  glBufferData(GL_ARRAY_BUFFER, 3 * 8 * sizeof(float), nullptr, GL_STREAM_DRAW);
  ok = ok && !gpu.evaluate_into(bezier.control_points(), buffer, deform::GpuVertexLayout{8, 6, 2}) &&
       gpu.evaluate_into(bezier.control_points(), buffer);
  deform::GpuBezierLattice moved = std::move(gpu);
  ok = ok && !gpu.created() && !gpu.evaluate_into(bezier.control_points(), buffer) && moved.created() &&
       moved.evaluate_into(bezier.control_points(), buffer);
  glDeleteBuffers(1, &buffer);
  std::printf("%s refusals (B-spline binding, short normals, wrong point count, short vertex buffer, layout); move\n",
              ok ? "ok  " : "FAIL");
  return ok;
}

// Mean seconds per call of `f` over enough calls to take about a second.
template <class F>
double seconds_per_call(F&& f) {
  using clock = std::chrono::steady_clock;
  f();
  int calls = 0;
  const auto start = clock::now();
  double elapsed = 0.0;
  while (elapsed < 1.0) {
    f();
    ++calls;
    elapsed = std::chrono::duration<double>(clock::now() - start).count();
  }
  return elapsed / calls;
}

void bench_one(const char* name, const deform::BezierLattice& lattice, const deform::LatticeBinding& binding,
               std::span<const glm::vec3> normals) {
  std::vector<glm::vec3> positions(normals.size()), normals_out(normals.size());
  deform::LatticeEvaluateJob job;
  job.binding = &binding;
  job.control_points = lattice.control_points();
  job.positions = positions;
  job.normals_in = normals;
  job.normals_out = normals_out;
  const double cpu = seconds_per_call([&] { job.run(); });
  deform::GpuBezierLattice gpu;
  gpu.create(binding, normals);
  GLuint buffer = 0;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(normals.size() * 8 * sizeof(float)), nullptr, GL_STREAM_DRAW);
  const double into = seconds_per_call([&] {
    gpu.evaluate_into(lattice.control_points(), buffer);
    glFinish();
  });
  const double read = seconds_per_call([&] {
    gpu.evaluate(lattice.control_points());
    gpu.read_back(positions, normals_out);
  });
  glDeleteBuffers(1, &buffer);
  std::printf(
      "%-34s %7zu vertices: CPU kernel (1 thread) %8.3f ms, GPU into vertex buffer %8.3f ms, "
      "GPU + read back %8.3f ms\n",
      name, binding.vertex_count, cpu * 1e3, into * 1e3, read * 1e3);
}

// Per-frame times with normals, tricubic: the ffd_lattice sample's bound render vertices, and 100k points in a box.
void bench() {
  const deform::Model model = deform::builtin_character();
  std::vector<glm::vec3> render_positions(model.mesh.vertex_count());
  for (std::size_t r = 0; r < render_positions.size(); ++r)
    render_positions[r] = model.mesh.positions[model.mesh.vertex_point[r]];
  const deform::BezierLattice sample_lattice(
      deform::LatticeFrame::axis_aligned({-0.35f, 1.15f, -0.25f}, {0.7f, 0.7f, 0.5f}), glm::ivec3(3));
  bench_one("ffd_lattice sample (tricubic)", sample_lattice, deform::bind_lattice(sample_lattice, render_positions),
            model.mesh.vertex_normals);

  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<glm::vec3> points(100000), normals(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    points[i] = glm::vec3{unit(rng), unit(rng), unit(rng)};
    normals[i] = random_unit(rng);
  }
  deform::BezierLattice cube(deform::LatticeFrame::axis_aligned(glm::vec3(0.0f), glm::vec3(1.0f)), glm::ivec3(3));
  for (glm::vec3& p : cube.control_points()) p += 0.05f * glm::vec3{unit(rng), unit(rng), unit(rng)};
  bench_one("100k points (tricubic)", cube, deform::bind_lattice(cube, points), normals);
}

}  // namespace

int main(int argc, char** argv) {
  const bool benchmark = argc == 2 && std::string(argv[1]) == "--bench";
  if (argc > 1 && !benchmark) {
    std::fprintf(stderr, "usage: gpu_lattice_check [--bench]\n");
    return 2;
  }
  if (benchmark) {
    const auto timings = [] {
      bench();
      return 0;
    };
    return gpu_test::run_in_context("gpu_lattice_check", timings, false);
  }
  return gpu_test::run_in_context("gpu_lattice_check", [] {
    const Case cases[] = {{{1, 1, 1}, 1},
                          {{1, 1, 1}, 2},
                          {{3, 3, 3}, 3},
                          {{3, 3, 3}, 4},
                          {{2, 4, 5}, 5},
                          {{2, 4, 5}, 6},
                          {{6, 6, 6}, 7},
                          {{6, 6, 6}, 8},
                          {{16, 2, 1}, 9},
                          {{3, 3, 3}, 10, Case::to_point},
                          {{6, 6, 6}, 11, Case::onto_line},
                          {{16, 2, 1}, 12, Case::onto_line}};
    bool ok = check_refusals();
    for (const Case& c : cases) ok = check(c) && ok;
    return ok ? 0 : 1;
  });
}
