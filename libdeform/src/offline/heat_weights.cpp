// Bone heat weights (heat_weights.hpp): welded surface, nearest visible bone, cotangent Laplacian, one sparse LDLᵀ
// factorisation, one solve per heated bone.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "deform/offline/heat_weights.hpp"
#include "deform/offline/picking.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "bone_shapes.hpp"
#include "finite.hpp"
namespace deform {
namespace {

// Influences below this fraction of a point's total are dropped (as the distance method does).
constexpr float min_weight = 1e-3f;
// The uniform Laplacian's share, relative to the mean cotangent weight.
constexpr double uniform_share = 1e-3;
// Nearest bones tried for visibility per point before the point is declared to see none.
constexpr std::size_t max_visibility_tries = 32;
// A bone heats a point only from behind the surface: the direction to the bone at most 78° from the inward normal
// (cos 78° ≈ 0.2). A bone beside or in front of the surface is another part's (a finger resting on the hip).
constexpr float max_facing = -0.2f;

void check_options(const HeatWeightsOptions& o, std::size_t bone_count) {
  auto fail = [](const char* what, const std::string& rule) { throw Error::invalid_argument(what, rule); };
  if (o.max_influences < 1 || o.max_influences > max_requested_influences)
    fail("max_influences", "must be 1 to " + std::to_string(max_requested_influences));
  if (!std::isfinite(o.heat) || o.heat <= 0.0f) fail("heat", "must be finite and > 0");
  if (!std::isfinite(o.leaf_length) || o.leaf_length < 0.0f) fail("leaf_length", "must be finite and >= 0");
  if (!std::isfinite(o.oblique_penalty) || o.oblique_penalty < 0.0f) fail("oblique_penalty", "must be finite and >= 0");
  if (o.smoothing_iterations < 0 || o.smoothing_iterations > 100) fail("smoothing_iterations", "must be 0 to 100");
  if (!o.deforming.empty()) {
    if (o.deforming.size() != bone_count) fail("deforming", "must be empty or hold one entry per bone");
    if (std::none_of(o.deforming.begin(), o.deforming.end(), [](std::uint8_t d) { return d != 0; }))
      fail("deforming", "no bone deforms");
  }
}

// The nearest point of segment [a, b] to p.
glm::vec3 nearest_on_segment(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
  const glm::vec3 axis = b - a;
  const float length2 = glm::dot(axis, axis);
  if (length2 <= 0.0f) return a;
  const float t = std::clamp(glm::dot(p - a, axis) / length2, 0.0f, 1.0f);
  return a + t * axis;
}

// The nearest point of a bone to p.
glm::vec3 nearest_on_bone(glm::vec3 p, const detail::BoneShape& shape) {
  glm::vec3 best = shape.segments.front().first;
  float best2 = INFINITY;
  for (const auto& [a, b] : shape.segments) {
    const glm::vec3 q = nearest_on_segment(p, a, b);
    const float d2 = glm::dot(q - p, q - p);
    if (d2 < best2) {
      best2 = d2;
      best = q;
    }
  }
  return best;
}

struct Influence {
  std::uint32_t bone;
  float weight;
};

// The strongest few influences of one point, kept while bones are solved one by one.
struct Strongest {
  std::array<Influence, max_requested_influences> slot{};
  int used = 0;
  void offer(std::uint32_t bone, float weight, int keep) {
    if (used < keep) {
      slot[static_cast<std::size_t>(used++)] = {bone, weight};
    } else {
      int weakest = 0;
      for (int k = 1; k < used; ++k)
        if (slot[static_cast<std::size_t>(k)].weight < slot[static_cast<std::size_t>(weakest)].weight) weakest = k;
      if (weight <= slot[static_cast<std::size_t>(weakest)].weight) return;
      slot[static_cast<std::size_t>(weakest)] = {bone, weight};
    }
  }
};

// Appends point's influences to `weights`: those under min_weight of the sum dropped, the rest normalised, strongest
// first, past the fourth in the extras (append_influences). `fallback` alone when none is left.
void store(const Strongest& s, std::uint32_t fallback, SkinWeights& weights) {
  float total = 0.0f;
  for (int k = 0; k < s.used; ++k) total += s.slot[static_cast<std::size_t>(k)].weight;
  std::array<std::uint16_t, max_requested_influences> bones{};
  std::array<float, max_requested_influences> values{};
  std::size_t kept = 0;
  for (int k = 0; k < s.used; ++k) {
    const Influence& in = s.slot[static_cast<std::size_t>(k)];
    if (!(total > 0.0f) || in.weight < min_weight * total) continue;
    bones[kept] = static_cast<std::uint16_t>(in.bone);
    values[kept++] = in.weight;
  }
  append_influences(weights, std::span(bones.data(), kept), std::span(values.data(), kept),
                    static_cast<std::uint16_t>(fallback));
}

std::string bone_label(const Skeleton& skeleton, std::uint32_t bone) {
  return "bone '" + skeleton.key(static_cast<std::int32_t>(bone)) + "' (id " + std::to_string(bone) + ")";
}

std::string position_text(glm::vec3 p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.4g, %.4g, %.4g)", static_cast<double>(p.x), static_cast<double>(p.y),
                static_cast<double>(p.z));
  return text;
}

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

std::vector<std::string> bones_without_vertices(const SkinWeights& weights, const Skeleton& skeleton,
                                                const std::vector<std::uint8_t>& deforming) {
  std::vector<std::uint8_t> used(skeleton.bone_count(), 0);
  for (std::size_t i = 0; i < weights.size(); ++i)
    for (int k = 0; k < max_influences; ++k)
      if (weights.weights[i][k] > 0.0f && weights.bones[i][k] < used.size()) used[weights.bones[i][k]] = 1;
  std::vector<std::string> warnings;
  for (std::size_t b = 0; b < used.size(); ++b) {
    if (used[b] || (!deforming.empty() && b < deforming.size() && deforming[b] == 0)) continue;
    warnings.push_back(bone_label(skeleton, static_cast<std::uint32_t>(b)) + " gets no vertex");
  }
  return warnings;
}

WeightsResult compute_heat_weights(const Mesh& mesh, const Skeleton& skeleton, const HeatWeightsOptions& options) {
  const std::size_t bone_count = skeleton.bone_count();
  check_options(options, bone_count);
  auto deforms = [&](std::size_t b) { return options.deforming.empty() || options.deforming[b] != 0; };
  const std::size_t point_count = mesh.point_count();
  const std::vector<std::uint32_t> corners = detail::checked_corners(mesh);

  WeightsResult result;
  result.weights.bones.assign(point_count, glm::u16vec4(0));
  result.weights.weights.assign(point_count, glm::vec4(0.0f));
  if (point_count == 0) {
    result.warnings = bones_without_vertices(result.weights, skeleton, options.deforming);
    return result;
  }

  // --- weld points by exact position: `welded[point]` = surface vertex ---
  std::vector<std::uint32_t> order(point_count);
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    const glm::vec3 p = mesh.positions[a], q = mesh.positions[b];
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    if (p.z != q.z) return p.z < q.z;
    return a < b;
  };
  std::sort(order.begin(), order.end(), less);
  std::vector<std::uint32_t> welded(point_count);
  std::vector<glm::vec3> position;         // per surface vertex
  std::vector<std::uint32_t> first_point;  // per surface vertex: its lowest point index
  for (std::size_t k = 0; k < point_count; ++k) {
    const std::uint32_t p = order[k];
    if (k == 0 || mesh.positions[p] != mesh.positions[order[k - 1]]) {
      position.push_back(mesh.positions[p]);
      first_point.push_back(p);
    }
    welded[p] = static_cast<std::uint32_t>(position.size() - 1);
  }
  const std::size_t n = position.size();
  const Bounds bounds = compute_bounds(position);
  const float diagonal = std::max(glm::length(bounds.max - bounds.min), 1e-30f);

  // --- triangles over surface vertices (repeated corners dropped), islands ---
  std::vector<std::array<std::uint32_t, 3>> triangles;
  triangles.reserve(corners.size() / 3);
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (std::size_t t = 0; t + 2 < corners.size(); t += 3) {
    const std::array<std::uint32_t, 3> tri{welded[corners[t]], welded[corners[t + 1]], welded[corners[t + 2]]};
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    triangles.push_back(tri);
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find_root(parent, tri[0]), b = find_root(parent, tri[static_cast<std::size_t>(k)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::vector<std::uint32_t> island(n);
  std::vector<std::uint32_t> island_of_root(n, UINT32_MAX);
  std::size_t island_count = 0;
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t r = find_root(parent, v);
    if (island_of_root[r] == UINT32_MAX) island_of_root[r] = static_cast<std::uint32_t>(island_count++);
    island[v] = island_of_root[r];
  }

  // --- heat: the nearest visible bone of every surface vertex ---
  std::vector<detail::BoneShape> shapes = detail::bone_shapes(skeleton, options.leaf_length);
  std::vector<std::uint32_t> candidates;
  for (std::size_t b = 0; b < bone_count; ++b)
    if (deforms(b)) candidates.push_back(static_cast<std::uint32_t>(b));
  auto build_bvh = [&](TriangleBvh& bvh, std::uint32_t only_island) {
    std::vector<std::uint32_t> flat;
    for (const auto& t : triangles)
      if (only_island == UINT32_MAX || island[t[0]] == only_island) flat.insert(flat.end(), t.begin(), t.end());
    if (!flat.empty()) bvh.build(position, flat);
  };
  const float offset = 1e-5f * diagonal;  // the ray starts this far from the surface, off its own triangles
  const float min_distance = 1e-4f * diagonal;
  std::vector<std::uint32_t> heated_by(n, UINT32_MAX);  // bone, or none
  std::vector<double> heat(n, 0.0);
  std::vector<std::uint32_t> nearest_any(n, 0);  // nearest deforming bone, seen or not
  std::vector<std::pair<float, std::uint32_t>> by_distance(candidates.size());
  std::vector<glm::vec3> nearest_point(bone_count);
  // Outward vertex normals: area-weighted, each island turned so that most of its points have their nearest bone
  // behind them (a model may wind its triangles either way; a piece's winding is consistent more often than not).
  std::vector<glm::vec3> normal(n, glm::vec3(0.0f));
  auto orient_normals = [&] {
    for (const auto& t : triangles) {
      const glm::vec3 face = glm::cross(position[t[1]] - position[t[0]], position[t[2]] - position[t[0]]);
      for (std::uint32_t c : t) normal[c] += face;
    }
    std::vector<std::int64_t> votes(island_count, 0);
    for (std::uint32_t v = 0; v < n; ++v) {
      float best = INFINITY;
      glm::vec3 to_bone(0.0f);
      for (std::uint32_t b : candidates) {
        const glm::vec3 q = nearest_on_bone(position[v], shapes[b]);
        const float d2 = glm::dot(q - position[v], q - position[v]);
        if (d2 < best) {
          best = d2;
          to_bone = q - position[v];
        }
      }
      const float side = glm::dot(to_bone, normal[v]);
      votes[island[v]] += side < 0.0f ? 1 : side > 0.0f ? -1 : 0;
    }
    for (std::uint32_t v = 0; v < n; ++v) {
      const float length = glm::length(normal[v]);
      normal[v] = length > 0.0f ? normal[v] / (votes[island[v]] < 0 ? -length : length) : glm::vec3(0.0f);
    }
  };
  // Heats v from its nearest bone that `bvh` (null: nothing) does not hide; with `facing`, only from a bone behind
  // the surface (a point in no triangle has no side and takes any). v's own triangles never hide a bone: the segment
  // crosses them only at a sharp or creased corner of a coarse mesh, while what the test is for is another part of
  // the body in between.
  auto heat_vertex = [&](std::uint32_t v, const TriangleBvh* bvh, bool facing) {
    const glm::vec3 p = position[v];
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const glm::vec3 q = nearest_on_bone(p, shapes[candidates[c]]);
      nearest_point[candidates[c]] = q;
      by_distance[c] = {glm::length(q - p), candidates[c]};
    }
    const std::size_t tries = std::min(by_distance.size(), max_visibility_tries);
    const auto tried_end = by_distance.begin() + static_cast<std::ptrdiff_t>(tries);
    std::partial_sort(by_distance.begin(), tried_end, by_distance.end());
    nearest_any[v] = by_distance.front().second;
    facing = facing && normal[v] != glm::vec3(0.0f);
    if (facing && options.oblique_penalty > 0.0f) {
      // The nearest tried bones reordered by their oblique distance (a bone in front counts as beside).
      for (auto it = by_distance.begin(); it != tried_end; ++it) {
        const float outward = it->first > 0.0f ? glm::dot(nearest_point[it->second] - p, normal[v]) / it->first : 0.0f;
        it->first *= 1.0f + options.oblique_penalty * (1.0f + std::min(outward, 0.0f));
      }
      std::sort(by_distance.begin(), tried_end);
    }
    for (std::size_t k = 0; k < tries; ++k) {
      const std::uint32_t bone = by_distance[k].second;
      const float distance = glm::length(nearest_point[bone] - p);
      bool visible = true;
      if (bvh != nullptr && bvh->triangle_count() > 0 && distance > 2.0f * offset) {
        const glm::vec3 direction = (nearest_point[bone] - p) / distance;
        if (facing && glm::dot(direction, normal[v]) > max_facing) continue;
        visible = !bvh->intersect({p + offset * direction, direction}, distance - 2.0f * offset, v).hit;
      }
      if (visible) {
        heated_by[v] = bone;
        const double d = std::max(distance, min_distance);
        heat[v] = static_cast<double>(options.heat) / (d * d);
        return;
      }
    }
  };
  {
    TriangleBvh whole;
    build_bvh(whole, UINT32_MAX);
    detail::clip_guessed_segments(shapes, whole);
    if (options.visibility) orient_normals();
    for (std::uint32_t v = 0; v < n; ++v) heat_vertex(v, options.visibility ? &whole : nullptr, true);
    // A piece with no bone behind any of its points (a lone sheet, a piece that lies beside the bones) takes the
    // nearest visible bone on either side.
    std::vector<std::uint8_t> heated(island_count, 0);
    for (std::uint32_t v = 0; v < n; ++v)
      if (heated_by[v] != UINT32_MAX) heated[island[v]] = 1;
    for (std::uint32_t v = 0; v < n; ++v)
      if (!heated[island[v]]) heat_vertex(v, options.visibility ? &whole : nullptr, false);
  }
  std::vector<std::uint8_t> island_heated(island_count, 0);
  for (std::uint32_t v = 0; v < n; ++v)
    if (heated_by[v] != UINT32_MAX) island_heated[island[v]] = 1;
  std::vector<std::size_t> island_points(island_count, 0);
  std::vector<std::uint32_t> island_first(island_count, UINT32_MAX);  // its lowest point index
  std::vector<glm::dvec3> island_centre(island_count, glm::dvec3(0.0));
  std::vector<std::size_t> island_vertices(island_count, 0);
  for (std::uint32_t p = 0; p < point_count; ++p) {
    ++island_points[island[welded[p]]];
    island_first[island[welded[p]]] = std::min(island_first[island[welded[p]]], p);
  }
  for (std::uint32_t v = 0; v < n; ++v) {
    island_centre[island[v]] += glm::dvec3(position[v]);
    ++island_vertices[island[v]];
  }
  auto island_text = [&](std::uint32_t i) {
    return "island of " + std::to_string(island_points[i]) + " point" + (island_points[i] == 1 ? "" : "s") +
           " (from point " + std::to_string(island_first[i]) + ", around " +
           position_text(glm::vec3(island_centre[i] / static_cast<double>(island_vertices[i]))) + ")";
  };
  // An island that sees no bone past the rest of the mesh (a garment around a limb, a plate on a tail) looks again
  // past its own triangles only.
  if (options.visibility && options.island_visibility) {
    std::vector<std::vector<std::uint32_t>> members(island_count);
    for (std::uint32_t v = 0; v < n; ++v)
      if (!island_heated[island[v]]) members[island[v]].push_back(v);
    for (std::uint32_t i = 0; i < island_count; ++i) {
      if (island_heated[i]) continue;
      TriangleBvh own;
      build_bvh(own, i);
      for (std::uint32_t v : members[i]) heat_vertex(v, &own, false);
      for (std::uint32_t v : members[i])
        if (heated_by[v] != UINT32_MAX) island_heated[i] = 1;
      if (island_heated[i])
        result.warnings.push_back(island_text(i) +
                                  " sees no bone past the rest of the mesh: weighted by the bones it sees past its "
                                  "own triangles");
    }
  }

  // --- the islands with heat are solved, the others bound rigidly ---
  std::vector<std::int32_t> row(n, -1);  // surface vertex -> row of the system, -1 outside it
  std::size_t rows = 0;
  for (std::uint32_t v = 0; v < n; ++v)
    if (island_heated[island[v]]) row[v] = static_cast<std::int32_t>(rows++);

  std::vector<Strongest> strongest(n);
  if (rows > 0) {
    // Stiffness (clamped cotangents) and barycentric areas.
    std::vector<double> area(n, 0.0);
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(triangles.size() * 12 + rows);
    std::vector<std::array<double, 3>> edge_weight(triangles.size(), {0.0, 0.0, 0.0});
    double cot_total = 0.0;
    std::size_t cot_count = 0;
    const double degenerate_area = 1e-12 * static_cast<double>(diagonal) * static_cast<double>(diagonal);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const auto& tri = triangles[t];
      if (row[tri[0]] < 0) continue;
      const glm::dvec3 p0(position[tri[0]]), p1(position[tri[1]]), p2(position[tri[2]]);
      const double double_area = glm::length(glm::cross(p1 - p0, p2 - p0));
      if (!(double_area > 2.0 * degenerate_area)) continue;
      for (int k = 0; k < 3; ++k) area[tri[static_cast<std::size_t>(k)]] += double_area / 6.0;
      const glm::dvec3 corner[3] = {p0, p1, p2};
      for (int k = 0; k < 3; ++k) {  // the angle at corner k, opposite edge (k+1, k+2)
        const glm::dvec3 a = corner[(k + 1) % 3] - corner[k], b = corner[(k + 2) % 3] - corner[k];
        const double cot = glm::dot(a, b) / double_area;
        edge_weight[t][static_cast<std::size_t>(k)] = 0.5 * std::max(cot, 0.0);
        cot_total += 0.5 * std::max(cot, 0.0);
        ++cot_count;
      }
    }
    const double uniform = uniform_share * (cot_count > 0 && cot_total > 0.0 ? cot_total / double(cot_count) : 1.0);
    double mean_area = 0.0;
    std::size_t area_count = 0;
    for (std::uint32_t v = 0; v < n; ++v)
      if (row[v] >= 0 && area[v] > 0.0) {
        mean_area += area[v];
        ++area_count;
      }
    mean_area = area_count > 0 ? mean_area / double(area_count) : 1.0;
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const auto& tri = triangles[t];
      if (row[tri[0]] < 0) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = tri[static_cast<std::size_t>((k + 1) % 3)];
        const std::uint32_t b = tri[static_cast<std::size_t>((k + 2) % 3)];
        // An edge of two triangles gets the uniform share twice; it only has to keep the surface connected.
        const double w = edge_weight[t][static_cast<std::size_t>(k)] + 0.5 * uniform;
        const int ra = row[a], rb = row[b];
        entries.emplace_back(ra, rb, -w);
        entries.emplace_back(rb, ra, -w);
        entries.emplace_back(ra, ra, w);
        entries.emplace_back(rb, rb, w);
      }
    }
    std::vector<double> mass(n, 0.0);
    for (std::uint32_t v = 0; v < n; ++v) {
      if (row[v] < 0) continue;
      // A vertex of degenerate triangles only still needs a mass for its heat to count.
      mass[v] = area[v] > 0.0 ? area[v] : 1e-3 * mean_area;
      entries.emplace_back(row[v], row[v], mass[v] * heat[v]);
    }
    const auto size = static_cast<Eigen::Index>(rows);
    Eigen::SparseMatrix<double> system(size, size);
    system.setFromTriplets(entries.begin(), entries.end());
    entries = {};
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system);
    if (solver.info() != Eigen::Success) throw Error::invalid_argument("mesh", "the heat system could not be factored");

    std::vector<std::uint8_t> heats(bone_count, 0);
    for (std::uint32_t v = 0; v < n; ++v)
      if (row[v] >= 0 && heated_by[v] != UINT32_MAX) heats[heated_by[v]] = 1;
    Eigen::VectorXd rhs(size), w(size);
    for (std::uint32_t bone = 0; bone < bone_count; ++bone) {
      if (!heats[bone]) continue;
      rhs.setZero();
      for (std::uint32_t v = 0; v < n; ++v)
        if (row[v] >= 0 && heated_by[v] == bone) rhs[row[v]] = mass[v] * heat[v];
      w = solver.solve(rhs);
      for (std::uint32_t v = 0; v < n; ++v) {
        if (row[v] < 0) continue;
        const double x = w[row[v]];
        if (x > 1e-6) strongest[v].offer(bone, static_cast<float>(std::min(x, 1.0)), options.max_influences);
      }
    }
  }

  // --- islands without heat: the bone nearest most of their points, rigidly ---
  std::vector<std::uint32_t> rigid_bone(island_count, UINT32_MAX);
  {
    std::vector<std::vector<std::uint32_t>> votes(island_count);
    for (std::uint32_t v = 0; v < n; ++v) {
      if (island_heated[island[v]]) continue;
      if (votes[island[v]].empty()) votes[island[v]].assign(bone_count, 0u);
      ++votes[island[v]][nearest_any[v]];
    }
    for (std::uint32_t i = 0; i < island_count; ++i) {
      if (island_heated[i]) continue;
      const auto bone =
          static_cast<std::uint32_t>(std::max_element(votes[i].begin(), votes[i].end()) - votes[i].begin());
      rigid_bone[i] = bone;
      result.warnings.push_back(island_text(i) + " sees no bone: bound rigidly to the nearest, " +
                                bone_label(skeleton, bone));
      votes[i] = {};
    }
  }

  result.weights = {};
  result.weights.bones.reserve(point_count);
  result.weights.weights.reserve(point_count);
  for (std::uint32_t p = 0; p < point_count; ++p) {
    const std::uint32_t v = welded[p];
    const std::uint32_t i = island[v];
    if (!island_heated[i]) {
      append_influences(result.weights, {}, {}, static_cast<std::uint16_t>(rigid_bone[i]));
      continue;
    }
    const std::uint32_t fallback = heated_by[v] != UINT32_MAX ? heated_by[v] : nearest_any[v];
    store(strongest[v], fallback, result.weights);
  }
  if (options.smoothing_iterations > 0) {
    SmoothWeightsOptions smooth;
    smooth.iterations = options.smoothing_iterations;
    smooth.max_influences = options.max_influences;
    smooth_weights(result.weights, mesh, smooth);
    prune_weights(result.weights, min_weight);
  }
  for (std::string& w : bones_without_vertices(result.weights, skeleton, options.deforming))
    result.warnings.push_back(std::move(w));
  return result;
}

}  // namespace deform
