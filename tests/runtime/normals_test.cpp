// Vertex normals, bounds and point topology: hand-computed cases, invariances, plain reference implementations (the
// library's former atan2 code and a double-precision acos one), and OpenMesh as an independent reference for the
// angle-weighted normals, one-rings and boundary edges. Every normals case runs on every path: the one-shot
// compute_vertex_normals and VertexNormalsJob with each kernel copy (isa.hpp) this CPU runs.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <string>

#if DEFORM_HAVE_OPENMESH  // (tests/CMakeLists.txt: not in a cross build)
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#endif
#include <glm/gtc/matrix_transform.hpp>

#include "deform/extras/builtin.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/runtime/parallel.hpp"
#include "normals_reference.hpp"  // fixtures/: the plain reference (normals_bench times it too)

namespace {

using deform::Mesh;
#if DEFORM_HAVE_OPENMESH  // (tests/CMakeLists.txt: not in a cross build)
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;
#endif

// A mesh whose render vertices are its points (no seams).
Mesh make_mesh(std::vector<glm::vec3> positions, std::vector<std::uint32_t> triangles) {
  Mesh mesh;
  mesh.positions = std::move(positions);
  for (std::uint32_t p = 0; p < mesh.positions.size(); ++p) mesh.vertex_point.push_back(p);
  mesh.triangles = std::move(triangles);
  return mesh;
}

// The ways to get normals: the one-shot function and VertexNormalsJob with each kernel copy this CPU runs.
enum class Path { function, bound_portable, bound_avx2, bound_avx512, bound_neon, bound_simd128 };
deform::Isa isa_of(Path path) {
  return path == Path::bound_avx512    ? deform::Isa::avx512
         : path == Path::bound_avx2    ? deform::Isa::avx2
         : path == Path::bound_neon    ? deform::Isa::neon
         : path == Path::bound_simd128 ? deform::Isa::simd128
                                       : deform::Isa::portable;
}
const std::vector<Path> all_paths = [] {
  std::vector<Path> paths;
  for (const Path path : {Path::function, Path::bound_portable, Path::bound_avx2, Path::bound_avx512, Path::bound_neon,
                          Path::bound_simd128})
    if (path == Path::function || deform::isa_available(isa_of(path))) paths.push_back(path);
  return paths;
}();
std::string path_name(Path path) {
  switch (path) {
    case Path::function: return "compute_vertex_normals";
    case Path::bound_portable: return "VertexNormalsJob portable";
    case Path::bound_avx2: return "VertexNormalsJob avx2";
    case Path::bound_avx512: return "VertexNormalsJob avx512";
    case Path::bound_neon: return "VertexNormalsJob neon";
    case Path::bound_simd128: return "VertexNormalsJob simd128";
  }
  return "?";
}

std::vector<glm::vec3> normals_of(const Mesh& mesh, std::span<const glm::vec3> positions, Path path) {
  std::vector<glm::vec3> out(mesh.vertex_count());
  if (path == Path::function) {
    std::vector<glm::vec3> scratch(mesh.point_count());
    REQUIRE(deform::compute_vertex_normals(mesh, positions, scratch, out));
  } else {
    const deform::VertexNormalsBinding binding = deform::bind_vertex_normals(mesh);
    std::vector<glm::vec4> scratch(binding.scratch_size(), glm::vec4(-7.0f));
    deform::VertexNormalsJob job;
    job.binding = &binding;
    job.positions = positions;
    job.normals = out;
    job.scratch = scratch;
    job.isa = isa_of(path);
    REQUIRE(job.scratch_size() == scratch.size());
    REQUIRE(job.validate());
    REQUIRE(job.run());
  }
  return out;
}
std::vector<glm::vec3> normals_of(const Mesh& mesh, Path path = Path::function) {
  return normals_of(mesh, mesh.positions, path);
}

// The angle between two directions, in radians (0 when both are zero; pi when only one is).
double angle_between(const glm::vec3& a, const glm::vec3& b) {
  if (a == glm::vec3(0.0f) || b == glm::vec3(0.0f)) return a == b ? 0.0 : std::numbers::pi;
  const glm::dvec3 x = glm::normalize(glm::dvec3(a)), y = glm::normalize(glm::dvec3(b));
  return std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y));
}

void check_near(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-5f) {
  INFO("got (", a.x, ", ", a.y, ", ", a.z, "), expected (", b.x, ", ", b.y, ", ", b.z, ")");
  CHECK(glm::length(a - b) < tolerance);
}

// The unit cube as 12 triangles; `flip` picks the other diagonal of every face.
Mesh cube(bool flip) {
  const std::vector<glm::vec3> corners = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                          {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const std::uint32_t quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                     {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  std::vector<std::uint32_t> triangles;
  for (const auto& q : quads) {
    if (flip) triangles.insert(triangles.end(), {q[0], q[1], q[3], q[1], q[2], q[3]});
    else triangles.insert(triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  return make_mesh(corners, triangles);
}

// An n x m grid of points in z = 0 (jittered in-plane), each cell split along a random diagonal. (The sizes come as
// one braced pair so that a caller drawing both draws them in order.)
Mesh flat_grid(glm::ivec2 size, std::mt19937& random) {
  const int n = size.x, m = size.y;
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  std::vector<glm::vec3> positions;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) positions.push_back({float(i) + jitter(random), float(j) + jitter(random), 0.0f});
  std::vector<std::uint32_t> triangles;
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < m; ++j) {
      const auto a = std::uint32_t(i * m + j), b = a + std::uint32_t(m), c = b + 1, d = a + 1;
      if (random() % 2) triangles.insert(triangles.end(), {a, b, c, a, c, d});
      else triangles.insert(triangles.end(), {a, b, d, b, c, d});
    }
  return make_mesh(positions, triangles);
}

// A closed torus of n x m points with random diagonals and radial noise; its render vertices are split along the
// u = 0 and v = 0 seams the way a UV-mapped torus is, (n + 1) x (m + 1) of them.
Mesh torus(glm::ivec2 size, std::mt19937& random) {
  const int n = size.x, m = size.y;
  std::uniform_real_distribution<float> noise(-0.05f, 0.05f);
  Mesh mesh;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const float u = 2 * std::numbers::pi_v<float> * float(i) / float(n);
      const float v = 2 * std::numbers::pi_v<float> * float(j) / float(m);
      const float r = 0.4f + noise(random);
      mesh.positions.emplace_back((1 + r * std::cos(v)) * std::cos(u), (1 + r * std::cos(v)) * std::sin(u),
                                  r * std::sin(v));
    }
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= m; ++j) {
      mesh.vertex_point.push_back(std::uint32_t((i % n) * m + j % m));
      mesh.vertex_uvs.emplace_back(float(i) / float(n), float(j) / float(m));
    }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const auto a = std::uint32_t(i * (m + 1) + j), b = a + std::uint32_t(m + 1), c = b + 1, d = a + 1;
      if (random() % 2) mesh.triangles.insert(mesh.triangles.end(), {a, b, c, a, c, d});
      else mesh.triangles.insert(mesh.triangles.end(), {a, b, d, b, c, d});
    }
  return mesh;
}

// Plain reference: the corner angle from acos of the normalised edge dot product, per corner, in double. When
// `condition` is given it receives, per render vertex, the sum of the point's corner angles over the length of its
// weighted sum: how much rounding in the weights is amplified in the direction (1 on a flat or convex fan, large
// where a fold makes the contributions nearly cancel).
std::vector<glm::vec3> reference_normals(const Mesh& mesh, std::vector<double>* condition = nullptr) {
  std::vector<glm::dvec3> sums(mesh.point_count(), glm::dvec3(0.0));
  std::vector<double> angle_sums(mesh.point_count(), 0.0);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::uint32_t p[3];
    for (int k = 0; k < 3; ++k) p[k] = mesh.vertex_point[mesh.triangles[3 * t + std::size_t(k)]];
    const glm::dvec3 x[3] = {mesh.positions[p[0]], mesh.positions[p[1]], mesh.positions[p[2]]};
    const glm::dvec3 cross = glm::cross(x[1] - x[0], x[2] - x[0]);
    if (glm::length(cross) == 0.0) continue;
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 e1 = x[(k + 1) % 3] - x[k], e2 = x[(k + 2) % 3] - x[k];
      if (glm::length(e1) == 0.0 || glm::length(e2) == 0.0) continue;
      const double angle = std::acos(std::clamp(glm::dot(glm::normalize(e1), glm::normalize(e2)), -1.0, 1.0));
      sums[p[k]] += angle * glm::normalize(cross);
      angle_sums[p[k]] += angle;
    }
  }
  std::vector<glm::vec3> out;
  if (condition) condition->clear();
  for (const std::uint32_t point : mesh.vertex_point) {
    const glm::dvec3 s = sums[point];
    out.push_back(glm::length(s) > 1e-5 ? glm::vec3(glm::normalize(s)) : glm::vec3(0.0f));
    if (condition)
      condition->push_back(glm::length(s) > 0.0 ? std::max(1.0, angle_sums[point] / glm::length(s)) : 1e30);
  }
  return out;
}

// Plain reference: the library's code before the fast paths (float, std::atan2 per corner).
std::vector<glm::vec3> atan2_reference_normals(const Mesh& mesh, std::span<const glm::vec3> positions) {
  std::vector<glm::vec3> scratch(mesh.point_count()), out(mesh.vertex_count());
  normals_reference::atan2_vertex_normals(mesh, positions, scratch, out);
  return out;
}

// A smooth non-rigid deformation: a twist about y growing with height, a bend and a squash.
glm::vec3 warp(glm::vec3 p) {
  const float twist = 0.8f * p.y, c = std::cos(twist), s = std::sin(twist);
  return {c * p.x + s * p.z + 0.3f * p.y * p.y, 0.9f * p.y, -s * p.x + c * p.z + 0.1f * std::sin(3.0f * p.x)};
}

#if DEFORM_HAVE_OPENMESH  // (tests/CMakeLists.txt: not in a cross build)
OmMesh to_openmesh(const Mesh& mesh) {
  OmMesh om;
  for (const glm::vec3& p : mesh.positions) om.add_vertex(OmMesh::Point(p.x, p.y, p.z));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto vh = [&](int k) {
      return OmMesh::VertexHandle(int(mesh.vertex_point[mesh.triangles[3 * t + std::size_t(k)]]));
    };
    REQUIRE(om.add_face(vh(0), vh(1), vh(2)).is_valid());
  }
  return om;
}
#endif

}  // namespace

TEST_CASE("normals: hand-computed corner — 90 and 45 degree corners weigh 2 : 1") {
  // Corner O of a right angle in z = 0 (normal +z) and of a 45-degree triangle in x = 0 (normal +x).
  const Mesh mesh = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 1, 1}}, {0, 1, 2, 0, 2, 3});
  for (const Path path : all_paths) {
    INFO(path_name(path));
    const auto normals = normals_of(mesh, path);
    check_near(normals[0], glm::vec3(1, 0, 2) / std::sqrt(5.0f));
    check_near(normals[1], glm::vec3(0, 0, 1));
    check_near(normals[3], glm::vec3(1, 0, 0));
    // Point 2 (0,1,0): 45 degrees in the +z triangle, 90 degrees (between (0,-1,0) and (0,0,1)) in the +x one.
    check_near(normals[2], glm::vec3(2, 0, 1) / std::sqrt(5.0f));
  }
}

TEST_CASE("normals: hand-computed obtuse and acute corners, every octant of the polynomial atan2") {
  // Fans of two triangles around point 0 in the planes z = 0 and x = 0, with corner angles chosen to reach every
  // branch of corner_angle (|x| < y and |x| > y, x < 0 and x > 0): the normal at 0 is (w_x, 0, w_z) / |.|
  // with w the two corner angles.
  for (const double first : {0.3, 0.7, 1.2, 1.9, 2.6, 3.0})
    for (const double second : {0.2, 0.785, 1.5, 2.2, 2.9}) {
      const Mesh mesh = make_mesh({{0, 0, 0},
                                   {1, 0, 0},
                                   {float(std::cos(first)), float(std::sin(first)), 0},
                                   {0, 0, -1},
                                   {0, float(std::sin(second)), -float(std::cos(second))}},
                                  {0, 1, 2, 0, 3, 4});
      const glm::vec3 expected = glm::normalize(glm::vec3(float(second), 0, float(first)));
      for (const Path path : all_paths) {
        INFO(path_name(path), " corners ", first, " and ", second);
        check_near(normals_of(mesh, path)[0], expected, 1e-6f);
      }
    }
}

TEST_CASE("normals: a cube's corners point along the diagonal, whichever way the faces are split") {
  for (const bool flip : {false, true}) {
    const Mesh mesh = cube(flip);
    for (const Path path : all_paths) {
      INFO(path_name(path));
      const auto normals = normals_of(mesh, path);
      for (std::size_t p = 0; p < 8; ++p) check_near(normals[p], glm::normalize(mesh.positions[p] - glm::vec3(0.5f)));
    }
  }
}

TEST_CASE("normals: a flat grid gives +z everywhere for any triangulation") {
  std::mt19937 random(7);
  for (int round = 0; round < 20; ++round) {
    const Mesh mesh = flat_grid({2 + int(random() % 8), 2 + int(random() % 8)}, random);
    for (const Path path : all_paths)
      for (const glm::vec3& n : normals_of(mesh, path)) check_near(n, glm::vec3(0, 0, 1));
  }
}

TEST_CASE("normals: seams split by UV share the point's normal; degenerate triangles add nothing") {
  std::mt19937 random(3);
  const Mesh mesh = torus({12, 8}, random);
  for (const Path path : all_paths) {
    INFO(path_name(path));
    const auto normals = normals_of(mesh, path);
    for (int j = 0; j <= 8; ++j) CHECK(normals[std::size_t(j)] == normals[std::size_t(12 * 9 + j)]);  // u = 0, u = 1

    const Mesh with_degenerate = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}}, {0, 1, 2, 0, 1, 1, 3, 3, 3});
    const auto normals2 = normals_of(with_degenerate, path);
    check_near(normals2[0], glm::vec3(0, 0, 1));
    CHECK(normals2[3] == glm::vec3(0.0f));  // touched only by a degenerate triangle
  }
  const Mesh repeated = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}}, {0, 1, 2, 0, 1, 1, 3, 3, 3});
  CHECK(deform::bind_vertex_normals(repeated).triangle_count == 1);  // the two with a repeated point are dropped
}

TEST_CASE("normals: degenerate triangles, cancelling faces and non-finite points give finite results as documented") {
  // Points 0-2: a real triangle (+z). 3-5: exactly collinear (zero cross product). 6-8: one triangle and its mirror
  // image (the same points reversed), whose contributions cancel exactly. 9: NaN. 10: infinite.
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  Mesh mesh = make_mesh({{0, 0, 0},
                         {1, 0, 0},
                         {0, 1, 0},
                         {0, 0, 1},
                         {1, 1, 1},
                         {2, 2, 1},
                         {0, 0, 2},
                         {1, 0, 2},
                         {0, 1, 2},
                         {nan, 0, 0},
                         {inf, 0, 0}},
                        {0, 1, 2, 3, 4, 5, 6, 7, 8, 8, 7, 6, 9, 1, 2, 3, 4, 9, 10, 4, 5});
  // Enough copies of the real triangle to fill two blocks of 16 and part of a third (padding lanes).
  for (int copy = 0; copy < 35; ++copy) mesh.triangles.insert(mesh.triangles.end(), {0, 1, 2});
  for (const Path path : all_paths) {
    INFO(path_name(path));
    const auto normals = normals_of(mesh, path);
    for (const glm::vec3& n : normals) CHECK((std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z)));
    for (std::size_t p = 0; p < 3; ++p) check_near(normals[p], glm::vec3(0, 0, 1));  // the NaN triangle adds nothing
    for (std::size_t p = 6; p < 9; ++p) CHECK(normals[p] == glm::vec3(0.0f));        // cancelled
    CHECK(normals[9] == glm::vec3(0.0f));                                            // only in a NaN triangle
    CHECK(normals[3] == glm::vec3(0.0f));  // only in the collinear and NaN triangles
  }
}

TEST_CASE("normals: agree with plain references on random meshes, manifold or not (thousands of seeded cases)") {
  std::mt19937 random(11);
  std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
  for (int round = 0; round < 2000; ++round) {
    Mesh mesh;
    const int points = 3 + int(random() % 30);
    for (int i = 0; i < points; ++i)
      mesh.positions.push_back({coordinate(random), coordinate(random), coordinate(random)});
    for (int r = 0; r < points + int(random() % 10); ++r)
      mesh.vertex_point.push_back(std::uint32_t(random() % unsigned(points)));
    const int triangles = 1 + int(random() % 60);
    for (int i = 0; i < 3 * triangles; ++i) mesh.triangles.push_back(std::uint32_t(random() % mesh.vertex_count()));
    const auto reference = reference_normals(mesh);
    const auto former = atan2_reference_normals(mesh, mesh.positions);
    for (const Path path : all_paths) {
      INFO(path_name(path), " round ", round);
      const auto ours = normals_of(mesh, path);
      for (std::size_t r = 0; r < ours.size(); ++r) {
        check_near(ours[r], reference[r], 1e-4f);
        CHECK(angle_between(ours[r], former[r]) < 1e-4);
      }
    }
  }
}

TEST_CASE("normals: the built-in character and seeded deformed tori — fast paths equal the references") {
  // Against the double reference: within 5e-6 times the point's condition (1e-5 on the undeformed character, whose
  // every fan is well conditioned). Against the former atan2 code: within the 1e-4 rad the fast paths promise.
  std::vector<Mesh> meshes;
  meshes.push_back(deform::builtin_character().mesh);
  std::mt19937 random(17);
  for (int round = 0; round < 40; ++round)
    meshes.push_back(torus({3 + int(random() % 40), 3 + int(random() % 30)}, random));
  for (const Mesh& mesh : meshes) {
    std::vector<glm::vec3> warped;
    for (const glm::vec3& p : mesh.positions) warped.push_back(warp(p));
    for (const auto& positions : {std::span<const glm::vec3>(mesh.positions), std::span<const glm::vec3>(warped)}) {
      const auto former = atan2_reference_normals(mesh, positions);
      Mesh at_pose = mesh;
      at_pose.positions.assign(positions.begin(), positions.end());
      std::vector<double> condition;
      const auto reference = reference_normals(at_pose, &condition);
      for (const Path path : all_paths) {
        INFO(path_name(path), " mesh of ", mesh.point_count(), " points");
        const auto ours = normals_of(mesh, positions, path);
        for (std::size_t r = 0; r < ours.size(); ++r) {
          check_near(ours[r], reference[r], float(5e-6 * condition[r]));
          CHECK(angle_between(ours[r], former[r]) < 1e-4);
        }
      }
    }
  }
  const Mesh& character = meshes.front();
  for (const Path path : all_paths) {
    const auto ours = normals_of(character, path);
    const auto reference = reference_normals(character);
    for (std::size_t r = 0; r < ours.size(); ++r) check_near(ours[r], reference[r], 1e-5f);
  }
}

TEST_CASE("normals: rotating, scaling and moving the points rotates the normals (seeded)") {
  std::mt19937 random(23);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int round = 0; round < 50; ++round) {
    const Mesh mesh = torus({4 + int(random() % 20), 3 + int(random() % 20)}, random);
    const glm::vec3 axis = glm::normalize(glm::vec3{unit(random), unit(random), unit(random)} + glm::vec3(0, 0, 2));
    const float angle = 3.0f * unit(random), scale = 0.1f + 10.0f * std::abs(unit(random));
    const glm::vec3 offset = scale * glm::vec3{unit(random), unit(random), unit(random)};
    const glm::mat3 rotation = glm::mat3(glm::rotate(glm::mat4(1.0f), angle, axis));
    std::vector<glm::vec3> moved;
    for (const glm::vec3& p : mesh.positions) moved.push_back(scale * (rotation * p) + offset);
    for (const Path path : all_paths) {
      INFO(path_name(path), " round ", round);
      const auto before = normals_of(mesh, path);
      const auto after = normals_of(mesh, moved, path);
      for (std::size_t r = 0; r < before.size(); ++r) check_near(after[r], rotation * before[r], 2e-5f);
    }
  }
}

TEST_CASE("normals: every kernel copy and the one-shot function agree to float rounding") {
  // Float rounding in the weights moves a normal by about 1e-7 times its point's condition, more on thin triangles
  // (the rounding of the edges). The job computes a triangle from its lowest point and the function from its first
  // vertex, so the third corner's angle (π minus the other two, within 1e-6 rad) is a different corner in each:
  // measured up to 3.3e-6 times the condition (Clang 14), hence 5e-6, the bound against the double reference.
  INFO("best kernel copy on this CPU: ", std::string(deform::isa_name(deform::isa_best())));
  std::mt19937 random(29);
  for (int round = 0; round < 100; ++round) {
    Mesh mesh = torus({3 + int(random() % 50), 3 + int(random() % 50)}, random);
    for (glm::vec3& p : mesh.positions) p = warp(p);
    std::vector<double> condition;
    reference_normals(mesh, &condition);
    const auto function = normals_of(mesh, Path::function);
    for (const Path path : all_paths) {
      INFO(path_name(path));
      const auto ours = normals_of(mesh, path);
      for (std::size_t r = 0; r < ours.size(); ++r) check_near(ours[r], function[r], float(5e-6 * condition[r]));
    }
  }
}

#if DEFORM_HAVE_OPENMESH  // (tests/CMakeLists.txt: not in a cross build)
TEST_CASE("normals: match angle-weighted normals built on OpenMesh's half-edge circulators") {
  std::mt19937 random(5);
  const Mesh mesh = torus({24, 16}, random);
  OmMesh om = to_openmesh(mesh);
  om.request_face_normals();
  om.update_face_normals();
  std::vector<std::size_t> vertex_of_point(mesh.point_count());
  for (std::size_t r = 0; r < mesh.vertex_count(); ++r) vertex_of_point[mesh.vertex_point[r]] = r;
  // OpenMesh's own update_normals() weighs faces differently (not by angle): the two agree where every weighting
  // must, on a flat grid.
  std::mt19937 random2(9);
  const Mesh grid = flat_grid({6, 5}, random2);
  OmMesh om_grid = to_openmesh(grid);
  om_grid.request_face_normals();
  om_grid.request_vertex_normals();
  om_grid.update_normals();
  for (const Path path : all_paths) {
    INFO(path_name(path));
    const auto ours = normals_of(mesh, path);
    for (const auto vh : om.vertices()) {
      OmMesh::Normal sum(0, 0, 0);
      for (const auto heh : om.vih_range(vh))  // sector of the face left of each incoming half-edge, at vh
        if (!om.is_boundary(heh)) sum += om.calc_sector_angle(heh) * om.normal(om.face_handle(heh));
      sum.normalize();
      check_near(ours[vertex_of_point[std::size_t(vh.idx())]], glm::vec3(sum[0], sum[1], sum[2]), 1e-5f);
    }
    const auto grid_normals = normals_of(grid, path);
    for (const auto vh : om_grid.vertices()) {
      const auto n = om_grid.normal(vh);
      check_near(grid_normals[std::size_t(vh.idx())], glm::vec3(n[0], n[1], n[2]));
    }
  }
}
#endif

TEST_CASE("normals: wrong sizes and out-of-range indices are refused with a reason (or throw when binding)") {
  const Mesh mesh = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2});
  std::vector<glm::vec3> scratch(3), out(3), short_span(2);
  const auto reason = [](deform::Status status) { return std::string(status.reason()); };
  CHECK(deform::compute_vertex_normals(mesh, mesh.positions, scratch, out));
  CHECK(reason(deform::compute_vertex_normals(mesh, short_span, scratch, out)) == "positions: one per point");
  CHECK(reason(deform::compute_vertex_normals(mesh, mesh.positions, short_span, out)) == "scratch: one per point");
  CHECK(reason(deform::compute_vertex_normals(mesh, mesh.positions, scratch, short_span)) ==
        "normals: one per render vertex");
  const deform::VertexNormalsBinding binding = deform::bind_vertex_normals(mesh);
  CHECK(binding.point_count == 3);
  CHECK(binding.vertex_count == 3);
  std::vector<glm::vec4> corner_scratch(6);  // 3 points, 3 corners
  deform::VertexNormalsJob job;
  CHECK(reason(job.validate()) == "no binding");
  CHECK(job.count() == 0);
  CHECK(job.scratch_size() == 0);
  job.binding = &binding;
  job.positions = mesh.positions;
  job.normals = out;
  CHECK(reason(job.validate()) == "scratch: one per point and corner");
  CHECK(job.scratch_size() == 6);
  job.scratch = corner_scratch;
  CHECK(job.validate());
  CHECK(job.count() == 3);
  CHECK(job.run());
  std::vector<glm::vec3> untouched(2, glm::vec3(7.0f));
  deform::VertexNormalsJob bad_job = job;
  bad_job.positions = short_span;
  CHECK(reason(bad_job.run()) == "positions: one per point");
  bad_job = job, bad_job.normals = untouched;
  CHECK(reason(bad_job.run()) == "normals: one per render vertex");
  CHECK(untouched == std::vector<glm::vec3>(2, glm::vec3(7.0f)));  // "writing nothing"
  CHECK(reason(job.run(2, 4)) == "range outside the job");
  CHECK(reason(job.run(2, 1)) == "range outside the job");
  for (const deform::Isa isa : {deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128})
    if (!deform::isa_available(isa)) {  // a forced copy this CPU lacks is refused
      std::vector<glm::vec3> kept(3, glm::vec3(7.0f));
      bad_job = job, bad_job.normals = kept, bad_job.isa = isa;
      CHECK(reason(bad_job.validate()) == "instruction set not available");
      CHECK_FALSE(bad_job.run());
      CHECK(kept == std::vector<glm::vec3>(3, glm::vec3(7.0f)));
    }
  // A binding altered after bind_vertex_normals: validate() finds what run() would not look at.
  deform::VertexNormalsBinding broken = binding;
  broken.triangle_points[1] = 3;
  bad_job = job, bad_job.binding = &broken;
  CHECK(reason(bad_job.validate()) == "binding triangle invalid");
  broken = binding, broken.triangle_corners[2] = 1;  // the triangle's corner at point 2 is corner 2
  CHECK(reason(bad_job.validate()) == "binding triangle invalid");
  broken = binding, std::swap(broken.triangle_points[1], broken.triangle_points[0]);  // not from its lowest point
  CHECK(reason(bad_job.validate()) == "binding triangle invalid");
  broken = binding, broken.point_vertices[0] = 9;
  CHECK(reason(bad_job.validate()) == "binding vertex out of range");
  broken = binding, broken.corner_offsets[1] = 3, broken.corner_offsets[2] = 2;
  CHECK(reason(bad_job.validate()) == "binding offsets invalid");
  broken = binding, broken.corner_triangle.pop_back();
  CHECK(reason(bad_job.validate()) == "binding arrays differ in size");
  CHECK(reason(bad_job.run()) == "binding arrays differ in size");

  Mesh bad = mesh;
  bad.triangles[2] = 3;
  CHECK(reason(deform::compute_vertex_normals(bad, bad.positions, scratch, out)) == "triangle vertex out of range");
  CHECK_THROWS_AS(deform::bind_vertex_normals(bad), deform::Error);
  bad = mesh;
  bad.vertex_point[1] = 7;
  CHECK(reason(deform::compute_vertex_normals(bad, bad.positions, scratch, out)) == "vertex point out of range");
  CHECK_THROWS_AS(deform::bind_vertex_normals(bad), deform::Error);
  bad = mesh;
  bad.triangles.pop_back();
  CHECK(reason(deform::compute_vertex_normals(bad, bad.positions, scratch, out)) ==
        "triangle index count not a multiple of 3");
  CHECK_THROWS_AS(deform::bind_vertex_normals(bad), deform::Error);

  // No triangles: every normal is zero. An empty mesh binds to an empty job.
  Mesh bare = mesh;
  bare.triangles.clear();
  const deform::VertexNormalsBinding none = deform::bind_vertex_normals(bare);
  out.assign(3, glm::vec3(1.0f));
  job.binding = &none, job.scratch = std::span<glm::vec4>(corner_scratch).first(3);  // 3 points, no corners
  CHECK(job.run());
  CHECK(out == std::vector<glm::vec3>(3, glm::vec3(0.0f)));
  const deform::VertexNormalsBinding empty = deform::bind_vertex_normals(Mesh{});
  job.binding = &empty, job.positions = {}, job.normals = {}, job.scratch = {};
  CHECK(job.validate());
  CHECK(job.run());
}

TEST_CASE("normals: any split of the points, and run_parallel, give run()'s bits") {
  std::mt19937 random(31);
  deform::ThreadPool pool(3);
  for (int round = 0; round < 20; ++round) {
    Mesh mesh = torus({3 + int(random() % 60), 3 + int(random() % 60)}, random);
    for (glm::vec3& p : mesh.positions) p = warp(p);
    const deform::VertexNormalsBinding binding = deform::bind_vertex_normals(mesh);
    for (const Path path : all_paths) {
      if (path == Path::function) continue;
      INFO(path_name(path), " round ", round);
      std::vector<glm::vec3> whole(mesh.vertex_count()), parts(mesh.vertex_count()), threaded(mesh.vertex_count());
      std::vector<glm::vec4> scratch(binding.scratch_size());
      deform::VertexNormalsJob job;
      job.binding = &binding;
      job.positions = mesh.positions;
      job.scratch = scratch;
      job.isa = isa_of(path);
      job.normals = whole;
      REQUIRE(job.run());
      // Random cuts, covering every point once.
      job.normals = parts;
      std::size_t begin = 0;
      while (begin < job.count()) {
        const std::size_t end = std::min(job.count(), begin + 1 + random() % 40);
        REQUIRE(job.run(begin, end));
        begin = end;
      }
      CHECK(parts == whole);
      job.normals = threaded;
      REQUIRE(deform::run_parallel(job, pool, 16));
      CHECK(threaded == whole);
    }
  }
}

TEST_CASE("bounds") {
  const std::vector<glm::vec3> points = {{1, -2, 3}, {-4, 5, 0}, {0, 0, 9}};
  const deform::Bounds bounds = deform::compute_bounds(points);
  CHECK(bounds.min == glm::vec3(-4, -2, 0));
  CHECK(bounds.max == glm::vec3(1, 5, 9));
  const deform::Bounds empty = deform::compute_bounds({});
  CHECK(empty.min == glm::vec3(0.0f));
  CHECK(empty.max == glm::vec3(0.0f));
}

#if DEFORM_HAVE_OPENMESH  // (tests/CMakeLists.txt: not in a cross build)
TEST_CASE("topology: one-rings and boundary edges match OpenMesh on open and closed meshes") {
  std::mt19937 random(21);
  for (int round = 0; round < 10; ++round) {
    const Mesh mesh = round % 2 ? torus({5 + int(random() % 6), 4 + int(random() % 6)}, random)
                                : flat_grid({2 + int(random() % 7), 2 + int(random() % 7)}, random);
    const deform::PointTopology topology = deform::build_point_topology(mesh);
    const OmMesh om = to_openmesh(mesh);
    REQUIRE(topology.neighbour_offsets.size() == mesh.point_count() + 1);
    for (const auto vh : om.vertices()) {
      std::vector<std::uint32_t> expected;
      for (const auto other : om.vv_range(vh)) expected.push_back(std::uint32_t(other.idx()));
      std::sort(expected.begin(), expected.end());
      const auto ring = topology.point_neighbours(std::uint32_t(vh.idx()));
      CHECK(std::vector<std::uint32_t>(ring.begin(), ring.end()) == expected);
    }
    std::vector<std::uint32_t> boundary;
    for (const auto eh : om.edges())
      if (om.is_boundary(eh)) {
        const auto a = std::uint32_t(om.from_vertex_handle(om.halfedge_handle(eh, 0)).idx());
        const auto b = std::uint32_t(om.to_vertex_handle(om.halfedge_handle(eh, 0)).idx());
        boundary.push_back(std::min(a, b));
        boundary.push_back(std::max(a, b));
      }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (std::size_t i = 0; i < boundary.size(); i += 2) pairs.emplace_back(boundary[i], boundary[i + 1]);
    std::sort(pairs.begin(), pairs.end());
    std::vector<std::uint32_t> sorted;
    for (const auto& [a, b] : pairs) sorted.insert(sorted.end(), {a, b});
    CHECK(topology.boundary_edges == sorted);
    if (round % 2) CHECK(topology.boundary_edge_count() == 0);  // closed torus: the UV seams are not boundaries
  }
}
#endif

TEST_CASE("topology: non-manifold soups, isolated points and bad indices") {
  // Three triangles on one edge (0, 1), a degenerate triangle, and an isolated point 5.
  const Mesh mesh = make_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, -1, 0}, {9, 9, 9}},
                              {0, 1, 2, 0, 1, 3, 1, 0, 4, 2, 2, 3});
  const deform::PointTopology topology = deform::build_point_topology(mesh);
  const auto ring = [&](std::uint32_t p) {
    const auto span = topology.point_neighbours(p);
    return std::vector<std::uint32_t>(span.begin(), span.end());
  };
  CHECK(ring(0) == std::vector<std::uint32_t>{1, 2, 3, 4});
  CHECK(ring(2) == std::vector<std::uint32_t>{0, 1, 3});
  CHECK(ring(5).empty());
  // Edge (0, 1) has three triangles (not a boundary); the degenerate triangle (2, 2, 3) uses edge (2, 3) once.
  CHECK(topology.boundary_edges == std::vector<std::uint32_t>{0, 2, 0, 3, 0, 4, 1, 2, 1, 3, 1, 4, 2, 3});
  Mesh bad = mesh;
  bad.triangles[0] = 99;
  CHECK_THROWS_AS(deform::build_point_topology(bad), deform::Error);
}

// The in-place gather (Character's transported normals without a per-point array) against the plain gather into a
// second array: random maps of every shape — identity, permutations (cycles), many destinations per source, sources
// no destination reads, more destinations than sources — thousands of seeded cases, and the built-in character's.
TEST_CASE("in-place gather: equals the plain gather on seeded random maps and the built-in character's") {
  const auto check = [](const std::vector<std::uint32_t>& map, std::size_t sources, std::mt19937& rng) {
    std::uniform_real_distribution<float> any(-1.0f, 1.0f);
    std::vector<glm::vec3> values(map.size() + 1);
    for (glm::vec3& v : values) v = {any(rng), any(rng), any(rng)};
    std::vector<glm::vec3> expected(map.size() + 1);
    for (std::size_t v = 0; v < map.size(); ++v) expected[v] = values[map[v]];
    const deform::InPlaceGather plan = deform::plan_in_place_gather(map, sources);
    deform::InPlaceGatherJob job;
    job.plan = &plan;
    job.values = values;
    REQUIRE(job.validate());
    REQUIRE(job.run());
    bool same = true;
    for (std::size_t v = 0; v < map.size(); ++v) same = same && values[v] == expected[v];  // (not the scratch)
    CHECK(same);
    std::size_t moved = 0;
    for (std::size_t v = 0; v < map.size(); ++v) moved += map[v] != v;
    CHECK(plan.moves.size() % 2 == 0);
    CHECK(plan.moves.size() / 2 >= moved);
    CHECK(plan.moves.size() / 2 <= moved + moved / 2 + 1);  // at most one held value per cycle (of 2 or more)
  };
  std::mt19937 rng(18);
  for (int round = 0; round < 4000; ++round) {
    const std::size_t count = 1 + rng() % 64;
    const std::size_t sources = 1 + rng() % count;
    std::vector<std::uint32_t> map(count);
    switch (round % 4) {
      case 0:  // any source per destination
        for (auto& m : map) m = std::uint32_t(rng() % sources);
        break;
      case 1: {  // a permutation of the sources, then random duplicates
        std::vector<std::uint32_t> perm(sources);
        for (std::size_t s = 0; s < sources; ++s) perm[s] = std::uint32_t(s);
        std::shuffle(perm.begin(), perm.end(), rng);
        for (std::size_t v = 0; v < count; ++v) map[v] = v < sources ? perm[v] : std::uint32_t(rng() % sources);
        break;
      }
      case 2:  // mostly the identity, a few moved
        for (std::size_t v = 0; v < count; ++v)
          map[v] = v < sources && rng() % 4 ? std::uint32_t(v) : std::uint32_t(rng() % sources);
        break;
      default: {  // a render-vertex order: every source once in shuffled order, duplicates interleaved
        std::vector<std::uint32_t> order;
        for (std::size_t s = 0; s < sources; ++s) order.push_back(std::uint32_t(s));
        while (order.size() < count) order.push_back(std::uint32_t(rng() % sources));
        std::shuffle(order.begin(), order.end(), rng);
        map = order;
      }
    }
    check(map, sources, rng);
  }
  const deform::Mesh mesh = deform::builtin_character().mesh;
  check(mesh.vertex_point, mesh.point_count(), rng);
  std::vector<std::uint32_t> bad = {0, 2, 1};
  CHECK_THROWS_AS(deform::plan_in_place_gather(bad, 2), deform::Error);
  CHECK_THROWS_AS(deform::plan_in_place_gather(bad, 4), deform::Error);
  deform::InPlaceGatherJob job;
  CHECK(!job.validate());
  const deform::InPlaceGather plan = deform::plan_in_place_gather(bad, 3);
  std::vector<glm::vec3> short_values(3);
  job.plan = &plan;
  job.values = short_values;
  CHECK(job.validate().reason() == std::string("values: one per destination and one more"));
  CHECK(!job.run());
}

// order_vertices_by_point on seeded random meshes (seam copies, unused points, more points than render vertices):
// every corner draws the same point, normal and UV; point p's first render vertex is at p where p is used and below
// the vertex count; the in-place gather then moves exactly the other render vertices. Bad input leaves the mesh as it
// was. The built-in character is laid out so: one move per seam copy.
TEST_CASE("order_vertices_by_point: draws the same, and gathers in place with a move per seam copy") {
  std::mt19937 rng(2026);
  for (int round = 0; round < 2000; ++round) {
    Mesh mesh;
    const std::size_t points = 1 + rng() % 40, vertices = 1 + rng() % 60;
    mesh.positions.resize(points);
    for (std::size_t v = 0; v < vertices; ++v) {
      mesh.vertex_point.push_back(std::uint32_t(rng() % points));
      mesh.vertex_normals.push_back({float(v), 1.0f, 0.0f});
      if (round % 3) mesh.vertex_uvs.push_back({0.0f, float(v)});
    }
    for (std::size_t t = 0; t < 3 * (rng() % 30); ++t) mesh.triangles.push_back(std::uint32_t(rng() % vertices));
    mesh.face_corners = mesh.triangles;
    mesh.face_sizes.assign(mesh.triangle_count(), 3);
    const Mesh before = mesh;
    const std::vector<std::uint32_t> slot = deform::order_vertices_by_point(mesh);
    REQUIRE(slot.size() == vertices);
    REQUIRE(mesh.vertex_count() == vertices);
    std::vector<std::uint32_t> sorted = slot;
    std::sort(sorted.begin(), sorted.end());
    bool permutation = true, same = true;
    for (std::size_t v = 0; v < vertices; ++v) permutation = permutation && sorted[v] == v;
    CHECK(permutation);
    for (std::size_t v = 0; v < vertices; ++v) {
      same = same && mesh.vertex_point[slot[v]] == before.vertex_point[v] &&
             mesh.vertex_normals[slot[v]] == before.vertex_normals[v] &&
             (mesh.vertex_uvs.empty() || mesh.vertex_uvs[slot[v]] == before.vertex_uvs[v]);
    }
    for (std::size_t c = 0; c < mesh.triangles.size(); ++c) {
      same = same && mesh.triangles[c] == slot[before.triangles[c]] &&
             mesh.face_corners[c] == slot[before.face_corners[c]];
    }
    CHECK(same);
    CHECK(mesh.vertex_uvs.size() == before.vertex_uvs.size());
    std::vector<std::uint8_t> used(points, 0);
    for (const std::uint32_t p : before.vertex_point) used[p] = 1;
    std::size_t at_home = 0, expected_home = 0;
    for (std::size_t p = 0; p < std::min(points, vertices); ++p) {
      expected_home += used[p];
      at_home += mesh.vertex_point[p] == p;
    }
    CHECK(at_home == expected_home);
    if (points <= vertices) {
      const deform::InPlaceGather plan = deform::plan_in_place_gather(mesh.vertex_point, points);
      CHECK(plan.moves.size() / 2 == vertices - at_home);
    }
  }
  Mesh bad = deform::builtin_character().mesh;
  const Mesh kept = bad;
  bad.face_corners.back() = std::uint32_t(bad.vertex_count());
  CHECK_THROWS_AS(deform::order_vertices_by_point(bad), deform::Error);
  CHECK(bad.triangles == kept.triangles);
  CHECK(bad.vertex_point == kept.vertex_point);
  bad = kept;
  bad.vertex_uvs.pop_back();
  CHECK_THROWS_AS(deform::order_vertices_by_point(bad), deform::Error);

  const Mesh& builtin = kept;
  const deform::InPlaceGather plan = deform::plan_in_place_gather(builtin.vertex_point, builtin.point_count());
  CHECK(plan.moves.size() / 2 == builtin.vertex_count() - builtin.point_count());  // 218 seam copies
}
