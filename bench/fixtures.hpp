#pragma once
// Meshes and frames that several benchmarks share (normals/*, mush/*), so that their figures are of the same input:
// the built-in character, a 100,000-point torus, and points bent a little differently each frame so that no two
// frames are alike to the caches' eyes.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/runtime/mesh.hpp"

namespace bench_fixtures {

// A closed torus of n x m points, its render vertices split along the u = 0 and v = 0 seams ((n + 1) x (m + 1)),
// as a textured mesh's are.
inline deform::Mesh seamed_torus(int n, int m) {
  deform::Mesh mesh;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const float u = 2 * std::numbers::pi_v<float> * float(i) / float(n);
      const float v = 2 * std::numbers::pi_v<float> * float(j) / float(m);
      mesh.positions.emplace_back((1 + 0.4f * std::cos(v)) * std::cos(u), (1 + 0.4f * std::cos(v)) * std::sin(u),
                                  0.4f * std::sin(v));
    }
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= m; ++j) mesh.vertex_point.push_back(std::uint32_t((i % n) * m + j % m));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const auto a = std::uint32_t(i * (m + 1) + j), b = a + std::uint32_t(m + 1), c = b + 1, d = a + 1;
      mesh.triangles.insert(mesh.triangles.end(), {a, b, c, a, c, d});
    }
  return mesh;
}

// The built-in character (2,850 points) or the 400 x 250 torus (100,000 points), made once.
inline const deform::Mesh& mesh(bool builtin) {
  static const deform::Mesh character = deform::builtin_character().mesh;
  static const deform::Mesh big = seamed_torus(400, 250);
  return builtin ? character : big;
}

// The points bent a little differently for each frame (16 different bends, then again).
inline std::vector<glm::vec3> bent_points(const deform::Mesh& m, int frame) {
  std::vector<glm::vec3> points;
  const float bend = 0.05f * float(frame % 16);
  for (const glm::vec3& p : m.positions) points.emplace_back(p.x + bend * p.y * p.y, p.y, p.z + bend * p.x * p.y);
  return points;
}

}  // namespace bench_fixtures
