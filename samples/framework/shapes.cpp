#include "shapes.hpp"

#include <cmath>

namespace sample {
namespace {

// Appends a render vertex that is its own point.
std::uint32_t add_vertex(deform::Mesh& m, glm::vec3 p, glm::vec3 n, glm::vec2 uv) {
  const auto index = static_cast<std::uint32_t>(m.positions.size());
  m.positions.push_back(p);
  m.vertex_point.push_back(index);
  m.vertex_normals.push_back(n);
  m.vertex_uvs.push_back(uv);
  return index;
}

}  // namespace

deform::Mesh make_floor(float size, int cells) {
  deform::Mesh m;
  deform::Material light, dark;
  light.name = "floor_light";
  light.diffuse = glm::vec3(0.55f, 0.57f, 0.6f);
  dark.name = "floor_dark";
  dark.diffuse = glm::vec3(0.38f, 0.4f, 0.44f);
  m.materials = {light, dark};
  const float cell = size / float(cells);
  for (int parity = 0; parity < 2; ++parity) {
    deform::Submesh s;
    s.first_triangle = static_cast<std::uint32_t>(m.triangle_count());
    s.material = parity;
    for (int z = 0; z < cells; ++z)
      for (int x = 0; x < cells; ++x) {
        if ((x + z) % 2 != parity) continue;
        const float x0 = -0.5f * size + float(x) * cell, z0 = -0.5f * size + float(z) * cell;
        const glm::vec3 up(0, 1, 0);
        const std::uint32_t a = add_vertex(m, {x0, 0, z0}, up, {0, 0});
        const std::uint32_t b = add_vertex(m, {x0, 0, z0 + cell}, up, {0, 1});
        const std::uint32_t c = add_vertex(m, {x0 + cell, 0, z0 + cell}, up, {1, 1});
        const std::uint32_t d = add_vertex(m, {x0 + cell, 0, z0}, up, {1, 0});
        m.triangles.insert(m.triangles.end(), {a, b, c, a, c, d});
      }
    s.triangle_count = static_cast<std::uint32_t>(m.triangle_count()) - s.first_triangle;
    m.submeshes.push_back(s);
  }
  return m;
}

deform::Mesh make_sphere(float radius, int rings, int segments, glm::vec3 colour) {
  deform::Mesh m;
  deform::Material material;
  material.name = "ball";
  material.diffuse = colour;
  material.specular = glm::vec3(0.5f);
  material.shininess = 40.0f;
  m.materials = {material};
  const float pi = 3.14159265f;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s <= segments; ++s) {
      const float theta = pi * float(r) / float(rings), phi = 2.0f * pi * float(s) / float(segments);
      const glm::vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
      add_vertex(m, radius * n, n, {float(s) / float(segments), float(r) / float(rings)});
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const auto a = static_cast<std::uint32_t>(r * (segments + 1) + s),
                 b = a + static_cast<std::uint32_t>(segments + 1);
      m.triangles.insert(m.triangles.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
  m.submeshes.push_back({0, static_cast<std::uint32_t>(m.triangle_count()), 0});
  return m;
}

}  // namespace sample
