// BezierLattice and the evaluation kernel against hand-computed values, invariants and the pow/binomial reference.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
#include "runtime/lattice_reference.hpp"
#include "runtime/lattice_test_util.hpp"

using namespace lattice_test;
using deform::BezierLattice;
using deform::BsplineLattice;
using deform::LatticeFrame;

TEST_CASE("degree 1: moving one corner is trilinear interpolation (hand-computed)") {
  BezierLattice lattice(LatticeFrame::axis_aligned({0, 0, 0}, {2, 4, 8}), glm::ivec3(1));
  CHECK(lattice.point_count() == 8);
  CHECK(lattice.rest_point(1, 1, 1) == glm::vec3(2, 4, 8));
  lattice.control_points()[lattice.index(1, 1, 1)] += glm::vec3(1.0f, 0.0f, 0.0f);
  // (1, 2, 4) has (u, v, w) = (0.5, 0.5, 0.5): the corner's weight is 0.5³ = 0.125.
  const std::vector<glm::vec3> in = {{1, 2, 4}, {2, 4, 8}, {0, 0, 0}, {2, 2, 8}};
  const auto binding = deform::bind_lattice(lattice, in);
  REQUIRE(binding.vertex_count == 4);
  const auto out = evaluate(binding, lattice.control_points(), in);
  CHECK(out[0].x == doctest::Approx(1.125f).epsilon(1e-6));
  CHECK(out[0].y == doctest::Approx(2.0f).epsilon(1e-6));
  CHECK(out[1].x == doctest::Approx(3.0f).epsilon(1e-6));  // the corner itself moves by the whole offset
  CHECK(out[2] == glm::vec3(0, 0, 0));                     // the opposite corner does not move
  CHECK(out[3].x == doctest::Approx(2.5f).epsilon(1e-6));  // (1, 0.5, 1): weight 0.5
}

TEST_CASE("tricubic: an interior point moves the centre by B_1,3(1/2)³ = 27/512 of its offset") {
  BezierLattice lattice(LatticeFrame::axis_aligned({-1, -1, -1}, {2, 2, 2}));
  CHECK(lattice.degree() == glm::ivec3(3));
  lattice.control_points()[lattice.index(1, 1, 1)] += glm::vec3(0.0f, 0.0f, 512.0f);
  const std::vector<glm::vec3> in = {{0, 0, 0}};
  const auto out = evaluate(deform::bind_lattice(lattice, in), lattice.control_points(), in);
  CHECK(out[0].z == doctest::Approx(27.0f).epsilon(1e-6));
  CHECK(lattice.evaluate({0.5f, 0.5f, 0.5f}).z == doctest::Approx(27.0f).epsilon(1e-6));
}

TEST_CASE("a rest lattice is the identity to 1e-6 for every degree") {
  std::mt19937 rng(11);
  for (int d = 1; d <= deform::max_bezier_degree; ++d) {
    for (const glm::ivec3 degree : {glm::ivec3(d), glm::ivec3(d, 1 + d % 3, 1 + (d * 7) % 16)}) {
      const LatticeFrame frame = random_frame(rng);
      const BezierLattice lattice(frame, degree);
      const std::vector<glm::vec3> in = points_inside(frame, rng, 200);
      std::vector<glm::vec3> normals(in.size());
      for (glm::vec3& n : normals) n = glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(0.0f, 0.0f, 1e-3f));
      const std::vector<glm::vec3> normals_in = normals;
      const auto out = evaluate(deform::bind_lattice(lattice, in), lattice.control_points(), in, &normals);
      double worst = 0.0, worst_normal = 0.0;
      for (std::size_t i = 0; i < in.size(); ++i) {
        worst = std::max(worst, dist(out[i], in[i]));
        worst = std::max(worst, dist(lattice.evaluate(frame.to_lattice(in[i])), in[i]));
        worst_normal = std::max(worst_normal, dist(normals[i], normals_in[i]));
      }
      INFO("degree " << degree.x << "," << degree.y << "," << degree.z);
      CHECK(worst < 1e-6 * 8);  // coordinates up to ~8: 1e-6 relative
      // Float Bernstein derivatives up to degree 16 through a cofactor: about 1e-5; 2e-5 leaves room for another
      // compiler's rounding (Clang 14 reaches 1.1e-5 where GCC 12 stays under 1e-5).
      CHECK(worst_normal < 2e-5);
    }
  }
}

// A lattice collapsed to a point or onto a line has a Jacobian of rank 0 or 1: no normal to give (its cofactor is 0),
// so every kernel copy keeps each input normal, bit for bit, while the positions follow the collapse.
TEST_CASE("a collapsed lattice keeps the input normals on every kernel copy") {
  std::mt19937 rng(12);
  for (int d = 1; d <= deform::max_bezier_degree; d += 2) {
    const LatticeFrame frame = random_frame(rng);
    BezierLattice lattice(frame, glm::ivec3(d));
    const std::vector<glm::vec3> in = points_inside(frame, rng, 100);
    const deform::LatticeBinding binding = deform::bind_lattice(lattice, in);
    const glm::vec3 point = uniform3(rng, -2.0f, 2.0f), along = uniform3(rng, -1.0f, 1.0f);
    for (const bool onto_line : {false, true}) {
      collapse(lattice.control_points(), point, along, onto_line);
      std::vector<glm::vec3> normals = random_normals(rng, in.size());
      const std::vector<glm::vec3> normals_in = normals;
      const auto out = evaluate(binding, lattice.control_points(), in, &normals);
      bool kept = true, on_the_collapse = true;
      for (std::size_t i = 0; i < in.size(); ++i) {
        kept = kept && normals[i] == normals_in[i];
        const glm::vec3 offset = out[i] - point;
        const float off_line =
            onto_line ? glm::length(glm::cross(offset, along)) / glm::length(along) : glm::length(offset);
        on_the_collapse = on_the_collapse && off_line < 1e-4f;
      }
      INFO("degree " << d << std::string(onto_line ? ", onto a line" : ", to a point"));
      CHECK(kept);
      CHECK(on_the_collapse);
    }
  }
}

TEST_CASE("affine precision: an affine map of the control points maps the vertices the same way, every degree") {
  std::mt19937 rng(12);
  for (int d = 1; d <= deform::max_bezier_degree; ++d) {
    const LatticeFrame frame = random_frame(rng);
    BezierLattice lattice(frame, glm::ivec3(d, 1 + (d + 1) % 4, d));
    glm::mat4 affine(1.0f);
    for (int c = 0; c < 3; ++c) affine[c] = glm::vec4(uniform3(rng, -1.5f, 1.5f), 0.0f);
    affine[3] = glm::vec4(uniform3(rng, -3.0f, 3.0f), 1.0f);
    for (glm::vec3& p : lattice.control_points()) p = glm::vec3(affine * glm::vec4(p, 1.0f));
    const std::vector<glm::vec3> in = points_inside(frame, rng, 100);
    const auto out =
        evaluate(deform::bind_lattice(BezierLattice(frame, lattice.degree()), in), lattice.control_points(), in);
    for (std::size_t i = 0; i < in.size(); ++i) {
      const glm::vec3 expected(affine * glm::vec4(in[i], 1.0f));
      INFO("degree " << d << " vertex " << i);
      CHECK(dist(out[i], expected) < 1e-5 * (1.0 + glm::length(expected)));
    }
  }
}

TEST_CASE("optimised kernel = pow/binomial reference to 1e-5 over thousands of random lattices and points") {
  std::mt19937 rng(13);
  int compared = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const bool high = trial % 10 == 0;
    const glm::ivec3 degree{1 + static_cast<int>(rng() % (high ? 16 : 6)), 1 + static_cast<int>(rng() % 6),
                            1 + static_cast<int>(rng() % (high ? 12 : 6))};
    const LatticeFrame frame = random_frame(rng);
    BezierLattice lattice(frame, degree);
    for (glm::vec3& p : lattice.control_points()) p += uniform3(rng, -0.3f, 0.3f);
    // 1..40 vertices so that partial blocks are covered; some exactly on the border.
    std::vector<glm::vec3> uvws;
    const std::size_t count = 1 + rng() % 40;
    for (std::size_t i = 0; i < count; ++i) {
      glm::vec3 uvw = uniform3(rng, 0.0f, 1.0f);
      if (rng() % 8 == 0) uvw[static_cast<int>(rng() % 3)] = static_cast<float>(rng() % 2);
      uvws.push_back(uvw);
    }
    std::vector<glm::vec3> in;
    for (const glm::vec3& uvw : uvws) in.push_back(frame.to_world(uvw));
    const auto binding = deform::bind_lattice(lattice, in);
    std::vector<glm::vec3> normals(in.size());
    for (glm::vec3& n : normals) n = glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(1e-3f, 0.0f, 0.0f));
    const std::vector<glm::vec3> normals_in = normals;
    const auto out = evaluate(binding, lattice.control_points(), in, &normals);
    const auto positions_only = evaluate(binding, lattice.control_points(), in);
    const glm::dmat3 axes(glm::dvec3(frame.u_axis), glm::dvec3(frame.v_axis), glm::dvec3(frame.w_axis));
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (!glm::all(glm::greaterThanEqual(frame.to_lattice(in[i]), glm::vec3(0.0f))) ||
          !glm::all(glm::lessThanEqual(frame.to_lattice(in[i]), glm::vec3(1.0f))))
        continue;  // rounding put a border vertex just outside: it is (correctly) not bound
      const glm::dvec3 uvw(frame.to_lattice(in[i]));
      const glm::dvec3 ref = lattice_reference::bezier(lattice.control_points(), degree, uvw);
      // The world Jacobian is ∂Q/∂(u,v,w) · M⁻¹.
      const glm::dmat3 jac =
          lattice_reference::bezier_jacobian(lattice.control_points(), degree, uvw) * glm::inverse(axes);
      const glm::dvec3 ref_normal = lattice_reference::transform_normal(jac, glm::dvec3(normals_in[i]));
      INFO("trial " << trial << " degree " << degree.x << "," << degree.y << "," << degree.z << " vertex " << i);
      CHECK(dist(out[i], ref) < 1e-5 * (1.0 + glm::length(ref)));
      CHECK(positions_only[i] == out[i]);
      CHECK(dist(lattice.evaluate(glm::vec3(uvw)), ref) < 1e-5 * (1.0 + glm::length(ref)));
      CHECK(dist(normals[i], ref_normal) < 1e-4);
      ++compared;
    }
  }
  CHECK(compared > 20000);
}

// The kernels evaluate Bézier lattices of degree 1 to 3 (equal on the three axes) with the rows along u in power
// form, whose rounding grows with the control points' differences rather than with their size: held here to the same
// references far from the origin (up to 100 units, where a float step is 8e-6) and bent hard (every point moved up to
// the lattice's own size), with normals and without, over thousands of lattices.
TEST_CASE("degrees 1 to 3 (rows in power form) = reference, far from the origin and bent hard, every copy") {
  std::mt19937 rng(29);
  int compared = 0;
  double worst_position = 0.0, worst_normal = 0.0;
  for (int trial = 0; trial < 1200; ++trial) {
    const int d = 1 + trial % 3;
    LatticeFrame frame = random_frame(rng);
    frame.origin += uniform3(rng, -100.0f, 100.0f) * float(trial % 2);  // odd trials: far
    BezierLattice lattice(frame, glm::ivec3(d));
    const float bend = uniform(rng, 0.0f, 1.0f) * glm::length(frame.u_axis);
    for (glm::vec3& p : lattice.control_points()) p += uniform3(rng, -bend, bend);
    std::vector<glm::vec3> in;
    const std::size_t count = 1 + rng() % 40;
    for (std::size_t i = 0; i < count; ++i) in.push_back(frame.to_world(uniform3(rng, 0.001f, 0.999f)));
    const auto binding = deform::bind_lattice(lattice, in);
    std::vector<glm::vec3> normals = random_normals(rng, in.size());
    const std::vector<glm::vec3> normals_in = normals;
    // Normals near the origin only: far from it the derivatives are differences of coordinates ~100, and the
    // Bernstein sums and the power form lose digits there alike (and the copies differ by their rounding).
    const bool far = trial % 2 == 1;
    const auto out = evaluate(binding, lattice.control_points(), in, far ? nullptr : &normals);
    const glm::dmat3 axes(glm::dvec3(frame.u_axis), glm::dvec3(frame.v_axis), glm::dvec3(frame.w_axis));
    for (std::size_t i = 0; i < in.size(); ++i) {
      const glm::dvec3 uvw(frame.to_lattice(in[i]));
      if (binding.vertices.end() == std::find(binding.vertices.begin(), binding.vertices.end(), std::uint32_t(i)))
        continue;  // not bound (rounding put it outside)
      const glm::dvec3 ref = lattice_reference::bezier(lattice.control_points(), glm::ivec3(d), uvw);
      const glm::dmat3 jac =
          lattice_reference::bezier_jacobian(lattice.control_points(), glm::ivec3(d), uvw) * glm::inverse(axes);
      const glm::dvec3 ref_normal = lattice_reference::transform_normal(jac, glm::dvec3(normals_in[i]));
      INFO("trial " << trial << " degree " << d << " vertex " << i);
      const double position_error = dist(out[i], ref) / (1.0 + glm::length(ref));
      CHECK(position_error < 1e-5);
      // A normal is as precise as the Jacobian's smallest singular value allows: the nearly folded are skipped.
      if (!far &&
          glm::abs(glm::determinant(jac)) > 1e-3 * glm::length(jac[0]) * glm::length(jac[1]) * glm::length(jac[2])) {
        CHECK(dist(normals[i], ref_normal) < 1e-4);
        worst_normal = std::max(worst_normal, dist(normals[i], ref_normal));
      }
      worst_position = std::max(worst_position, position_error);
      ++compared;
    }
  }
  MESSAGE("worst position error " << worst_position << " (relative), worst normal " << worst_normal);
  CHECK(compared > 20000);
}

TEST_CASE("the Jacobian agrees with finite differences, and so do the deformed normals") {
  std::mt19937 rng(14);
  for (int trial = 0; trial < 200; ++trial) {
    const glm::ivec3 degree{1 + static_cast<int>(rng() % 5), 1 + static_cast<int>(rng() % 5),
                            1 + static_cast<int>(rng() % 5)};
    const LatticeFrame frame = random_frame(rng);
    BezierLattice lattice(frame, degree);
    for (glm::vec3& p : lattice.control_points()) p += uniform3(rng, -0.2f, 0.2f);
    const glm::vec3 uvw = uniform3(rng, 0.1f, 0.9f);
    const float h = 1e-2f;
    const glm::mat3 jac = lattice.jacobian(uvw);
    for (int a = 0; a < 3; ++a) {
      glm::vec3 step(0.0f);
      step[a] = h;
      const glm::vec3 fd = (lattice.evaluate(uvw + step) - lattice.evaluate(uvw - step)) / (2.0f * h);
      CHECK(dist(jac[a], fd) < 2e-3 * (1.0 + glm::length(fd)));
    }
    // A surface through the point with normal n: deform two tangents by finite differences of the whole map.
    const glm::vec3 x = frame.to_world(uvw);
    const glm::vec3 n = glm::normalize(uniform3(rng, -1.0f, 1.0f) + glm::vec3(0.0f, 1e-3f, 0.0f));
    const glm::vec3 t1 = glm::normalize(glm::cross(n, glm::vec3(0.3f, 0.5f, 0.81f)));
    const glm::vec3 t2 = glm::cross(n, t1);
    const float e = 1e-3f;
    auto map = [&](glm::vec3 p) { return lattice.evaluate(frame.to_lattice(p)); };
    const glm::vec3 d1 = map(x + e * t1) - map(x - e * t1), d2 = map(x + e * t2) - map(x - e * t2);
    const glm::vec3 fd_normal = glm::normalize(glm::cross(d1, d2));
    std::vector<glm::vec3> normals = {n};
    const std::vector<glm::vec3> in = {x};
    evaluate(deform::bind_lattice(BezierLattice(frame, degree), in), lattice.control_points(), in, &normals);
    INFO("trial " << trial);
    CHECK(dist(normals[0], fd_normal) < 2e-3);
  }
}

TEST_CASE("weights: the field added by each point's weight and the normals blended alike, = reference, every copy") {
  // The displacement form DeformerHierarchy::apply uses: position += w·Q(uvw), normal = normalize(n + w·(n' − n))
  // with n' the deformed normal of n carried into the binding's space by normals_in_to_binding; Bézier and B-spline,
  // every kernel copy, against the double references; a collapsed field keeps the normals. Points outside the box are
  // not touched.
  std::mt19937 rng(24);
  std::size_t compared = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const bool bspline = trial % 3 == 2;
    const LatticeFrame frame = random_frame(rng);
    const glm::ivec3 counts = bspline ? glm::ivec3{4 + int(rng() % 4), 4 + int(rng() % 4), 4 + int(rng() % 4)}
                                      : glm::ivec3{2 + int(rng() % 5), 2 + int(rng() % 5), 2 + int(rng() % 5)};
    BezierLattice bezier(frame, counts - 1);
    deform::BsplineLattice bspline_lattice(frame, bspline ? counts : glm::ivec3(4));
    const std::span<glm::vec3> control = bspline ? bspline_lattice.control_points() : bezier.control_points();
    for (glm::vec3& p : control) p = uniform3(rng, -0.3f, 0.3f);  // a displacement field: small vectors
    // Some fields collapsed to a point or a line: no normal to give, each point keeps its own.
    const bool collapsed = trial % 20 == 7;
    if (collapsed) {
      const glm::vec3 point = uniform3(rng, -1.0f, 1.0f);
      collapse(control, point, uniform3(rng, -0.1f, 0.1f), trial % 40 == 7);
    }
    std::vector<glm::vec3> in = points_inside(frame, rng, 1 + rng() % 40);
    in.push_back(frame.to_world(glm::vec3(1.5f, 0.5f, 0.5f)));  // outside: not bound
    const deform::LatticeBinding binding = bspline ? deform::bind_lattice(BsplineLattice(frame, counts), in)
                                                   : deform::bind_lattice(BezierLattice(frame, counts - 1), in);
    std::vector<float> point_weight(in.size());
    for (float& w : point_weight) w = rng() % 5 == 0 ? float(rng() % 2) : uniform(rng, 0.0f, 1.0f);
    std::vector<float> lane_weight(binding.vertices.size(), 0.0f);
    for (std::size_t lane = 0; lane < binding.vertices.size(); ++lane)
      if (binding.vertices[lane] != deform::LatticeBinding::no_vertex)
        lane_weight[lane] = point_weight[binding.vertices[lane]];
    // Half the trials carry the normals by a rotation and a scale first, as a skinned bone's would be.
    const glm::vec3 axis = glm::normalize(uniform3(rng, 0.1f, 1.0f));
    glm::mat3 to_binding(1.0f);
    if (trial % 2) {
      const float turn = uniform(rng, -3.0f, 3.0f);
      to_binding = glm::mat3(glm::rotate(glm::mat4(1.0f), turn, axis)) * uniform(rng, 0.5f, 2.0f);
    }
    const std::vector<glm::vec3> normals_in = random_normals(rng, in.size());

    const glm::dmat3 axes(glm::dvec3(frame.u_axis), glm::dvec3(frame.v_axis), glm::dvec3(frame.w_axis));
    for (const deform::Isa isa :
         {deform::Isa::portable, deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128}) {
      if (!deform::isa_available(isa)) continue;
      std::vector<glm::vec3> positions = in, normals = normals_in, normals_only = normals_in;
      deform::LatticeEvaluateJob job;
      job.binding = &binding;
      job.control_points = control;
      job.positions = positions;
      job.normals_in = normals;  // in place, as the hierarchy runs it
      job.normals_out = normals;
      job.weights = lane_weight;
      job.normals_in_to_binding = to_binding;
      job.isa = isa;
      REQUIRE(job.validate());
      REQUIRE(job.run());
      job.positions = {};  // normals only: the same normals
      job.normals_in = normals_only;
      job.normals_out = normals_only;
      REQUIRE(job.run());
      for (std::size_t i = 0; i < in.size(); ++i) {
        INFO("trial " << trial << " isa " << std::string(deform::isa_name(isa)) << " point " << i);
        CHECK(normals_only[i] == normals[i]);
        const glm::vec3 uvw = frame.to_lattice(in[i]);
        if (glm::any(glm::lessThan(uvw, glm::vec3(0.0f))) || glm::any(glm::greaterThan(uvw, glm::vec3(1.0f)))) {
          CHECK(positions[i] == in[i]);
          CHECK(normals[i] == normals_in[i]);
          continue;
        }
        const double w = point_weight[i];
        const glm::dvec3 q = bspline ? lattice_reference::bspline(control, counts, glm::dvec3(uvw))
                                     : lattice_reference::bezier(control, counts - 1, glm::dvec3(uvw));
        CHECK(dist(positions[i], glm::dvec3(in[i]) + w * q) < 1e-5 * (1.0 + glm::length(glm::dvec3(in[i]))));
        if (collapsed) {
          CHECK(glm::length(normals[i] - normals_in[i]) < 1e-6f);
          continue;
        }
        const glm::dmat3 jac = (bspline ? lattice_reference::bspline_jacobian(control, counts, glm::dvec3(uvw))
                                        : lattice_reference::bezier_jacobian(control, counts - 1, glm::dvec3(uvw))) *
                               glm::inverse(axes);
        const glm::dvec3 n(normals_in[i]);
        const glm::dvec3 deformed = lattice_reference::transform_normal(jac, glm::dmat3(to_binding) * n);
        const glm::dvec3 blended = n + w * (deformed - n);
        if (glm::length(blended) < 0.1) continue;  // nearly opposite normals half blended: no direction to compare
        CHECK(dist(normals[i], glm::normalize(blended)) < 1e-4 / glm::length(blended));
        ++compared;
      }
    }
  }
  CHECK(compared > 10000);
}

TEST_CASE("invalid Bézier lattices are errors with context") {
  const LatticeFrame unit = LatticeFrame::axis_aligned({0, 0, 0}, {1, 1, 1});
  CHECK_THROWS_AS(BezierLattice(LatticeFrame::axis_aligned({0, 0, 0}, {1, 0, 1})), deform::Error);
  CHECK_THROWS_AS(BezierLattice(LatticeFrame::axis_aligned({0, 0, 0}, {1, -1, 1})), deform::Error);
  CHECK_THROWS_AS(BezierLattice(LatticeFrame::axis_aligned({0, NAN, 0}, {1, 1, 1})), deform::Error);
  CHECK_THROWS_AS(BezierLattice(LatticeFrame::axis_aligned({0, 0, 0}, {1, INFINITY, 1})), deform::Error);
  LatticeFrame flat = unit;
  flat.w_axis = flat.u_axis + flat.v_axis;
  CHECK_THROWS_AS(BezierLattice{flat}, deform::Error);
  LatticeFrame left_handed = unit;
  left_handed.w_axis = -left_handed.w_axis;
  CHECK_THROWS_AS(BezierLattice{left_handed}, deform::Error);
  try {
    BezierLattice bad(unit, glm::ivec3(3, 0, 3), "arm.json");
    FAIL("degree 0 accepted");
  } catch (const deform::Error& e) {
    CHECK(e.file() == "arm.json");
    CHECK(e.element() == "degree m");
  }
  CHECK_THROWS_AS(BezierLattice(unit, glm::ivec3(3, 3, deform::max_bezier_degree + 1)), deform::Error);
  CHECK_NOTHROW(BezierLattice(unit, glm::ivec3(deform::max_bezier_degree, 1, 2)));
  // A candidate index out of range and a non-finite position are bind-time errors.
  const BezierLattice lattice(unit);
  const std::vector<glm::vec3> points = {{0.5f, 0.5f, 0.5f}, {NAN, 0, 0}};
  const std::vector<std::uint32_t> out_of_range = {0, 2};
  CHECK_THROWS_AS(deform::bind_lattice(lattice, points, out_of_range), deform::Error);
  CHECK_THROWS_AS(deform::bind_lattice(lattice, points), deform::Error);
}

TEST_CASE("LatticeEvaluateJob::validate rejects what it cannot run, says why, and run() writes nothing") {
  const auto reason = [](deform::Status status) { return std::string(status.reason()); };
  const BezierLattice lattice(LatticeFrame::axis_aligned({0, 0, 0}, {1, 1, 1}));
  const std::vector<glm::vec3> in = {{0.5f, 0.5f, 0.5f}, {0.1f, 0.2f, 0.3f}};
  const auto binding = deform::bind_lattice(lattice, in);
  std::vector<glm::vec3> out(2, glm::vec3(7.0f)), normals(2, glm::vec3(0, 0, 1)), small(1);
  deform::LatticeEvaluateJob job;
  CHECK(reason(job.validate()) == "no binding");
  CHECK(job.count() == 0);
  job.binding = &binding;
  job.control_points = lattice.control_points();
  job.positions = out;
  CHECK(job.validate());
  CHECK(job.count() == 1);  // one block of 16 lanes
  job.positions = small;
  CHECK(reason(job.run()) == "positions too short");
  CHECK(small[0] == glm::vec3(0.0f));
  job.positions = out;
  const std::vector<glm::vec3> too_few(lattice.control_points().begin(), lattice.control_points().end() - 1);
  job.control_points = too_few;
  CHECK(reason(job.validate()) == "control point count differs from the binding");
  job.control_points = lattice.control_points();
  job.normals_in = normals;  // normals in without normals out
  CHECK(reason(job.validate()) == "normals_in and normals_out: both or neither");
  job.normals_out = normals;
  CHECK(job.validate());
  job.normals_out = small;
  CHECK(reason(job.validate()) == "normals too short");
  job.positions = {};  // positions may be left out when normals are asked for
  job.normals_out = normals;
  CHECK(job.validate());
  job.positions = out;
  const std::vector<float> weights(16, 1.0f), short_weights(15, 1.0f);
  job.weights = short_weights;
  CHECK(reason(job.validate()) == "weights: one per binding lane");
  job.weights = weights;
  CHECK(job.validate());
  job.weights = {};
  job.normals_in = {};
  job.normals_out = {};
  job.positions = {};
  CHECK(reason(job.validate()) == "positions too short");
  job.positions = out;
  for (const deform::Isa isa : {deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128})
    if (!deform::isa_available(isa)) {  // a forced copy this CPU lacks is refused, never run
      job.isa = isa;
      CHECK(reason(job.validate()) == "instruction set not available");
      CHECK_FALSE(job.run());
      job.isa = deform::Isa::automatic;
    }
  CHECK(reason(job.run(0, 2)) == "range outside the job");
  CHECK(reason(job.run(1, 0)) == "range outside the job");
  CHECK(job.run(1, 1));
  CHECK(out[0] == glm::vec3(7.0f));

  // A binding altered after bind_lattice: run() checks its sizes and point counts (O(1)), validate() its contents.
  deform::LatticeBinding broken = binding;
  job.binding = &broken;
  broken.u.pop_back();
  CHECK(reason(job.run()) == "binding arrays differ in size");
  broken = binding, broken.point_counts = glm::ivec3(deform::max_bezier_degree + 2, 2, 2);
  CHECK(reason(job.run()) == "binding point counts invalid");
  broken = binding, broken.vertices[0] = 5;
  CHECK(reason(job.validate()) == "binding vertex out of range");
  broken = binding, broken.w[1] = NAN;
  CHECK(reason(job.validate()) == "binding parameter is not finite");
  CHECK(out[0] == glm::vec3(7.0f));

  // A B-spline binding needs B-spline-sized control points, and cells inside the lattice.
  const deform::BsplineLattice bspline(LatticeFrame::axis_aligned({0, 0, 0}, {1, 1, 1}), glm::ivec3(5));
  const auto bspline_binding = deform::bind_lattice(bspline, in);
  job.binding = &bspline_binding;
  CHECK(reason(job.validate()) == "control point count differs from the binding");
  job.control_points = bspline.control_points();
  CHECK(job.run());
  broken = bspline_binding, broken.block_first_point[0] = 2;  // i = 2: the cell's 4 points would run past i = 4
  job.binding = &broken;
  CHECK(reason(job.validate()) == "binding cell out of range");
}
