#pragma once
// Shared helpers of the lattice tests: seeded random frames, lattices and points; running the evaluation job.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
namespace lattice_test {

inline float uniform(std::mt19937& rng, float a, float b) { return std::uniform_real_distribution<float>(a, b)(rng); }
inline glm::vec3 uniform3(std::mt19937& rng, float a, float b) {
  return glm::vec3{uniform(rng, a, b), uniform(rng, a, b), uniform(rng, a, b)};
}

// A rotated, sheared, non-uniformly scaled right-handed frame near the origin.
inline deform::LatticeFrame random_frame(std::mt19937& rng) {
  const float turn = uniform(rng, -3.0f, 3.0f);
  const glm::mat4 r =
      glm::rotate(glm::mat4(1.0f), turn, glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(0.0f, 0.0f, 0.01f)));
  const glm::mat3 rot(r);
  deform::LatticeFrame f;
  f.origin = uniform3(rng, -2.0f, 2.0f);
  f.u_axis = rot * glm::vec3{uniform(rng, 0.5f, 3.0f), uniform(rng, -0.3f, 0.3f), 0.0f};
  f.v_axis = rot * glm::vec3{0.0f, uniform(rng, 0.5f, 3.0f), uniform(rng, -0.3f, 0.3f)};
  f.w_axis = rot * glm::vec3{uniform(rng, -0.3f, 0.3f), 0.0f, uniform(rng, 0.5f, 3.0f)};
  return f;
}

// `count` random unit normals.
inline std::vector<glm::vec3> random_normals(std::mt19937& rng, std::size_t count) {
  std::vector<glm::vec3> out(count);
  for (glm::vec3& n : out) n = glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(0.0f, 0.0f, 1e-3f));
  return out;
}

// Every control point moved onto `point` or (onto_line) onto the line through it along `along`, point n at
// (n mod 5) steps: a lattice whose Jacobian has rank 0 or 1 everywhere (to float rounding).
inline void collapse(std::span<glm::vec3> control, glm::vec3 point, glm::vec3 along, bool onto_line) {
  for (std::size_t n = 0; n < control.size(); ++n)
    control[n] = point + (onto_line ? float(n % 5) * along : glm::vec3(0.0f));
}

// Random points of the box (parameters in [0, 1]³), in world space.
inline std::vector<glm::vec3> points_inside(const deform::LatticeFrame& f, std::mt19937& rng, std::size_t count) {
  std::vector<glm::vec3> out;
  for (std::size_t i = 0; i < count; ++i) out.push_back(f.to_world(uniform3(rng, 0.0f, 1.0f)));
  return out;
}

// Evaluates a binding over every block with every kernel copy this CPU runs (isa.hpp) and returns the positions (and
// the normals when `normals` is not null, in place) of the best one, the copy `automatic` runs. The copies differ only
// in float rounding (fused multiply-adds): each is checked here against the portable copy within the tolerances the
// tests hold the kernel to against its references (positions 1e-5 · (1 + |p|), unit normals 1e-4), so every lattice
// test holds every copy to those references.
inline std::vector<glm::vec3> evaluate(const deform::LatticeBinding& binding, std::span<const glm::vec3> control_points,
                                       std::vector<glm::vec3> positions, std::vector<glm::vec3>* normals = nullptr) {
  const auto run = [&](deform::Isa isa, std::vector<glm::vec3>& out_positions, std::vector<glm::vec3>& out_normals) {
    out_positions = positions;
    if (normals) out_normals = *normals;
    deform::LatticeEvaluateJob job;
    job.binding = &binding;
    job.control_points = control_points;
    job.positions = out_positions;
    job.isa = isa;
    if (normals) {
      job.normals_in = out_normals;
      job.normals_out = out_normals;
    }
    REQUIRE(job.run());
  };
  std::vector<glm::vec3> portable_positions, portable_normals;
  run(deform::Isa::portable, portable_positions, portable_normals);
  std::vector<glm::vec3> best_positions = portable_positions, best_normals = portable_normals;
  for (const deform::Isa isa : {deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128}) {
    if (!deform::isa_available(isa)) continue;
    std::vector<glm::vec3> p, n;
    run(isa, p, n);
    double worst_position = 0.0, worst_normal = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const double size = 1.0 + double(glm::length(portable_positions[i]));
      worst_position = std::max(worst_position, double(glm::length(p[i] - portable_positions[i])) / size);
      if (normals) worst_normal = std::max(worst_normal, double(glm::length(n[i] - portable_normals[i])));
    }
    INFO("kernel copy " << std::string(deform::isa_name(isa)) << " against the portable one");
    CHECK(worst_position <= 1e-5);
    CHECK(worst_normal <= 1e-4);
    if (isa == deform::isa_best()) best_positions = std::move(p), best_normals = std::move(n);
  }
  if (normals) *normals = best_normals;
  return best_positions;
}

inline double dist(glm::dvec3 a, glm::dvec3 b) { return glm::length(a - b); }

}  // namespace lattice_test
