// Euler angles (X·Y·Z, degrees) <-> quaternions: hand values, seeded round trips, gimbal lock, clamping.
#include <doctest/doctest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <random>

#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
namespace {

// Rx·Ry·Rz built independently of the library, from glm::rotate.
glm::mat3 reference_matrix(glm::vec3 degrees) {
  glm::mat4 m(1.0f);
  m = glm::rotate(m, glm::radians(degrees.x), {1, 0, 0});
  m = glm::rotate(m, glm::radians(degrees.y), {0, 1, 0});
  m = glm::rotate(m, glm::radians(degrees.z), {0, 0, 1});
  return glm::mat3(m);
}

float max_difference(const glm::mat3& a, const glm::mat3& b) {
  float d = 0.0f;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) d = std::max(d, std::abs(a[c][r] - b[c][r]));
  return d;
}

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

bool in_canonical_range(glm::vec3 e) {
  return e.x >= -180.0f && e.x <= 180.0f && e.y >= -90.0f && e.y <= 90.0f && e.z >= -180.0f && e.z <= 180.0f;
}

}  // namespace

TEST_CASE("quat_from_euler: hand values") {
  const float h = std::sqrt(0.5f);
  const glm::quat x = deform::quat_from_euler({90, 0, 0});
  CHECK(x.w == doctest::Approx(h));
  CHECK(x.x == doctest::Approx(h));
  CHECK(x.y == doctest::Approx(0.0f));
  CHECK(x.z == doctest::Approx(0.0f));
  const glm::quat y = deform::quat_from_euler({0, -90, 0});
  CHECK(y.w == doctest::Approx(h));
  CHECK(y.y == doctest::Approx(-h));
  const glm::quat z = deform::quat_from_euler({0, 0, 180});
  CHECK(z.w == doctest::Approx(0.0f).epsilon(1e-6));
  CHECK(z.z == doctest::Approx(1.0f));
  // q = qx · qy · qz
  const glm::quat xyz = deform::quat_from_euler({30, 40, 50});
  const glm::quat product =
      deform::quat_from_euler({30, 0, 0}) * deform::quat_from_euler({0, 40, 0}) * deform::quat_from_euler({0, 0, 50});
  CHECK(glm::abs(glm::dot(xyz, product)) == doctest::Approx(1.0f));
}

TEST_CASE("quat_from_euler is the rotation Rx·Ry·Rz (seeded, 5000 triples)") {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> angle(-360.0f, 360.0f);
  for (int i = 0; i < 5000; ++i) {
    const glm::vec3 e{angle(rng), angle(rng), angle(rng)};
    CHECK(max_difference(glm::mat3_cast(deform::quat_from_euler(e)), reference_matrix(e)) < 2e-6f);
  }
}

TEST_CASE("euler_from_quat: hand values and the canonical range") {
  CHECK(glm::all(
      glm::lessThan(glm::abs(deform::euler_from_quat(deform::quat_from_euler({30, 40, 50})) - glm::vec3(30, 40, 50)),
                    glm::vec3(1e-4f))));
  // (x + 180, 180 - y, z + 180) is the same rotation; the canonical answer has |y| <= 90.
  const glm::vec3 e = deform::euler_from_quat(deform::quat_from_euler({10, 120, -20}));
  CHECK(e.x == doctest::Approx(-170.0f));
  CHECK(e.y == doctest::Approx(60.0f));
  CHECK(e.z == doctest::Approx(160.0f));
  CHECK(deform::euler_from_quat(glm::quat(1, 0, 0, 0)) == glm::vec3(0.0f));
  // Degenerate input never gives NaN.
  CHECK(finite(deform::euler_from_quat(glm::quat(0, 0, 0, 0))));
  CHECK(finite(deform::euler_from_quat(glm::quat(2, 0, 0, 0))));
}

TEST_CASE("round trip over seeded random angles: same angles away from gimbal lock, same rotation always") {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> angle(-179.9f, 179.9f);
  std::uniform_real_distribution<float> pitch(-85.0f, 85.0f);
  for (int i = 0; i < 10000; ++i) {
    const glm::vec3 e{angle(rng), pitch(rng), angle(rng)};
    const glm::vec3 back = deform::euler_from_quat(deform::quat_from_euler(e));
    REQUIRE(finite(back));
    CHECK(glm::all(glm::lessThan(glm::abs(back - e), glm::vec3(2e-3f))));
  }
  // Any angles, including beyond ±90 on y: compare rotations.
  std::uniform_real_distribution<float> any(-720.0f, 720.0f);
  for (int i = 0; i < 10000; ++i) {
    const glm::vec3 e{any(rng), any(rng), any(rng)};
    const glm::vec3 back = deform::euler_from_quat(deform::quat_from_euler(e));
    REQUIRE(finite(back));
    CHECK(in_canonical_range(back));
    CHECK(max_difference(reference_matrix(back), reference_matrix(e)) < 1e-5f);
  }
}

TEST_CASE("gimbal lock: y = ±90 and within a hair of it, no NaN, same rotation") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> angle(-180.0f, 180.0f);
  const float pitches[] = {90.0f, -90.0f, 89.9999f, -89.9999f, 90.0001f, -90.0001f, 89.99f, -89.99f, 89.0f};
  for (const float y : pitches)
    for (int i = 0; i < 1000; ++i) {
      const glm::vec3 e{angle(rng), y, angle(rng)};
      const glm::quat q = deform::quat_from_euler(e);
      const glm::vec3 back = deform::euler_from_quat(q);
      REQUIRE(finite(back));
      CHECK(in_canonical_range(back));
      CHECK(max_difference(glm::mat3_cast(deform::quat_from_euler(back)), glm::mat3_cast(q)) < 2e-5f);
    }
  // Exactly at the lock the whole X/Z rotation goes on x.
  const glm::vec3 locked = deform::euler_from_quat(deform::quat_from_euler({20, 90, 30}));
  CHECK(locked.x == doctest::Approx(50.0f).epsilon(1e-3));
  CHECK(locked.y == doctest::Approx(90.0f));
  CHECK(locked.z == 0.0f);
  const glm::vec3 locked_down = deform::euler_from_quat(deform::quat_from_euler({20, -90, 30}));
  CHECK(locked_down.x == doctest::Approx(-10.0f).epsilon(1e-3));
  CHECK(locked_down.z == 0.0f);
}

TEST_CASE("random unit quaternions survive quat -> euler -> quat (seeded, 10000)") {
  std::mt19937 rng(99);
  std::normal_distribution<float> n(0.0f, 1.0f);
  for (int i = 0; i < 10000; ++i) {
    const glm::quat q = glm::normalize(glm::quat{n(rng), n(rng), n(rng), n(rng)});
    const glm::quat back = deform::quat_from_euler(deform::euler_from_quat(q));
    CHECK(glm::abs(glm::dot(q, back)) > 1.0f - 1e-6f);
  }
}

TEST_CASE("clamp_euler and within_limits") {
  deform::DofLimits limits;
  limits.min = {-10, 0, -90};
  limits.max = {10, 0, 45};
  CHECK(deform::clamp_euler({-20, 5, 50}, limits) == glm::vec3(-10, 0, 45));
  CHECK(deform::clamp_euler({3, 0, -30}, limits) == glm::vec3(3, 0, -30));
  CHECK(deform::within_limits({3, 0, -30}, limits));
  CHECK(deform::within_limits({10.0005f, 0, -30}, limits));
  CHECK_FALSE(deform::within_limits({10.1f, 0, -30}, limits));
  CHECK_FALSE(deform::within_limits({0, 0.01f, 0}, limits, 0.0f));
  CHECK_FALSE(deform::within_limits({0, std::nanf(""), 0}, limits));
  CHECK(deform::within_limits({180, -180, 180}, deform::DofLimits{}));
}
