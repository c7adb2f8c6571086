// BsplineLattice against the Cox-de Boor reference, invariants and locality.
#include <doctest/doctest.h>

#include <random>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
#include "runtime/lattice_reference.hpp"
#include "runtime/lattice_test_util.hpp"

using namespace lattice_test;
using deform::BsplineLattice;
using deform::LatticeFrame;

TEST_CASE("B-spline rest lattice: one cell of overhang on each side, identity to 1e-6") {
  const BsplineLattice lattice(LatticeFrame::axis_aligned({0, 0, 0}, {4, 2, 1}), glm::ivec3(6, 4, 5));
  CHECK(lattice.cell_counts() == glm::ivec3(3, 1, 2));
  CHECK(lattice.rest_point(0, 0, 0) == glm::vec3(-4.0f / 3.0f, -2.0f, -0.5f));
  CHECK(lattice.rest_point(5, 3, 4) == glm::vec3(16.0f / 3.0f, 4.0f, 1.5f));
  std::mt19937 rng(21);
  for (int trial = 0; trial < 100; ++trial) {
    const glm::ivec3 counts{4 + static_cast<int>(rng() % 12), 4 + static_cast<int>(rng() % 12),
                            4 + static_cast<int>(rng() % 12)};
    const LatticeFrame frame = random_frame(rng);
    const BsplineLattice b(frame, counts);
    const std::vector<glm::vec3> in = points_inside(frame, rng, 100);
    std::vector<glm::vec3> normals(in.size(), glm::normalize(glm::vec3(1, 2, 3)));
    const auto out = evaluate(deform::bind_lattice(b, in), b.control_points(), in, &normals);
    for (std::size_t i = 0; i < in.size(); ++i) {
      CHECK(dist(out[i], in[i]) < 8e-6);
      // The normal goes through two cofactor maps (the frame's, the Jacobian's), each a sum of products of sheared
      // axes: float rounding reaches 1.1e-5 on some of these seeded frames (those Clang's rounding of the test's own
      // glm math draws), hence 2e-5.
      CHECK(dist(normals[i], glm::normalize(glm::vec3(1, 2, 3))) < 2e-5);
    }
  }
}

// As for Bézier lattices (bezier_lattice_test.cpp): collapsed to a point or onto a line, no normal to give; every
// kernel copy keeps each input normal, bit for bit.
TEST_CASE("a collapsed B-spline lattice keeps the input normals on every kernel copy") {
  std::mt19937 rng(22);
  for (int trial = 0; trial < 6; ++trial) {
    const glm::ivec3 counts{4 + static_cast<int>(rng() % 8), 4 + static_cast<int>(rng() % 8), 4};
    const LatticeFrame frame = random_frame(rng);
    BsplineLattice lattice(frame, counts);
    const std::vector<glm::vec3> in = points_inside(frame, rng, 100);
    const deform::LatticeBinding binding = deform::bind_lattice(lattice, in);
    const glm::vec3 point = uniform3(rng, -2.0f, 2.0f), along = uniform3(rng, -1.0f, 1.0f);
    const bool onto_line = trial % 2 == 1;
    collapse(lattice.control_points(), point, along, onto_line);
    std::vector<glm::vec3> normals = random_normals(rng, in.size());
    const std::vector<glm::vec3> normals_in = normals;
    evaluate(binding, lattice.control_points(), in, &normals);
    INFO("trial " << trial << std::string(onto_line ? ", onto a line" : ", to a point"));
    CHECK(normals == normals_in);
  }
}

TEST_CASE("B-spline affine precision and optimised = Cox-de Boor reference to 1e-5") {
  std::mt19937 rng(22);
  int compared = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const glm::ivec3 counts{4 + static_cast<int>(rng() % 8), 4 + static_cast<int>(rng() % 8),
                            4 + static_cast<int>(rng() % 8)};
    const LatticeFrame frame = random_frame(rng);
    BsplineLattice lattice(frame, counts);
    const bool affine_case = trial % 4 == 0;
    glm::mat4 affine(1.0f);
    if (affine_case) {
      for (int c = 0; c < 3; ++c) affine[c] = glm::vec4(uniform3(rng, -1.5f, 1.5f), 0.0f);
      affine[3] = glm::vec4(uniform3(rng, -3.0f, 3.0f), 1.0f);
      for (glm::vec3& p : lattice.control_points()) p = glm::vec3(affine * glm::vec4(p, 1.0f));
    } else {
      for (glm::vec3& p : lattice.control_points()) p += uniform3(rng, -0.1f, 0.1f);
    }
    const std::vector<glm::vec3> in = points_inside(frame, rng, 1 + rng() % 60);
    std::vector<glm::vec3> normals(in.size());
    for (glm::vec3& n : normals) n = glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(1e-3f, 0.0f, 0.0f));
    const std::vector<glm::vec3> normals_in = normals;
    const auto out =
        evaluate(deform::bind_lattice(BsplineLattice(frame, counts), in), lattice.control_points(), in, &normals);
    for (std::size_t i = 0; i < in.size(); ++i) {
      const glm::vec3 uvw = frame.to_lattice(in[i]);
      if (glm::any(glm::lessThan(uvw, glm::vec3(0.0f))) || glm::any(glm::greaterThan(uvw, glm::vec3(1.0f)))) continue;
      const glm::dvec3 ref = affine_case ? glm::dvec3(affine * glm::vec4(in[i], 1.0f))
                                         : lattice_reference::bspline(lattice.control_points(), counts, uvw);
      INFO("trial " << trial << " vertex " << i);
      CHECK(dist(out[i], ref) < 1e-5 * (1.0 + glm::length(ref)));
      CHECK(dist(lattice.evaluate(uvw), ref) < 1e-5 * (1.0 + glm::length(ref)));
      // Normals against the reference's Jacobian (central differences in double).
      const glm::dmat3 axes(glm::dvec3(frame.u_axis), glm::dvec3(frame.v_axis), glm::dvec3(frame.w_axis));
      const glm::dmat3 jac =
          lattice_reference::bspline_jacobian(lattice.control_points(), counts, glm::dvec3(uvw)) * glm::inverse(axes);
      CHECK(dist(normals[i], lattice_reference::transform_normal(jac, glm::dvec3(normals_in[i]))) < 1e-4);
      ++compared;
    }
  }
  CHECK(compared > 10000);
}

TEST_CASE("B-spline Jacobian agrees with finite differences") {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 200; ++trial) {
    const LatticeFrame frame = random_frame(rng);
    BsplineLattice lattice(frame, glm::ivec3(4 + static_cast<int>(rng() % 6)));
    for (glm::vec3& p : lattice.control_points()) p += uniform3(rng, -0.2f, 0.2f);
    const glm::vec3 uvw = uniform3(rng, 0.05f, 0.95f);
    const glm::mat3 jac = lattice.jacobian(uvw);
    const float h = 1e-3f;
    for (int a = 0; a < 3; ++a) {
      glm::vec3 step(0.0f);
      step[a] = h;
      const glm::vec3 fd = (lattice.evaluate(uvw + step) - lattice.evaluate(uvw - step)) / (2.0f * h);
      CHECK(dist(jac[a], fd) < 1e-2 * (1.0 + glm::length(fd)));
    }
  }
}

TEST_CASE("a B-spline control point moves only the vertices of the 4x4x4 cells around it") {
  BsplineLattice lattice(LatticeFrame::axis_aligned({0, 0, 0}, {1, 1, 1}), glm::ivec3(13));  // 10 cells per axis
  lattice.control_points()[lattice.index(6, 6, 6)] += glm::vec3(0.0f, 1.0f, 0.0f);
  // Point 6 weighs on cells 3..6, i.e. parameters (0.3, 0.7) per axis.
  std::vector<glm::vec3> in;
  for (int i = 0; i <= 20; ++i) in.push_back(glm::vec3(0.05f * static_cast<float>(i), 0.5f, 0.5f));
  const auto out =
      evaluate(deform::bind_lattice(BsplineLattice(lattice.frame(), glm::ivec3(13)), in), lattice.control_points(), in);
  for (std::size_t i = 0; i < in.size(); ++i) {
    INFO("x = " << in[i].x);
    if (in[i].x < 0.29f || in[i].x > 0.71f) CHECK(dist(out[i], in[i]) < 1e-6);  // the rest map, to rounding
    else if (in[i].x > 0.31f && in[i].x < 0.69f) CHECK(out[i].y > in[i].y + 1e-4f);
  }
  CHECK(out[10].y == doctest::Approx(0.5f + std::pow(4.0f / 6.0f, 3.0f)).epsilon(1e-5));  // centre weight (4/6)³
}

TEST_CASE("invalid B-spline lattices are errors with context") {
  const LatticeFrame unit = LatticeFrame::axis_aligned({0, 0, 0}, {1, 1, 1});
  CHECK_THROWS_AS(BsplineLattice(unit, glm::ivec3(4, 3, 4)), deform::Error);
  CHECK_THROWS_AS(BsplineLattice(unit, glm::ivec3(4, 4, deform::max_bspline_points + 1)), deform::Error);
  CHECK_THROWS_AS(BsplineLattice(LatticeFrame::axis_aligned({0, 0, 0}, {0, 1, 1})), deform::Error);
  try {
    BsplineLattice bad(unit, glm::ivec3(4, 4, 2), "legs.json");
    FAIL("2 points accepted");
  } catch (const deform::Error& e) {
    CHECK(e.file() == "legs.json");
    CHECK(e.element() == "point count w");
  }
}
