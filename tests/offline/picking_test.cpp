// Picking: the triangle test by hand, the BVH against brute force over thousands of random rays, refit, camera rays.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/offline/picking.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
using namespace deform;

namespace {

// A plain reference: every triangle, Möller–Trumbore written out again in double, nearest hit (lowest index on ties).
RayHit brute_force(const Ray& ray, std::span<const glm::vec3> p, std::span<const std::uint32_t> indices) {
  RayHit best;
  const glm::dvec3 o(ray.origin), d = glm::normalize(glm::dvec3(ray.direction));
  double best_t = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < indices.size(); i += 3) {
    const glm::dvec3 a(p[indices[i]]), b(p[indices[i + 1]]), c(p[indices[i + 2]]);
    const glm::dvec3 n = glm::cross(b - a, c - a);
    const double denom = glm::dot(n, d);
    if (std::abs(denom) < 1e-18) continue;
    const double t = glm::dot(n, a - o) / denom;
    if (t < 0.0 || t >= best_t) continue;
    const glm::dvec3 x = o + t * d;
    const double area = glm::dot(n, n);
    const double w1 = glm::dot(glm::cross(x - a, c - a), n) / area;  // sub-area weights of b and c
    const double w2 = glm::dot(glm::cross(b - a, x - a), n) / area;
    if (w1 < 0.0 || w2 < 0.0 || w1 + w2 > 1.0) continue;
    best_t = t;
    best = RayHit{true, static_cast<std::uint32_t>(i / 3), glm::vec3(float(1.0 - w1 - w2), float(w1), float(w2)),
                  float(t)};
  }
  return best;
}

// A bumpy closed-ish surface: a grid of n × n quads displaced by noise, plus random loose triangles.
void random_mesh(std::mt19937& random, int n, int loose, std::vector<glm::vec3>& positions,
                 std::vector<std::uint32_t>& indices) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  positions.clear();
  indices.clear();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      positions.emplace_back(float(i) / float(n) * 2.0f - 1.0f, 0.3f * unit(random), float(j) / float(n) * 2.0f - 1.0f);
  const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      indices.insert(indices.end(),
                     {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
  for (int t = 0; t < loose; ++t) {
    const glm::vec3 centre{unit(random), unit(random), unit(random)};
    for (int c = 0; c < 3; ++c) {
      indices.push_back(static_cast<std::uint32_t>(positions.size()));
      positions.push_back(centre + 0.2f * glm::vec3{unit(random), unit(random), unit(random)});
    }
  }
}

Ray random_ray(std::mt19937& random) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  const glm::vec3 origin = 3.0f * glm::vec3{unit(random), unit(random), unit(random)};
  const glm::vec3 aim = 0.9f * glm::vec3{unit(random), unit(random), unit(random)};
  return Ray{origin, (aim - origin) * (0.5f + unit(random) + 1.0f)};
}

// A seeded random_mesh, its BVH, and the generator for the rays that go with it.
struct RandomScene {
  std::mt19937 random;
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  TriangleBvh bvh;
  RandomScene(unsigned seed, int n, int loose) : random(seed) {
    random_mesh(random, n, loose, positions, indices);
    bvh.build(positions, indices);
  }
};

void check_same(const RayHit& bvh, const RayHit& reference, std::span<const glm::vec3> p,
                std::span<const std::uint32_t> indices, const Ray& ray) {
  REQUIRE(bvh.hit == reference.hit);
  if (!bvh.hit) return;
  CHECK(bvh.distance == doctest::Approx(reference.distance).epsilon(1e-4));
  if (bvh.triangle != reference.triangle) {
    // Only a tie at an edge shared by two triangles may pick the other one; the distance then agrees anyway.
    CHECK(std::abs(bvh.distance - reference.distance) < 1e-4f);
    return;
  }
  CHECK(bvh.barycentric.x == doctest::Approx(reference.barycentric.x).epsilon(1e-3).scale(1.0));
  CHECK(bvh.barycentric.y == doctest::Approx(reference.barycentric.y).epsilon(1e-3).scale(1.0));
  // The reported point is on the ray at that distance, and the barycentric combination of the corners.
  const glm::vec3 on_ray = ray.origin + glm::normalize(ray.direction) * bvh.distance;
  const std::uint32_t* c = &indices[3 * std::size_t{bvh.triangle}];
  const glm::vec3 blended = bvh.barycentric.x * p[c[0]] + bvh.barycentric.y * p[c[1]] + bvh.barycentric.z * p[c[2]];
  CHECK(glm::length(on_ray - blended) < 1e-4f);
}

}  // namespace

TEST_CASE("a ray hits one hand-made triangle where the arithmetic says") {
  const std::vector<glm::vec3> p = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  const std::vector<std::uint32_t> tri = {0, 1, 2};
  RayHit hit = intersect_triangles(Ray{{0.5f, 0.5f, 3.0f}, {0, 0, -2}}, p, tri);
  REQUIRE(hit.hit);
  CHECK(hit.triangle == 0);
  CHECK(hit.distance == doctest::Approx(3.0f));
  CHECK(hit.barycentric.x == doctest::Approx(0.5f));
  CHECK(hit.barycentric.y == doctest::Approx(0.25f));
  CHECK(hit.barycentric.z == doctest::Approx(0.25f));
  // From behind (two-sided), outside the triangle, pointing away, beyond max_distance, zero direction.
  CHECK(intersect_triangles(Ray{{0.5f, 0.5f, -1.0f}, {0, 0, 1}}, p, tri).distance == doctest::Approx(1.0f));
  CHECK_FALSE(intersect_triangles(Ray{{1.5f, 1.5f, 3.0f}, {0, 0, -1}}, p, tri).hit);
  CHECK_FALSE(intersect_triangles(Ray{{0.5f, 0.5f, 3.0f}, {0, 0, 1}}, p, tri).hit);
  CHECK_FALSE(intersect_triangles(Ray{{0.5f, 0.5f, 3.0f}, {0, 0, -1}}, p, tri, 2.5f).hit);
  CHECK_FALSE(intersect_triangles(Ray{{0.5f, 0.5f, 3.0f}, {0, 0, 0}}, p, tri).hit);
  TriangleBvh bvh;
  bvh.build(p, tri);
  hit = bvh.intersect(Ray{{0.5f, 0.5f, 3.0f}, {0, 0, -2}});
  CHECK(hit.hit);
  CHECK(hit.distance == doctest::Approx(3.0f));
  CHECK(hit.barycentric.y == doctest::Approx(0.25f));
}

TEST_CASE("the BVH agrees with brute force over thousands of random rays, before and after refit") {
  RandomScene scene(17, 40, 300);  // 3,500 triangles
  auto& [random, positions, indices, bvh] = scene;
  CHECK(bvh.triangle_count() == indices.size() / 3);
  int hits = 0;
  for (int r = 0; r < 5000; ++r) {
    const Ray ray = random_ray(random);
    const RayHit reference = brute_force(ray, positions, indices);
    check_same(bvh.intersect(ray), reference, positions, indices, ray);
    check_same(intersect_triangles(ray, positions, indices), reference, positions, indices, ray);
    hits += reference.hit;
  }
  CHECK(hits > 1000);  // the rays do exercise hits, not only misses
  // Deform (a twist and a lift, large enough to reorder the boxes) and refit: same answers as brute force.
  for (glm::vec3& p : positions) {
    const float angle = 1.5f * p.z;
    p = glm::vec3(std::cos(angle) * p.x - std::sin(angle) * p.y, std::sin(angle) * p.x + std::cos(angle) * p.y, p.z) +
        glm::vec3(0, 0.5f * p.x * p.x, 0);
  }
  REQUIRE(bvh.refit(positions));
  for (int r = 0; r < 3000; ++r) {
    const Ray ray = random_ray(random);
    check_same(bvh.intersect(ray), brute_force(ray, positions, indices), positions, indices, ray);
  }
  std::vector<glm::vec3> fewer(positions.begin(), positions.end() - 1);
  CHECK_FALSE(bvh.refit(fewer));
}

TEST_CASE("max_distance limits the BVH as it limits brute force") {
  RandomScene scene(23, 20, 100);
  auto& [random, positions, indices, bvh] = scene;
  for (int r = 0; r < 2000; ++r) {
    const Ray ray = random_ray(random);
    const float limit = 1.0f + 4.0f * float(r % 7) / 7.0f;
    const RayHit a = bvh.intersect(ray, limit), b = intersect_triangles(ray, positions, indices, limit);
    REQUIRE(a.hit == b.hit);
    if (a.hit) CHECK(a.distance == doctest::Approx(b.distance));
    if (a.hit) CHECK(a.distance <= limit);
  }
}

TEST_CASE("skip_point: the BVH passes the triangles around one point, as brute force over the others does") {
  RandomScene scene(29, 20, 100);
  auto& [random, positions, indices, bvh] = scene;
  int skipped = 0;
  for (int r = 0; r < 3000; ++r) {
    const Ray ray = random_ray(random);
    const RayHit plain = bvh.intersect(ray);
    if (!plain.hit) continue;
    // Skip one corner of the triangle the ray hits first: brute force over the triangles without that corner.
    const std::uint32_t point = indices[3 * std::size_t{plain.triangle} + std::size_t(r % 3)];
    std::vector<std::uint32_t> others, original;  // the kept triangles, and their indices in `indices`
    for (std::size_t t = 0; t < indices.size(); t += 3)
      if (indices[t] != point && indices[t + 1] != point && indices[t + 2] != point) {
        others.insert(others.end(), {indices[t], indices[t + 1], indices[t + 2]});
        original.push_back(static_cast<std::uint32_t>(t / 3));
      }
    RayHit reference = brute_force(ray, positions, others);
    if (reference.hit) reference.triangle = original[reference.triangle];
    const RayHit hit = bvh.intersect(ray, std::numeric_limits<float>::infinity(), point);
    check_same(hit, reference, positions, indices, ray);
    if (hit.hit) {
      const std::uint32_t* c = &indices[3 * std::size_t{hit.triangle}];
      CHECK((c[0] != point && c[1] != point && c[2] != point));
    }
    ++skipped;
  }
  CHECK(skipped > 500);
}

TEST_CASE("build rejects bad triangles; an empty BVH never hits") {
  const std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  TriangleBvh bvh;
  CHECK_THROWS_AS(bvh.build(p, std::vector<std::uint32_t>{0, 1}), Error);
  CHECK_THROWS_AS(bvh.build(p, std::vector<std::uint32_t>{0, 1, 3}), Error);
  const std::vector<glm::vec3> bad = {{0, 0, 0}, {1, std::numeric_limits<float>::quiet_NaN(), 0}, {0, 1, 0}};
  CHECK_THROWS_AS(bvh.build(bad, std::vector<std::uint32_t>{0, 1, 2}), Error);
  TriangleBvh empty;
  CHECK_FALSE(empty.intersect(Ray{}).hit);
  CHECK_FALSE(empty.refit(p));
  empty.build(p, std::vector<std::uint32_t>{});
  CHECK_FALSE(empty.intersect(Ray{{0.2f, 0.2f, 1}, {0, 0, -1}}).hit);
  // A refit with a NaN position makes that triangle unpickable and leaves the others working.
  const std::vector<glm::vec3> two = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {6, 0, 0}, {5, 1, 0}};
  const std::vector<std::uint32_t> tris = {0, 1, 2, 3, 4, 5};
  bvh.build(two, tris);
  std::vector<glm::vec3> moved = two;
  moved[1].x = std::numeric_limits<float>::quiet_NaN();
  REQUIRE(bvh.refit(moved));
  CHECK_FALSE(bvh.intersect(Ray{{0.2f, 0.2f, 1}, {0, 0, -1}}).hit);
  CHECK(bvh.intersect(Ray{{5.2f, 0.2f, 1}, {0, 0, -1}}).triangle == 1);
}

TEST_CASE("a camera ray through a pixel passes through what that pixel shows") {
  const glm::mat4 view = glm::lookAt(glm::vec3(1, 2, 5), glm::vec3(0, 0.5f, 0), glm::vec3(0, 1, 0));
  const glm::mat4 projection = glm::perspective(glm::radians(50.0f), 800.0f / 600.0f, 0.1f, 100.0f);
  const glm::vec4 viewport(0, 0, 800, 600);
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int i = 0; i < 1000; ++i) {
    const glm::vec3 point{unit(random), unit(random), unit(random)};
    // Project with GL conventions, then flip y to window coordinates (top-left origin).
    const glm::vec3 window = glm::project(point, view, projection, viewport);
    const Ray ray = ray_from_pixel(view, projection, glm::vec2(window.x, 600.0f - window.y), viewport);
    CHECK(glm::length(ray.direction) == doctest::Approx(1.0f));
    const glm::vec3 to_point = point - ray.origin;
    const float along = glm::dot(to_point, ray.direction);
    CHECK(along > 0.0f);
    CHECK(glm::length(to_point - along * ray.direction) < 1e-4f);
  }
  // The centre pixel looks along the view direction.
  const Ray centre = ray_from_pixel(view, projection, glm::vec2(400, 300), viewport);
  CHECK(glm::dot(centre.direction, glm::normalize(glm::vec3(0, 0.5f, 0) - glm::vec3(1, 2, 5))) ==
        doctest::Approx(1.0f));
  // A pick of a quad in front of the camera through the pixel it projects to.
  const std::vector<glm::vec3> quad = {{-1, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 1, 0}};
  const std::vector<std::uint32_t> tris = {0, 1, 2, 0, 2, 3};
  const glm::vec3 w = glm::project(glm::vec3(0.5f, 0.25f, 0), view, projection, viewport);
  const RayHit hit =
      intersect_triangles(ray_from_pixel(view, projection, glm::vec2(w.x, 600.0f - w.y), viewport), quad, tris);
  REQUIRE(hit.hit);
  CHECK(hit.triangle == 0);
}

TEST_CASE("point_triangles maps render vertices to points") {
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.vertex_point = {0, 1, 2, 1};
  mesh.triangles = {0, 3, 2};
  CHECK(point_triangles(mesh) == std::vector<std::uint32_t>{0, 1, 2});
}
