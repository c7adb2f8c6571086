#pragma once
// Shared helpers of the lattice tests: seeded random frames, lattices and points; running the evaluation job.
#include <doctest/doctest.h>

#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
namespace lattice_test {

inline float uniform(std::mt19937& rng, float a, float b) { return std::uniform_real_distribution<float>(a, b)(rng); }
inline glm::vec3 uniform3(std::mt19937& rng, float a, float b) {
  return glm::vec3(uniform(rng, a, b), uniform(rng, a, b), uniform(rng, a, b));
}

// A rotated, sheared, non-uniformly scaled right-handed frame near the origin.
inline deform::LatticeFrame random_frame(std::mt19937& rng) {
  const glm::mat4 r = glm::rotate(glm::mat4(1.0f), uniform(rng, -3.0f, 3.0f),
                                  glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(0.0f, 0.0f, 0.01f)));
  const glm::mat3 rot(r);
  deform::LatticeFrame f;
  f.origin = uniform3(rng, -2.0f, 2.0f);
  f.u_axis = rot * glm::vec3(uniform(rng, 0.5f, 3.0f), uniform(rng, -0.3f, 0.3f), 0.0f);
  f.v_axis = rot * glm::vec3(0.0f, uniform(rng, 0.5f, 3.0f), uniform(rng, -0.3f, 0.3f));
  f.w_axis = rot * glm::vec3(uniform(rng, -0.3f, 0.3f), 0.0f, uniform(rng, 0.5f, 3.0f));
  return f;
}

// Random points of the box (parameters in [0, 1]³), in world space.
inline std::vector<glm::vec3> points_inside(const deform::LatticeFrame& f, std::mt19937& rng, std::size_t count) {
  std::vector<glm::vec3> out;
  for (std::size_t i = 0; i < count; ++i) out.push_back(f.to_world(uniform3(rng, 0.0f, 1.0f)));
  return out;
}

// Evaluates a binding over every block; returns the positions (and normals when `normals` is not empty).
inline std::vector<glm::vec3> evaluate(const deform::LatticeBinding& binding, std::span<const glm::vec3> control_points,
                                       std::vector<glm::vec3> positions, std::vector<glm::vec3>* normals = nullptr) {
  deform::LatticeEvaluateJob job;
  job.binding = &binding;
  job.control_points = control_points;
  job.positions = positions;
  if (normals) {
    job.normals_in = *normals;
    job.normals_out = *normals;
  }
  REQUIRE(job.run());
  return positions;
}

inline double dist(glm::dvec3 a, glm::dvec3 b) { return glm::length(a - b); }

}  // namespace lattice_test
