// Binding: vertex selection, untouched vertices, bone-bound lattices (thesis eq. 42), the seam with skinning, threads.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/io/lattice_json.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/parallel.hpp"
#include "deform/runtime/skeleton.hpp"
#include "runtime/lattice_test_util.hpp"

using namespace lattice_test;
using deform::BezierLattice;
using deform::BsplineLattice;
using deform::LatticeFrame;

TEST_CASE("vertices outside the box or outside the chosen set are bit-identical") {
  std::mt19937 rng(31);
  const LatticeFrame frame = random_frame(rng);
  BezierLattice bezier(frame);
  BsplineLattice bspline(frame, glm::ivec3(7, 5, 6));
  for (glm::vec3& p : bezier.control_points()) p += uniform3(rng, -0.5f, 0.5f);
  for (glm::vec3& p : bspline.control_points()) p += uniform3(rng, -0.5f, 0.5f);
  std::vector<glm::vec3> in;
  for (int i = 0; i < 3000; ++i) in.push_back(frame.to_world(uniform3(rng, -0.5f, 1.5f)));
  std::vector<std::uint32_t> chosen;
  for (std::uint32_t i = 0; i < in.size(); i += 3) chosen.push_back(i);
  for (int kind = 0; kind < 2; ++kind) {
    const auto binding = kind == 0 ? deform::bind_lattice(BezierLattice(frame), in, chosen)
                                   : deform::bind_lattice(BsplineLattice(frame, glm::ivec3(7, 5, 6)), in, chosen);
    const auto points = kind == 0 ? bezier.control_points() : bspline.control_points();
    std::vector<glm::vec3> normals(in.size(), glm::vec3(0.0f, 0.6f, 0.8f));
    const auto out = evaluate(binding, points, in, &normals);
    std::size_t moved = 0, expected_moved = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      const glm::vec3 uvw = frame.to_lattice(in[i]);
      const bool inside =
          glm::all(glm::greaterThanEqual(uvw, glm::vec3(0.0f))) && glm::all(glm::lessThanEqual(uvw, glm::vec3(1.0f)));
      if (inside && i % 3 == 0) {
        ++expected_moved;
        moved += out[i] != in[i];
      } else {
        CHECK(std::memcmp(&out[i], &in[i], sizeof(glm::vec3)) == 0);
        CHECK(normals[i] == glm::vec3(0.0f, 0.6f, 0.8f));
      }
    }
    CHECK(binding.vertex_count == expected_moved);
    CHECK(expected_moved > 50);
    CHECK(moved == expected_moved);
  }
}

TEST_CASE("selection by skin weight, by box, and vertex list files") {
  deform::SkinWeights weights;
  weights.bones = {{0, 1, 0, 0}, {1, 0, 0, 0}, {2, 1, 0, 0}, {0, 0, 0, 0}};
  weights.weights = {{0.7f, 0.3f, 0, 0}, {0.9f, 0.1f, 0, 0}, {0.5f, 0.5f, 0, 0}, {1, 0, 0, 0}};
  CHECK(deform::select_by_weight(weights, 1, 0.25f) == std::vector<std::uint32_t>{0, 1, 2});
  CHECK(deform::select_by_weight(weights, 1, 0.4f) == std::vector<std::uint32_t>{1, 2});
  CHECK(deform::select_by_weight(weights, 0, 0.5f) == std::vector<std::uint32_t>{0, 3});
  CHECK(deform::select_by_weight(weights, 7, 0.0f).empty());

  const std::vector<glm::vec3> points = {{0.5f, 0.5f, 0.5f}, {1.5f, 0.5f, 0.5f}, {1, 1, 1}, {0, 0, -1e-6f}};
  CHECK(deform::select_inside(LatticeFrame::axis_aligned({0, 0, 0}, {1, 1, 1}), points) ==
        std::vector<std::uint32_t>{0, 2});

  CHECK(deform::parse_vertex_list("# arm\n3 1\n\t7 # wrist\n0\n", 8) == std::vector<std::uint32_t>{3, 1, 7, 0});
  CHECK(deform::parse_vertex_list("", 8).empty());
  auto error_of = [](std::string_view text) -> std::string {
    try {
      deform::parse_vertex_list(text, 8, "arm.txt");
    } catch (const deform::Error& e) {
      return e.what();
    }
    return "";
  };
  CHECK(error_of("1 2\n8\n") == "arm.txt: line 2: entry 2: vertex 8 is out of range (8 vertices)");
  CHECK(error_of("1\n\n1\n") == "arm.txt: line 3: entry 1: vertex 1 is listed twice");
  CHECK(error_of("-1") == "arm.txt: line 1: entry 0: '-1' is not a vertex index (0-based)");
  CHECK(error_of("2 x3") == "arm.txt: line 1: entry 1: 'x3' is not a vertex index (0-based)");
  CHECK(error_of("99999999999999999999999") != "");
}

namespace {

// A bone's bind and current world matrices, and a lattice living in its frame along +x.
const glm::mat4 bind_world =
    glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(1.0f, 0.5f, 0.0f)), 0.5f, glm::vec3(0, 0, 1));

std::vector<glm::vec3> around_bone(std::mt19937& rng, std::size_t count) {
  std::vector<glm::vec3> out;  // bind-pose world positions, bone-local x in [-0.5, 2.5]
  for (std::size_t i = 0; i < count; ++i)
    out.push_back(glm::vec3(
        bind_world * glm::vec4{uniform(rng, -0.5f, 2.5f), uniform(rng, -0.6f, 0.6f), uniform(rng, -0.6f, 0.6f), 1.0f}));
  return out;
}

std::vector<glm::vec3> carried(std::span<const glm::vec3> points, const glm::mat4& m) {
  std::vector<glm::vec3> out(points.size());
  REQUIRE(deform::transform_points(points, m, out));
  return out;
}

}  // namespace

TEST_CASE("a bone-bound lattice is the identity at rest and follows the bone (eq. 42)") {
  std::mt19937 rng(32);
  BezierLattice lattice(LatticeFrame::axis_aligned({0.0f, -0.5f, -0.5f}, {2.0f, 1.0f, 1.0f}));
  const std::vector<glm::vec3> bind_positions = around_bone(rng, 500);
  const auto binding = deform::bind_lattice(lattice, bind_positions, glm::inverse(bind_world));
  CHECK(binding.vertex_count > 200);
  CHECK(binding.vertex_count < 500);

  // Rest: carried into the bind frame, the lattice gives the bind positions back, normals included.
  std::vector<glm::vec3> normals(bind_positions.size(), glm::normalize(glm::vec3(0.2f, -0.4f, 0.9f)));
  const auto rest = evaluate(binding, carried(lattice.control_points(), bind_world), bind_positions, &normals);
  for (std::size_t i = 0; i < rest.size(); ++i) {
    CHECK(dist(rest[i], bind_positions[i]) < 1e-5);
    CHECK(dist(normals[i], glm::normalize(glm::vec3(0.2f, -0.4f, 0.9f))) < 1e-5);
  }

  // Stretch the lattice along the bone, then pose the bone two ways: the deformation moves with it.
  for (int k = 0; k <= 3; ++k)
    for (int j = 0; j <= 3; ++j) lattice.control_points()[lattice.index(3, j, k)].x += 0.8f;
  lattice.control_points()[lattice.index(1, 2, 1)] += glm::vec3(0.1f, 0.3f, -0.2f);
  const glm::mat4 pose_a = glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0, 2, 0)), 1.4f, glm::vec3(0, 1, 1));
  const glm::mat4 pose_b = glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(-3, 0, 1)), -2.0f, glm::vec3(1, 0, 0));
  const auto at_a = evaluate(binding, carried(lattice.control_points(), pose_a), bind_positions);
  const auto at_b = evaluate(binding, carried(lattice.control_points(), pose_b), bind_positions);
  const auto in_bind = evaluate(binding, carried(lattice.control_points(), bind_world), bind_positions);
  std::size_t deformed = 0;
  for (std::size_t i = 0; i < bind_positions.size(); ++i) {
    if (binding.vertex_count && at_a[i] == bind_positions[i]) continue;  // not bound
    ++deformed;
    // In the bone's frame the result is the same whatever the pose...
    const glm::vec3 local_a(glm::inverse(pose_a) * glm::vec4(at_a[i], 1.0f));
    const glm::vec3 local_b(glm::inverse(pose_b) * glm::vec4(at_b[i], 1.0f));
    CHECK(dist(local_a, local_b) < 1e-5);
    // ...and equals deforming in bind space then skinning rigidly to the bone (T_W · T_B⁻¹).
    const glm::vec3 skinned(pose_a * glm::inverse(bind_world) * glm::vec4(in_bind[i], 1.0f));
    CHECK(dist(skinned, at_a[i]) < 1e-5);
    // The stretch is along the bone: bone-local x grows, by at most the 0.8 of the moved face.
    const glm::vec3 before(glm::inverse(bind_world) * glm::vec4(bind_positions[i], 1.0f));
    CHECK(local_a.x >= before.x - 0.05f);
  }
  CHECK(deformed == binding.vertex_count);
}

TEST_CASE("lattice in bind space, then skinning: no seam at the lattice border") {
  // Two bones along +x: the root at the origin, the child at x = 2, bent 60° in the pose. Vertices along a line
  // through the child's lattice [2.5, 3.5] × [-0.5, 0.5]², with weights blending around the joint.
  const glm::mat4 bind[2] = {glm::mat4(1.0f), glm::translate(glm::mat4(1.0f), glm::vec3(2, 0, 0))};
  const glm::mat4 world[2] = {
      glm::rotate(glm::mat4(1.0f), 0.2f, glm::vec3(0, 1, 0)),
      glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(2, 0, 0)), 1.05f, glm::vec3(0, 0, 1))};
  std::vector<glm::vec3> positions;
  std::vector<float> child_weight;
  const float eps = 1e-4f;
  for (const float x : {2.5f - eps, 2.5f + eps, 3.0f, 3.5f - eps, 3.5f + eps})
    for (const float y : {0.1f, 0.5f - eps, 0.5f + eps}) {
      positions.push_back({x, y, 0.2f});
      child_weight.push_back(glm::clamp((x - 1.5f) / 1.5f, 0.0f, 1.0f));
    }
  auto pipeline = [&](const BezierLattice& lattice) {
    const auto binding =
        deform::bind_lattice(BezierLattice(lattice.frame(), lattice.degree()), positions, glm::inverse(bind[1]));
    const auto deformed = evaluate(binding, carried(lattice.control_points(), bind[1]), positions);
    std::vector<glm::vec3> skinned;  // reference linear blend skinning with T_C = T_W · T_B⁻¹
    for (std::size_t i = 0; i < deformed.size(); ++i) {
      const glm::mat4 blend = (1.0f - child_weight[i]) * (world[0] * glm::inverse(bind[0])) +
                              child_weight[i] * (world[1] * glm::inverse(bind[1]));
      skinned.push_back(glm::vec3(blend * glm::vec4(deformed[i], 1.0f)));
    }
    return skinned;
  };
  // The largest jump between the two vertices of a pair straddling a border (they are 2·eps apart at bind).
  auto largest_jump = [&](const std::vector<glm::vec3>& out) {
    double worst = 0.0;
    for (std::size_t a = 0; a < positions.size(); ++a)
      for (std::size_t b = a + 1; b < positions.size(); ++b)
        if (dist(positions[a], positions[b]) < 3.0 * eps) worst = std::max(worst, dist(out[a], out[b]));
    return worst;
  };

  BezierLattice lattice(LatticeFrame::axis_aligned({0.5f, -0.5f, -0.5f}, {1.0f, 1.0f, 1.0f}));
  // Interior control points only (i, j, k in 1..2): a strong bulge.
  for (int k = 1; k <= 2; ++k)
    for (int j = 1; j <= 2; ++j)
      for (int i = 1; i <= 2; ++i) lattice.control_points()[lattice.index(i, j, k)] += glm::vec3(0.3f, 0.6f, -0.4f);
  const auto smooth = pipeline(lattice);
  CHECK(dist(smooth[6], pipeline(BezierLattice(lattice.frame()))[6]) > 0.05);  // the centre did bulge
  CHECK(largest_jump(smooth) < 10.0 * eps);

  // Moving a border control point instead opens a seam, which the same measure sees.
  BezierLattice torn(lattice.frame());
  torn.control_points()[torn.index(3, 3, 2)] += glm::vec3(0.0f, 0.6f, 0.0f);
  CHECK(largest_jump(pipeline(torn)) > 100.0 * eps);
}

TEST_CASE("run_parallel and any split into block ranges give the single-threaded result") {
  std::mt19937 rng(33);
  const LatticeFrame frame = random_frame(rng);
  BsplineLattice bspline(frame, glm::ivec3(9, 6, 7));
  BezierLattice bezier(frame, glm::ivec3(4, 2, 5));
  for (glm::vec3& p : bspline.control_points()) p += uniform3(rng, -0.3f, 0.3f);
  for (glm::vec3& p : bezier.control_points()) p += uniform3(rng, -0.3f, 0.3f);
  const std::vector<glm::vec3> in = points_inside(frame, rng, 20000);
  deform::ThreadPool pool(3);
  for (int kind = 0; kind < 2; ++kind) {
    const auto binding = kind == 0 ? deform::bind_lattice(bezier, in) : deform::bind_lattice(bspline, in);
    const auto points = kind == 0 ? bezier.control_points() : bspline.control_points();
    std::vector<glm::vec3> normals(in.size(), glm::vec3(1, 0, 0)), parallel_positions = in, parallel_normals = normals;
    const auto serial = evaluate(binding, points, in, &normals);
    deform::LatticeEvaluateJob job;
    job.binding = &binding;
    job.control_points = points;
    job.positions = parallel_positions;
    job.normals_in = parallel_normals;
    job.normals_out = parallel_normals;
    REQUIRE(deform::run_parallel(job, pool));
    CHECK(parallel_positions == serial);
    CHECK(parallel_normals == normals);
    // Random block ranges, every block once, on every kernel copy: each gives that copy's run() bits.
    for (const deform::Isa isa :
         {deform::Isa::portable, deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128}) {
      if (!deform::isa_available(isa)) continue;
      CAPTURE(std::string(deform::isa_name(isa)));
      job.isa = isa;
      std::vector<glm::vec3> whole_positions = in, whole_normals(in.size(), glm::vec3(1, 0, 0));
      job.positions = whole_positions, job.normals_in = whole_normals, job.normals_out = whole_normals;
      REQUIRE(job.run());
      std::vector<glm::vec3> part_positions = in, part_normals(in.size(), glm::vec3(1, 0, 0));
      job.positions = part_positions, job.normals_in = part_normals, job.normals_out = part_normals;
      for (std::size_t begin = 0; begin < job.count();) {
        const std::size_t end = std::min(job.count(), begin + 1 + rng() % 50);
        REQUIRE(job.run(begin, end));
        begin = end;
      }
      CHECK(part_positions == whole_positions);
      CHECK(part_normals == whole_normals);
      CHECK(std::string(job.run(job.count(), job.count() + 1).reason()) == "range outside the job");
    }
  }
}
