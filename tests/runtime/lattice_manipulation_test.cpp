// Direct manipulation (Hsu, Hughes & Kaufman 1992): the point lands, with the minimum-norm displacement.
#include <doctest/doctest.h>

#include <random>
#include <vector>

#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
#include "runtime/lattice_reference.hpp"
#include "runtime/lattice_test_util.hpp"

using namespace lattice_test;

namespace {

// Σ |ΔP|² between two control point sets.
double squared_norm(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += glm::dot(glm::dvec3(a[i] - b[i]), glm::dvec3(a[i] - b[i]));
  return s;
}

}  // namespace

TEST_CASE("move_point puts the embedded point on its target with the minimum-norm displacement (Bézier)") {
  std::mt19937 rng(41);
  for (int trial = 0; trial < 500; ++trial) {
    const glm::ivec3 degree{1 + static_cast<int>(rng() % 5), 1 + static_cast<int>(rng() % 5),
                            1 + static_cast<int>(rng() % 5)};
    const deform::LatticeFrame frame = random_frame(rng);
    deform::BezierLattice lattice(frame, degree);
    for (glm::vec3& p : lattice.control_points()) p += uniform3(rng, -0.2f, 0.2f);
    const std::vector<glm::vec3> before(lattice.control_points().begin(), lattice.control_points().end());
    const glm::vec3 uvw = uniform3(rng, 0.0f, 1.0f);
    const glm::vec3 target = lattice.evaluate(uvw) + uniform3(rng, -1.0f, 1.0f);
    lattice.move_point(uvw, target);
    INFO("trial " << trial);
    CHECK(dist(lattice_reference::bezier(lattice.control_points(), degree, uvw), target) < 1e-4);
    // Any other displacement that lands the point is longer; here: the same move made by one control point alone.
    int best = 0;
    double best_weight = 0.0;
    for (int k = 0; k <= degree.z; ++k)
      for (int j = 0; j <= degree.y; ++j)
        for (int i = 0; i <= degree.x; ++i) {
          const double b = lattice_reference::bernstein(degree.x, i, uvw.x) *
                           lattice_reference::bernstein(degree.y, j, uvw.y) *
                           lattice_reference::bernstein(degree.z, k, uvw.z);
          if (b > best_weight) best_weight = b, best = static_cast<int>(lattice.index(i, j, k));
        }
    std::vector<glm::vec3> single = before;
    const glm::vec3 delta = target - glm::vec3(lattice_reference::bezier(before, degree, uvw));
    single[static_cast<std::size_t>(best)] += delta / static_cast<float>(best_weight);
    CHECK(dist(lattice_reference::bezier(single, degree, uvw), target) < 1e-4);
    CHECK(squared_norm(lattice.control_points(), before) <= squared_norm(single, before) * (1.0 + 1e-5));
    // And the displacement is the pseudo-inverse's: ΔP_ijk ∝ B_ijk.
    const glm::dvec3 expected = glm::dvec3(delta) / [&] {
      double s = 0.0;
      for (int k = 0; k <= degree.z; ++k)
        for (int j = 0; j <= degree.y; ++j)
          for (int i = 0; i <= degree.x; ++i) {
            const double b = lattice_reference::bernstein(degree.x, i, uvw.x) *
                             lattice_reference::bernstein(degree.y, j, uvw.y) *
                             lattice_reference::bernstein(degree.z, k, uvw.z);
            s += b * b;
          }
      return s;
    }();
    const std::size_t corner = lattice.index(degree.x, 0, degree.z);
    const double b_corner = lattice_reference::bernstein(degree.x, degree.x, uvw.x) *
                            lattice_reference::bernstein(degree.y, 0, uvw.y) *
                            lattice_reference::bernstein(degree.z, degree.z, uvw.z);
    CHECK(dist(glm::dvec3(lattice.control_points()[corner] - before[corner]), b_corner * expected) < 1e-5);
  }
}

TEST_CASE("move_point on a B-spline lattice lands and touches only the 4x4x4 points of the cell") {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 300; ++trial) {
    const glm::ivec3 counts{4 + static_cast<int>(rng() % 6), 4 + static_cast<int>(rng() % 6),
                            4 + static_cast<int>(rng() % 6)};
    deform::BsplineLattice lattice(random_frame(rng), counts);
    const std::vector<glm::vec3> before(lattice.control_points().begin(), lattice.control_points().end());
    const glm::vec3 uvw = uniform3(rng, 0.0f, 1.0f);
    const glm::vec3 target = lattice.evaluate(uvw) + uniform3(rng, -1.0f, 1.0f);
    lattice.move_point(uvw, target);
    INFO("trial " << trial);
    CHECK(dist(lattice_reference::bspline(lattice.control_points(), counts, uvw), target) < 1e-4);
    std::size_t changed = 0;
    for (std::size_t i = 0; i < before.size(); ++i) changed += lattice.control_points()[i] != before[i];
    CHECK(changed <= 64);
    CHECK(changed >= 8);
  }
}
