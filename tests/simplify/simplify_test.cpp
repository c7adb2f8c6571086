// simplify_model (deform/simplify/simplify.hpp) on the built-in character and assimp-testmodels' rigged characters:
// the triangle count near its target, every kept point and render vertex its source's (place, weights, UV), no seam
// or border opened, and the simplified surface near the full one, posed, as a fraction of the model's size.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "import/skin_model.hpp"
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
#include "deform/simplify/simplify.hpp"
#if defined(DEFORM_HAVE_IMPORT)
#include "deform/import/import.hpp"
#endif

namespace {

using deform::Model;

float model_size(const Model& model) {
  const deform::Bounds b = deform::compute_bounds(model.mesh.positions);
  const glm::vec3 e = b.max - b.min;
  return std::max({e.x, e.y, e.z});
}

using import_test::skin;

// Edges (point pairs) used by one triangle only: the mesh's open borders, in points (seams are not edges here).
std::size_t open_edges(const deform::Mesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) {
      std::uint32_t a = mesh.vertex_point[mesh.triangles[3 * t + std::size_t(c)]];
      std::uint32_t b = mesh.vertex_point[mesh.triangles[3 * t + std::size_t(c + 1) % 3]];
      if (a > b) std::swap(a, b);
      if (a != b) ++uses[{a, b}];
    }
  return std::size_t(std::count_if(uses.begin(), uses.end(), [](const auto& u) { return u.second == 1; }));
}

// The closest point to p on triangle (a, b, c): the region of the triangle's plane p projects into (Voronoi regions
// of the corners, edges and face).
glm::vec3 closest_on_triangle(glm::vec3 p, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denominator = 1.0f / (va + vb + vc);
  return a + ab * (vb * denominator) + ac * (vc * denominator);
}

// Every full point's distance to the simplified surface (posed points `simple` over `mesh`'s triangles): mean and
// largest, fractions of the size.
std::pair<double, double> surface_gap(const std::vector<glm::vec3>& full, const std::vector<glm::vec3>& simple,
                                      const deform::Mesh& mesh, float size) {
  double mean = 0.0, largest = 0.0;
  for (const glm::vec3& p : full) {
    float nearest = std::numeric_limits<float>::max();
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      const auto corner = [&](int c) { return simple[mesh.vertex_point[mesh.triangles[3 * t + std::size_t(c)]]]; };
      nearest = std::min(nearest, glm::length(p - closest_on_triangle(p, corner(0), corner(1), corner(2))));
    }
    mean += nearest / size / double(full.size());
    largest = std::max(largest, double(nearest / size));
  }
  return {mean, largest};
}

void check_simplified(const std::string& name, const Model& model, float ratio, double largest_gap) {
  CAPTURE(name);
  CAPTURE(ratio);
  const deform::SimplifiedModel s = deform::simplify_model(model, {ratio, 0.05f});
  const deform::Mesh& in = model.mesh;
  const deform::Mesh& out = s.model.mesh;
  const double target = double(in.triangle_count()) * ratio;
  MESSAGE(name << " at " << ratio << ": " << out.triangle_count() << " of " << in.triangle_count() << " triangles, "
               << out.point_count() << " of " << in.point_count() << " points, error " << s.error);
  CHECK(double(out.triangle_count()) <= 1.25 * target + 3.0);  // short of it where borders are locked
  CHECK(double(out.triangle_count()) >= 0.5 * target);
  // Every kept point and render vertex is its source's.
  REQUIRE(s.source_point.size() == out.point_count());
  REQUIRE(s.source_vertex.size() == out.vertex_count());
  REQUIRE(s.model.weights.size() == out.point_count());
  for (std::size_t p = 0; p < out.point_count(); ++p) {
    const std::uint32_t from = s.source_point[p];
    CHECK(out.positions[p] == in.positions[from]);
    CHECK(s.model.weights.bones[p] == model.weights.bones[from]);
    CHECK(s.model.weights.weights[p] == model.weights.weights[from]);
  }
  for (std::size_t r = 0; r < out.vertex_count(); ++r) {
    const std::uint32_t from = s.source_vertex[r];
    CHECK(s.source_point[out.vertex_point[r]] == in.vertex_point[from]);
    if (!in.vertex_uvs.empty()) CHECK(out.vertex_uvs[r] == in.vertex_uvs[from]);
  }
  std::size_t submesh_triangles = 0;
  for (const deform::Submesh& sub : out.submeshes) submesh_triangles += sub.triangle_count;
  CHECK(submesh_triangles == out.triangle_count());
  // No seam or border opened: as many open edges (in points) as the full mesh has, or fewer.
  CHECK(open_edges(out) <= open_edges(in));
  // Posed, each kept point where its source goes (the same weights), the surface near the full one.
  std::mt19937 random(7);
  std::uniform_real_distribution<float> angle(-0.5f, 0.5f);
  deform::Pose pose = model.skeleton.bind_pose();
  for (glm::quat& q : pose.rotations) {
    const float x = angle(random), y = angle(random), z = angle(random);  // in this order on every compiler
    q = q * glm::quat(glm::vec3(x, y, z));
  }
  const std::vector<glm::vec3> full = skin(model, pose), simple = skin(s.model, pose);
  for (std::size_t p = 0; p < simple.size(); ++p) CHECK(simple[p] == full[s.source_point[p]]);
  const auto [mean, largest] = surface_gap(full, simple, out, model_size(model));
  MESSAGE("  posed: full points to the simplified surface, mean " << mean << ", largest " << largest << " of the size");
  CHECK(mean <= 0.01);
  CHECK(largest <= largest_gap);
}

}  // namespace

TEST_CASE("simplify_model on the built-in character") {
  const Model model = deform::builtin_character();
  check_simplified("builtin", model, 0.5f, 0.03);
  check_simplified("builtin", model, 0.25f, 0.04);
  check_simplified("builtin", model, 0.1f, 0.08);
  // The whole mesh kept at ratio 1 (nothing to collapse toward).
  const deform::SimplifiedModel whole = deform::simplify_model(model, {1.0f, 0.0f});
  CHECK(whole.model.mesh.triangle_count() == model.mesh.triangle_count());
}

TEST_CASE("simplify_model refuses settings out of range and empty meshes, naming them") {
  const Model model = deform::builtin_character();
  const auto refused = [&](const Model& m, deform::SimplifySettings settings, const std::string& element) {
    try {
      (void)deform::simplify_model(m, settings);
      FAIL("accepted");
    } catch (const deform::Error& error) {
      CHECK(std::string(error.what()).find(element) != std::string::npos);
    }
  };
  refused(model, {0.0f, 0.01f}, "triangle_ratio");
  refused(model, {1.5f, 0.01f}, "triangle_ratio");
  refused(model, {0.5f, -1.0f}, "max_error");
  refused(model, {std::numeric_limits<float>::quiet_NaN(), 0.01f}, "triangle_ratio");
  Model empty = model;
  empty.mesh.triangles.clear();
  refused(empty, {0.5f, 0.01f}, "mesh");
  Model broken = model;
  broken.mesh.triangles[7] = std::uint32_t(broken.mesh.vertex_count());
  refused(broken, {0.5f, 0.01f}, "mesh");
}

#if defined(DEFORM_HAVE_IMPORT)
TEST_CASE("simplify_model on assimp-testmodels' rigged characters") {
  const std::string dir = "/usr/share/assimp/models/";
  for (const char* path : {"IQM/mrfixit.iqm", "X/Testwuson.X"}) {
    REQUIRE_MESSAGE(std::filesystem::exists(dir + path), path << " is missing: install Debian's assimp-testmodels");
    const deform::ImportedModel imported = deform::import_model(dir + path);
    REQUIRE(imported.rigged);
    check_simplified(path, imported.model, 0.5f, 0.04);
    check_simplified(path, imported.model, 0.25f, 0.06);
  }
}
#endif

// A Character level on simplified meshes, built as docs/skinning.md says: nested simplifications, the model's points
// renumbered so that each level is a prefix, the simplified triangles drawn from the full character's arrays through
// source_vertex, source_point and the renumbering.
TEST_CASE("simplified meshes as Character levels: prefixes after order_points_first, drawn through the maps") {
  Model model = deform::builtin_character();
  const deform::SimplifiedModel near = deform::simplify_model(model, {0.25f, 0.05f});
  const deform::SimplifiedModel far = deform::simplify_model(near.model, {0.4f, 0.05f});
  std::vector<std::uint32_t> first;
  for (const std::uint32_t p : far.source_point) first.push_back(near.source_point[p]);
  for (const std::uint32_t p : near.source_point)
    if (std::find(first.begin(), first.end(), p) == first.end()) first.push_back(p);
  const Model before = model;
  const deform::PointOrder order = deform::order_points_first(model, first);
  deform::Character hero(model);
  deform::Character whole(model);
  std::vector<std::uint32_t> prefix(near.source_point.size());
  std::iota(prefix.begin(), prefix.end(), 0u);
  std::vector<deform::Character::LevelOptions> options = {{true, 1}, {false, 1}, {false, 1}};
  options[1].points = prefix;
  options[2].points = std::span<const std::uint32_t>(prefix).first(far.source_point.size());
  deform::BoneLodSettings lod;
  lod.bones_per_level = {20, 20};
  hero.set_levels(deform::build_bone_lod(hero.model(), lod), options);
  whole.set_levels(deform::build_bone_lod(whole.model(), lod), {{{true, 1}, {false, 1}, {false, 1}}});
  CHECK(hero.level_cost(2).points == far.model.mesh.point_count());
  deform::Pose pose = hero.skeleton().bind_pose();
  pose.rotations[5] = glm::angleAxis(0.6f, glm::vec3(1.0f, 0.0f, 0.0f));
  for (deform::Character* c : {&hero, &whole}) {
    REQUIRE(c->set_level(2));
    REQUIRE(c->set_pose(pose));
    REQUIRE(c->update(0.0f));
    REQUIRE(c->update(0.0f));  // past the switch's update (which deforms the outgoing level 0 too)
  }
  const auto normals = hero.normals(), whole_normals = whole.normals();
  // Each corner of far's triangles: its render vertex in the renumbered full mesh, and that vertex's point.
  for (const std::uint32_t v : far.model.mesh.triangles) {
    const std::uint32_t full_vertex = order.vertex[near.source_vertex[far.source_vertex[v]]];
    const std::uint32_t full_point = hero.model().mesh.vertex_point[full_vertex];
    CHECK(full_point == order.point[near.source_point[far.source_point[far.model.mesh.vertex_point[v]]]]);
    CHECK(full_point < far.model.mesh.point_count());  // in level 2's prefix
    CHECK(hero.positions()[full_point] == whole.positions()[full_point]);
    CHECK(normals[full_vertex] == whole_normals[full_vertex]);
    CHECK(hero.model().mesh.positions[full_point] == far.model.mesh.positions[far.model.mesh.vertex_point[v]]);
  }
  CHECK(before.mesh.point_count() == model.mesh.point_count());
}
