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

namespace {

// simplify_levels on one model: the chain of simplify_model it stands for (each level from the one before, at its
// share of the level before's triangles), nested point lists with each coarser level's first, every corner's point in
// its level, and, after order_points_first and renumber_levels, each level's points a prefix of the renumbered model
// whose triangles draw what the level's own did.
void check_levels(const std::string& name, const Model& model) {
  CAPTURE(name);
  const std::vector<deform::SimplifySettings> settings = {{0.5f, 0.05f}, {0.25f, 0.05f}, {0.1f, 0.05f}};
  std::vector<deform::MeshLevel> levels = deform::simplify_levels(model, settings);
  REQUIRE(levels.size() == 3);
  // The chain by hand: 0.5, then 0.5 of that, then 0.4 of that.
  const deform::SimplifiedModel mid = deform::simplify_model(model, settings[0]);
  const deform::SimplifiedModel near = deform::simplify_model(mid.model, {0.5f, 0.05f});
  const deform::SimplifiedModel far = deform::simplify_model(near.model, {0.4f, 0.05f});
  const deform::SimplifiedModel* chain[3] = {&mid, &near, &far};
  for (std::size_t l = 0; l < 3; ++l) {
    CAPTURE(l);
    const deform::Mesh& own = chain[l]->model.mesh;
    REQUIRE(levels[l].triangles.size() == own.triangles.size());
    CHECK(levels[l].points.size() == own.point_count());
    CHECK(levels[l].submeshes.size() == own.submeshes.size());
    for (std::size_t c = 0; c < own.triangles.size(); ++c) {
      std::uint32_t v = own.triangles[c];
      for (std::size_t up = l + 1; up-- > 0;) v = chain[up]->source_vertex[v];
      CHECK(levels[l].triangles[c] == v);
    }
    std::vector<char> member(model.mesh.point_count(), 0);
    for (const std::uint32_t p : levels[l].points) {
      REQUIRE(p < member.size());
      CHECK(member[p] == 0);  // each once
      member[p] = 1;
    }
    for (const std::uint32_t v : levels[l].triangles) CHECK(member[model.mesh.vertex_point[v]] == 1);
    if (l > 0) {
      CHECK(levels[l].points.size() < levels[l - 1].points.size());
      CHECK(std::equal(levels[l].points.begin(), levels[l].points.end(), levels[l - 1].points.begin()));
      CHECK(levels[l].error >= levels[l - 1].error);
    }
  }
  MESSAGE(name << ": " << levels[0].points.size() << ", " << levels[1].points.size() << ", " << levels[2].points.size()
               << " of " << model.mesh.point_count() << " points; errors " << levels[0].error << ", " << levels[1].error
               << ", " << levels[2].error);
  // Renumbered: prefixes, and the same corners in the same places.
  const std::vector<std::vector<std::uint32_t>> before = {levels[0].triangles, levels[1].triangles,
                                                          levels[2].triangles};
  Model renumbered = model;
  const deform::PointOrder order = deform::order_points_first(renumbered, levels.front().points);
  deform::renumber_levels(levels, order);
  for (std::size_t l = 0; l < 3; ++l) {
    for (std::size_t i = 0; i < levels[l].points.size(); ++i) CHECK(levels[l].points[i] == i);
    for (std::size_t c = 0; c < levels[l].triangles.size(); ++c) {
      const std::uint32_t v = levels[l].triangles[c];
      CHECK(renumbered.mesh.vertex_point[v] < levels[l].points.size());
      CHECK(renumbered.mesh.positions[renumbered.mesh.vertex_point[v]] ==
            model.mesh.positions[model.mesh.vertex_point[before[l][c]]]);
      if (!model.mesh.vertex_uvs.empty()) CHECK(renumbered.mesh.vertex_uvs[v] == model.mesh.vertex_uvs[before[l][c]]);
    }
  }
}

}  // namespace

TEST_CASE("simplify_levels: nested meshes whose points become prefixes") {
  check_levels("builtin", deform::builtin_character());
#if defined(DEFORM_HAVE_IMPORT)
  for (const char* path : {"IQM/mrfixit.iqm", "X/Testwuson.X"}) {
    const std::string file = std::string("/usr/share/assimp/models/") + path;
    REQUIRE_MESSAGE(std::filesystem::exists(file), path << " is missing: install Debian's assimp-testmodels");
    check_levels(path, deform::import_model(file).model);
  }
#endif
  const Model model = deform::builtin_character();
  for (const std::vector<deform::SimplifySettings>& refused :
       {std::vector<deform::SimplifySettings>{}, {{0.25f, 0.05f}, {0.5f, 0.05f}}, {{0.5f, 0.05f}, {0.0f, 0.05f}}}) {
    try {
      (void)deform::simplify_levels(model, refused);
      FAIL("accepted");
    } catch (const deform::Error& error) {
      CHECK(std::string(error.what())
                .find(refused.size() == 2 && refused[1].triangle_ratio == 0.0f ? "triangle_ratio" : "levels") !=
            std::string::npos);
    }
  }
}

// A Character level on simplified meshes, built as docs/skinning.md says: simplify_levels, the model's points
// renumbered so that each level is a prefix, the simplified triangles drawn from the full character's arrays.
TEST_CASE("simplified meshes as Character levels: prefixes after order_points_first, drawn through the maps") {
  Model model = deform::builtin_character();
  const Model before = model;
  const std::vector<deform::SimplifySettings> settings = {{0.25f, 0.05f}, {0.1f, 0.05f}};
  std::vector<deform::MeshLevel> levels = deform::simplify_levels(model, settings);
  const deform::PointOrder order = deform::order_points_first(model, levels.front().points);
  deform::renumber_levels(levels, order);
  deform::Character hero(model);
  deform::Character whole(model);
  std::vector<deform::Character::LevelOptions> options = {{true, 1}, {false, 1}, {false, 1}};
  options[1].points = levels[0].points;
  options[2].points = levels[1].points;
  deform::BoneLodSettings lod;
  lod.bones_per_level = {20, 20};
  hero.set_levels(deform::build_bone_lod(hero.model(), lod), options);
  whole.set_levels(deform::build_bone_lod(whole.model(), lod), {{{true, 1}, {false, 1}, {false, 1}}});
  CHECK(hero.level_cost(2).points == levels[1].points.size());
  deform::Pose pose = hero.skeleton().bind_pose();
  pose.rotations[5] = glm::angleAxis(0.6f, glm::vec3(1.0f, 0.0f, 0.0f));
  for (deform::Character* c : {&hero, &whole}) {
    REQUIRE(c->set_level(2));
    REQUIRE(c->set_pose(pose));
    REQUIRE(c->update(0.0f));
    REQUIRE(c->update(0.0f));  // past the switch's update (which deforms the outgoing level 0 too)
  }
  const auto normals = hero.normals(), whole_normals = whole.normals();
  // Each corner of level 2's triangles: a render vertex of the renumbered full mesh, drawn as the whole level draws it.
  for (const std::uint32_t full_vertex : levels[1].triangles) {
    const std::uint32_t full_point = hero.model().mesh.vertex_point[full_vertex];
    CHECK(full_point < levels[1].points.size());  // in level 2's prefix
    CHECK(hero.positions()[full_point] == whole.positions()[full_point]);
    CHECK(normals[full_vertex] == whole_normals[full_vertex]);
  }
  CHECK(before.mesh.point_count() == model.mesh.point_count());
}
