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
#include "finite.hpp"
#include "volumetric_weights.hpp"
namespace deform {
namespace {

// Influences below this fraction of a point's total are dropped (as the distance method does).
constexpr float min_weight = 1e-3f;
// The uniform Laplacian's share, relative to the mean cotangent weight.
constexpr double uniform_share = 1e-3;
// Nearest bones tried for visibility per point before the point is declared to see none.
constexpr std::size_t max_visibility_tries = 32;
// Bones whose (oblique) distances to a point are within this fraction of the nearest one's are equidistant: they heat
// the point together (HeatSources). Ties are exact where two bones' nearest points are one joint (a parent's segment
// ends where its child's starts: the points behind an elbow or a heel); the margin only absorbs rounding.
constexpr float tie_tolerance = 1e-5f;
// The most bones that heat one point together; a point equidistant from more keeps the nearest-ranked ones.
constexpr std::size_t max_tied_sources = 4;
// A bone heats a point only from behind the surface: the direction to the bone at most 78° from the inward normal
// (cos 78° ≈ 0.2). A bone beside or in front of the surface is another part's (a finger resting on the hip).
constexpr float max_facing = -0.2f;
// At a joint where a rig breaks a chain (HeatFinder::find_chain_joints), the two bones' weights are shared across a
// band this fraction of the incoming segment's length either side of the joint (share_across_chain_joint).
constexpr float chain_seam_half_width = 0.12f;

void check_options(const HeatWeightsOptions& o) {
  auto fail = [](const char* what, const std::string& rule) { throw Error::invalid_argument(what, rule); };
  detail::check_max_influences(o.max_influences, max_requested_influences);
  if (!std::isfinite(o.heat) || o.heat <= 0.0f) fail("heat", "must be finite and > 0");
  detail::check_leaf_length(o.leaf_length);
  if (!std::isfinite(o.oblique_penalty) || o.oblique_penalty < 0.0f) fail("oblique_penalty", "must be finite and >= 0");
  if (o.smoothing_iterations < 0 || o.smoothing_iterations > 100) fail("smoothing_iterations", "must be 0 to 100");
}

// The nearest point of a bone to p.
glm::vec3 nearest_on_bone(glm::vec3 p, const detail::BoneShape& shape) {
  glm::vec3 best = shape.segments.front().first;
  float best2 = INFINITY;
  for (const auto& [a, b] : shape.segments) {
    const glm::vec3 q = detail::nearest_on_segment(p, a, b);
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

namespace {

// --- the surface ---

// The mesh's points welded by exact position into surface vertices, its triangles over them (those with a repeated
// corner dropped) and its islands (connected pieces).
struct Surface {
  std::vector<std::uint32_t> welded;                    // per point: its surface vertex
  std::vector<glm::vec3> position;                      // per surface vertex
  float diagonal = 0.0f;                                // of the vertices' box, at least 1e-30
  std::vector<std::array<std::uint32_t, 3>> triangles;  // over surface vertices
  std::vector<std::uint32_t> island;                    // per surface vertex
  std::size_t island_count = 0;
  std::size_t size() const { return position.size(); }
};

void weld_points(const Mesh& mesh, Surface& s) {
  const std::size_t point_count = mesh.point_count();
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
  s.welded.assign(point_count, 0);
  for (std::size_t k = 0; k < point_count; ++k) {
    const std::uint32_t p = order[k];
    if (k == 0 || mesh.positions[p] != mesh.positions[order[k - 1]]) s.position.push_back(mesh.positions[p]);
    s.welded[p] = static_cast<std::uint32_t>(s.position.size() - 1);
  }
  const Bounds bounds = compute_bounds(s.position);
  s.diagonal = std::max(glm::length(bounds.max - bounds.min), 1e-30f);
}

void connect_triangles(const std::vector<std::uint32_t>& corners, Surface& s) {
  const std::size_t n = s.size();
  s.triangles.reserve(corners.size() / 3);
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (std::size_t t = 0; t + 2 < corners.size(); t += 3) {
    const std::array<std::uint32_t, 3> tri{s.welded[corners[t]], s.welded[corners[t + 1]], s.welded[corners[t + 2]]};
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    s.triangles.push_back(tri);
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find_root(parent, tri[0]), b = find_root(parent, tri[static_cast<std::size_t>(k)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  s.island.assign(n, 0);
  std::vector<std::uint32_t> island_of_root(n, UINT32_MAX);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t r = find_root(parent, v);
    if (island_of_root[r] == UINT32_MAX) island_of_root[r] = static_cast<std::uint32_t>(s.island_count++);
    s.island[v] = island_of_root[r];
  }
}

// `bvh` over the surface's triangles, or over one island's (`only_island`; UINT32_MAX: all); left empty for none.
void build_bvh(const Surface& s, TriangleBvh& bvh, std::uint32_t only_island) {
  std::vector<std::uint32_t> flat;
  for (const auto& t : s.triangles)
    if (only_island == UINT32_MAX || s.island[t[0]] == only_island) flat.insert(flat.end(), t.begin(), t.end());
  if (!flat.empty()) bvh.build(s.position, flat);
}

// --- heat: the nearest visible bone of every surface vertex ---

// Each surface vertex's source of heat, as HeatFinder::heat_vertex leaves it. A point equidistant from visible bones
// (behind a joint, where a parent's segment ends at its child's start: an elbow's tip, a heel) takes its heat from
// the ancestor among them. Among bones of which none descends from another (siblings that start at one place), it
// takes p_j = 1/k from each of the k, with the same H_jj, as Baran & Popović (section 4) do for every tie: either
// way the weights do not depend on the bones' numbering. Sharing a parent's tie with the child, as the paper does,
// measured further from the artists' weights (docs/weights.md, "What was tried and not kept").
struct HeatSources {
  std::vector<std::uint32_t> heated_by;    // the nearest visible bone, or UINT32_MAX for none
  std::vector<double> heat;                // heat / d² from it; 0 for none
  std::vector<std::uint32_t> nearest_any;  // nearest deforming bone, seen or not
  // Every bone that heats the vertex (heated_by first, then the bones equidistant with it), UINT32_MAX past them.
  std::vector<std::array<std::uint32_t, max_tied_sources>> sources;

  std::size_t source_count(std::uint32_t v) const noexcept {
    std::size_t k = 0;
    while (k < max_tied_sources && sources[v][k] != UINT32_MAX) ++k;
    return k;
  }
};

// Finds each vertex's heat source among the deforming bones (`candidates`). Its buffers are sized once here, so that
// heat_vertex allocates nothing per vertex.
struct HeatFinder {
  const Surface& surface;
  const std::vector<detail::BoneShape>& shapes;
  const std::vector<std::uint32_t>& candidates;
  const HeatWeightsOptions& options;
  const float offset;  // the ray starts this far from the surface, off its own triangles
  const float min_distance;
  HeatSources sources;
  std::vector<glm::vec3> normal;  // per surface vertex, outward (orient_normals), or 0 before and for no triangle
  std::vector<std::pair<float, std::uint32_t>> by_distance;
  std::vector<glm::vec3> nearest_point;  // per bone
  // Per bone: the deforming bone whose chain it continues (find_chain_joints), or UINT32_MAX; and that bone's
  // segment's direction into the joint.
  std::vector<std::uint32_t> continues;
  std::vector<std::int32_t> parents;  // each bone's parent (find_chain_joints)
  std::vector<glm::vec3> continues_direction;

  HeatFinder(const Surface& s, const std::vector<detail::BoneShape>& bone_shapes,
             const std::vector<std::uint32_t>& deforming, const HeatWeightsOptions& o, std::size_t bone_count)
      : surface(s),
        shapes(bone_shapes),
        candidates(deforming),
        options(o),
        offset(1e-5f * s.diagonal),
        min_distance(1e-4f * s.diagonal),
        normal(s.size(), glm::vec3(0.0f)),
        by_distance(deforming.size()),
        nearest_point(bone_count) {
    sources.heated_by.assign(s.size(), UINT32_MAX);
    sources.heat.assign(s.size(), 0.0);
    sources.sources.assign(s.size(), no_sources());
    sources.nearest_any.assign(s.size(), 0);
  }

  // A deforming bone whose head sits where another deforming bone's segment ends, and which does not descend from
  // that bone, continues that bone's chain: an IK goal or hand bone parented to the spine and placed at the wrist, at
  // the end of the forearm's segment (mrfixit.iqm's HandGoal.L/R). Heat_vertex gives the incoming bone the points on
  // its side of that joint. A child's joint is left to heat: its points already see their own bone, and sharpening
  // every joint costs the models whose artists blend there. `parent`: each bone's parent. O(deforming² · segments),
  // once; run after the segments are clipped.
  void find_chain_joints(const std::vector<std::int32_t>& parent) {
    parents = parent;
    continues.assign(shapes.size(), UINT32_MAX);
    continues_direction.assign(shapes.size(), glm::vec3(0.0f));
    // A descendant continues its ancestor's own chain, through bones of no length too (BCN_Epileptic.X's neck
    // sits on two bones at the same place).
    for (std::uint32_t b : candidates) {
      const glm::vec3 head = shapes[b].segments.front().first;
      for (std::size_t k = 0; k < candidates.size() && continues[b] == UINT32_MAX; ++k) {
        const std::uint32_t a = candidates[k];
        if (a == b || descends(b, a)) continue;
        for (const auto& [from, to] : shapes[a].segments)
          if (glm::length(to - head) <= min_distance && glm::length(to - from) > min_distance) {
            continues[b] = a;
            continues_direction[b] = to - from;
            break;
          }
      }
    }
  }

  // Whether bone b descends from bone a.
  bool descends(std::uint32_t b, std::uint32_t a) const {
    for (std::int32_t up = parents[b]; up >= 0; up = parents[static_cast<std::size_t>(up)])
      if (up == static_cast<std::int32_t>(a)) return true;
    return false;
  }

  // Whether v sees `bone` past `bvh` (null: nothing), from behind its surface with `facing` (heat_vertex's test).
  bool sees(std::uint32_t v, std::uint32_t bone, const TriangleBvh* bvh, bool facing) const {
    const glm::vec3 p = surface.position[v];
    const float distance = glm::length(nearest_point[bone] - p);
    if (bvh == nullptr || bvh->triangle_count() == 0 || distance <= 2.0f * offset) return true;
    const glm::vec3 direction = (nearest_point[bone] - p) / distance;
    if (facing && glm::dot(direction, normal[v]) > max_facing) return false;
    return !bvh->intersect({p + offset * direction, direction}, distance - 2.0f * offset, v).hit;
  }

  // Outward vertex normals: area-weighted, each island turned so that most of its points have their nearest bone
  // behind them (a model may wind its triangles either way; a piece's winding is consistent more often than not).
  void orient_normals() {
    const std::size_t n = surface.size();
    const auto& position = surface.position;
    for (const auto& t : surface.triangles) {
      const glm::vec3 face = glm::cross(position[t[1]] - position[t[0]], position[t[2]] - position[t[0]]);
      for (std::uint32_t c : t) normal[c] += face;
    }
    std::vector<std::int64_t> votes(surface.island_count, 0);
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
      votes[surface.island[v]] += side < 0.0f ? 1 : side > 0.0f ? -1 : 0;
    }
    for (std::uint32_t v = 0; v < n; ++v) {
      const float length = glm::length(normal[v]);
      normal[v] = length > 0.0f ? normal[v] / (votes[surface.island[v]] < 0 ? -length : length) : glm::vec3(0.0f);
    }
  }

  // Heats v from its nearest bone that `bvh` (null: nothing) does not hide; with `facing`, only from a bone behind
  // the surface (a point in no triangle has no side and takes any). v's own triangles never hide a bone: the segment
  // crosses them only at a sharp or creased corner of a coarse mesh, while what the test is for is another part of
  // the body in between. A bone that continues another's chain (find_chain_joints) gives way to the incoming bone
  // at a point behind its head, on the incoming side of the plane across the incoming segment, when v sees it.
  void heat_vertex(std::uint32_t v, const TriangleBvh* bvh, bool facing) {
    const glm::vec3 p = surface.position[v];
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const glm::vec3 q = nearest_on_bone(p, shapes[candidates[c]]);
      nearest_point[candidates[c]] = q;
      by_distance[c] = {glm::length(q - p), candidates[c]};
    }
    const std::size_t tries = std::min(by_distance.size(), max_visibility_tries);
    const auto tried_end = by_distance.begin() + static_cast<std::ptrdiff_t>(tries);
    std::partial_sort(by_distance.begin(), tried_end, by_distance.end());
    sources.nearest_any[v] = by_distance.front().second;
    facing = facing && normal[v] != glm::vec3(0.0f);
    if (facing && options.oblique_penalty > 0.0f) {
      // The nearest tried bones reordered by their oblique distance (a bone in front counts as beside).
      for (auto it = by_distance.begin(); it != tried_end; ++it) {
        const float outward = it->first > 0.0f ? glm::dot(nearest_point[it->second] - p, normal[v]) / it->first : 0.0f;
        it->first *= 1.0f + options.oblique_penalty * (1.0f + std::min(outward, 0.0f));
      }
      std::sort(by_distance.begin(), tried_end);
    }
    // The nearest visible bone and the visible bones as near as it (HeatSources).
    std::array<std::uint32_t, max_tied_sources> tied = no_sources();
    std::size_t count = 0;
    float tie_limit = 0.0f;
    for (std::size_t k = 0; k < tries && count < max_tied_sources; ++k) {
      if (count > 0 && by_distance[k].first > tie_limit) break;
      std::uint32_t bone = by_distance[k].second;
      if (!sees(v, bone, bvh, facing)) continue;
      const std::uint32_t incoming = continues.empty() ? UINT32_MAX : continues[bone];
      if (incoming != UINT32_MAX &&
          glm::dot(p - shapes[bone].segments.front().first, continues_direction[bone]) < 0.0f &&
          sees(v, incoming, bvh, facing))
        bone = incoming;
      if (count == 0) tie_limit = by_distance[k].first * (1.0f + tie_tolerance);
      // Two equidistant bones may both give way to one incoming bone.
      if (std::find(tied.begin(), tied.begin() + static_cast<std::ptrdiff_t>(count), bone) ==
          tied.begin() + static_cast<std::ptrdiff_t>(count))
        tied[count++] = bone;
    }
    // Of a bone and its descendant, the ancestor: the points behind a joint follow the parent (HeatSources).
    std::array<std::uint32_t, max_tied_sources>& heating = sources.sources[v];
    heating = no_sources();
    std::size_t kept = 0;
    for (std::size_t i = 0; i < count; ++i) {
      bool below = false;
      for (std::size_t j = 0; j < count && !below; ++j) below = j != i && descends(tied[i], tied[j]);
      if (!below) heating[kept++] = tied[i];
    }
    if (kept == 0) return;
    sources.heated_by[v] = heating[0];
    const double d = std::max(glm::length(nearest_point[heating[0]] - p), min_distance);
    sources.heat[v] = static_cast<double>(options.heat) / (d * d);
  }

  static std::array<std::uint32_t, max_tied_sources> no_sources() {
    std::array<std::uint32_t, max_tied_sources> none;
    none.fill(UINT32_MAX);
    return none;
  }
};

// Heats every vertex past the whole mesh, from behind its surface; clips the guessed bone segments to the mesh first
// (`shapes` is the finder's) and finds the chain joints (`parent`: each bone's parent). A piece with no bone behind
// any of its points (a lone sheet, a piece that lies beside the bones) takes the nearest visible bone on either side.
void heat_past_whole_mesh(HeatFinder& finder, std::vector<detail::BoneShape>& shapes,
                          const std::vector<std::int32_t>& parent) {
  const Surface& s = finder.surface;
  const bool visibility = finder.options.visibility;
  TriangleBvh whole;
  build_bvh(s, whole, UINT32_MAX);
  detail::clip_guessed_segments(shapes, whole);
  finder.find_chain_joints(parent);
  if (visibility) finder.orient_normals();
  for (std::uint32_t v = 0; v < s.size(); ++v) finder.heat_vertex(v, visibility ? &whole : nullptr, true);
  std::vector<std::uint8_t> heated(s.island_count, 0);
  for (std::uint32_t v = 0; v < s.size(); ++v)
    if (finder.sources.heated_by[v] != UINT32_MAX) heated[s.island[v]] = 1;
  for (std::uint32_t v = 0; v < s.size(); ++v)
    if (!heated[s.island[v]]) finder.heat_vertex(v, visibility ? &whole : nullptr, false);
}

// --- islands ---

// Per island: whether any of its vertices has heat, and what the warnings say of it.
struct Islands {
  std::vector<std::uint8_t> heated;
  std::vector<std::size_t> points;
  std::vector<std::uint32_t> first;  // its lowest point index
  std::vector<glm::dvec3> centre;    // sum of its surface vertices
  std::vector<std::size_t> vertices;

  std::string text(std::uint32_t i) const {
    return "island of " + std::to_string(points[i]) + " point" + (points[i] == 1 ? "" : "s") + " (from point " +
           std::to_string(first[i]) + ", around " +
           position_text(glm::vec3(centre[i] / static_cast<double>(vertices[i]))) + ")";
  }
};

Islands describe_islands(const Surface& s, const HeatSources& sources) {
  Islands is;
  is.heated.assign(s.island_count, 0);
  for (std::uint32_t v = 0; v < s.size(); ++v)
    if (sources.heated_by[v] != UINT32_MAX) is.heated[s.island[v]] = 1;
  is.points.assign(s.island_count, 0);
  is.first.assign(s.island_count, UINT32_MAX);
  is.centre.assign(s.island_count, glm::dvec3(0.0));
  is.vertices.assign(s.island_count, 0);
  for (std::uint32_t p = 0; p < s.welded.size(); ++p) {
    ++is.points[s.island[s.welded[p]]];
    is.first[s.island[s.welded[p]]] = std::min(is.first[s.island[s.welded[p]]], p);
  }
  for (std::uint32_t v = 0; v < s.size(); ++v) {
    is.centre[s.island[v]] += glm::dvec3(s.position[v]);
    ++is.vertices[s.island[v]];
  }
  return is;
}

// An island that sees no bone past the rest of the mesh (a garment around a limb, a plate on a tail) looks again past
// its own triangles only; a warning for each that then sees one.
void heat_past_own_triangles(HeatFinder& finder, Islands& islands, std::vector<std::string>& warnings) {
  const Surface& s = finder.surface;
  std::vector<std::vector<std::uint32_t>> members(s.island_count);
  for (std::uint32_t v = 0; v < s.size(); ++v)
    if (!islands.heated[s.island[v]]) members[s.island[v]].push_back(v);
  for (std::uint32_t i = 0; i < s.island_count; ++i) {
    if (islands.heated[i]) continue;
    TriangleBvh own;
    build_bvh(s, own, i);
    for (std::uint32_t v : members[i]) finder.heat_vertex(v, &own, false);
    for (std::uint32_t v : members[i])
      if (finder.sources.heated_by[v] != UINT32_MAX) islands.heated[i] = 1;
    if (islands.heated[i])
      warnings.push_back(islands.text(i) +
                         " sees no bone past the rest of the mesh: weighted by the bones it sees past its own "
                         "triangles");
  }
}

// --- the solve: the islands with heat ---

// The heat system over the surface vertices of the heated islands: (L + H·M) w = H·M, with L the clamped-cotangent
// stiffness plus a small uniform share, M the barycentric areas and H the heat.
struct HeatSystem {
  std::vector<std::int32_t> row;  // surface vertex -> row of the system, -1 outside it
  std::size_t rows = 0;
  std::vector<double> mass;  // per surface vertex
  Eigen::SparseMatrix<double> matrix;
};

HeatSystem heat_system(const Surface& s, const HeatSources& sources, const Islands& islands) {
  const std::size_t n = s.size();
  const auto& position = s.position;
  HeatSystem system;
  system.row.assign(n, -1);
  for (std::uint32_t v = 0; v < n; ++v)
    if (islands.heated[s.island[v]]) system.row[v] = static_cast<std::int32_t>(system.rows++);
  if (system.rows == 0) return system;
  const std::vector<std::int32_t>& row = system.row;
  // Stiffness (clamped cotangents) and barycentric areas.
  std::vector<double> area(n, 0.0);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(s.triangles.size() * 12 + system.rows);
  std::vector<std::array<double, 3>> edge_weight(s.triangles.size(), {0.0, 0.0, 0.0});
  double cot_total = 0.0;
  std::size_t cot_count = 0;
  const double degenerate_area = 1e-12 * static_cast<double>(s.diagonal) * static_cast<double>(s.diagonal);
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const auto& tri = s.triangles[t];
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
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    const auto& tri = s.triangles[t];
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
  system.mass.assign(n, 0.0);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (row[v] < 0) continue;
    // A vertex of degenerate triangles only still needs a mass for its heat to count.
    system.mass[v] = area[v] > 0.0 ? area[v] : 1e-3 * mean_area;
    entries.emplace_back(row[v], row[v], system.mass[v] * sources.heat[v]);
  }
  const auto size = static_cast<Eigen::Index>(system.rows);
  system.matrix.resize(size, size);
  system.matrix.setFromTriplets(entries.begin(), entries.end());
  return system;
}

// A joint where a rig breaks a chain (HeatFinder::find_chain_joints): the incoming bone, the bone that continues
// it, the joint (the continuing bone's head) and the incoming segment, from its start to the joint.
struct ChainJoint {
  std::uint32_t incoming = 0, continuing = 0;
  glm::vec3 joint{0.0f}, incoming_segment{0.0f};
};

std::vector<ChainJoint> chain_joints(const HeatFinder& finder) {
  std::vector<ChainJoint> joints;
  for (std::uint32_t b : finder.candidates)
    if (finder.continues[b] != UINT32_MAX)
      joints.push_back(
          {finder.continues[b], b, finder.shapes[b].segments.front().first, finder.continues_direction[b]});
  return joints;
}

// Shares the summed weight of a chain joint's two bones (`incoming`, `continuing`: their solutions over the system's
// rows) by the side of the joint a vertex lies on: all to the incoming bone from chain_seam_half_width of its
// segment's length behind the plane through the joint across that segment, all to the continuing bone from as far
// ahead, linearly between. Nothing in the hierarchy bends at such a joint (the continuing bone, an IK goal, moves
// with whatever it hangs from), so a blend as wide as heat's diffusion mixes two transforms that move apart;
// mrfixit.iqm's artist blends its wrist over one loop of the mesh.
void share_across_chain_joint(const ChainJoint& j, const std::vector<glm::vec3>& position,
                              const std::vector<std::int32_t>& row, Eigen::VectorXd& incoming,
                              Eigen::VectorXd& continuing) {
  const float length = glm::length(j.incoming_segment);
  if (!(length > 0.0f)) return;
  const double half_width = static_cast<double>(chain_seam_half_width * length);
  for (std::size_t v = 0; v < row.size(); ++v) {
    if (row[v] < 0) continue;
    const double ahead = static_cast<double>(glm::dot(position[v] - j.joint, j.incoming_segment) / length);
    const double share = std::clamp(0.5 + ahead / (2.0 * half_width), 0.0, 1.0);
    const double sum = incoming[row[v]] + continuing[row[v]];
    incoming[row[v]] = sum * (1.0 - share);
    continuing[row[v]] = sum * share;
  }
}

// Factors the system once and solves it for each bone that heats a vertex in it; shares the weights of the bones of
// each chain joint across it (share_across_chain_joint); keeps each vertex's strongest `max_influences` bones. Empty
// (no influence) for a vertex outside the system.
std::vector<Strongest> solve_heat(const HeatSystem& system, const HeatSources& sources,
                                  const std::vector<ChainJoint>& joints, const std::vector<glm::vec3>& position,
                                  std::size_t bone_count, int max_influences) {
  const std::size_t n = system.row.size();
  std::vector<Strongest> strongest(n);
  if (system.rows == 0) return strongest;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(system.matrix);
  if (solver.info() != Eigen::Success) throw Error::invalid_argument("mesh", "the heat system could not be factored");
  const std::vector<std::int32_t>& row = system.row;
  std::vector<std::uint8_t> heats(bone_count, 0);
  for (std::uint32_t v = 0; v < n; ++v)
    if (row[v] >= 0)
      for (std::size_t k = 0; k < sources.source_count(v); ++k) heats[sources.sources[v][k]] = 1;
  // The bones of a chain joint where both have heat keep their whole solution until it is shared.
  std::vector<std::uint8_t> kept(bone_count, 0);
  for (const ChainJoint& j : joints)
    if (heats[j.incoming] && heats[j.continuing]) kept[j.incoming] = kept[j.continuing] = 1;
  std::vector<Eigen::VectorXd> solution(bone_count);
  const auto size = static_cast<Eigen::Index>(system.rows);
  Eigen::VectorXd rhs(size), w(size);
  auto offer = [&](std::uint32_t bone, const Eigen::VectorXd& weights) {
    for (std::uint32_t v = 0; v < n; ++v) {
      if (row[v] < 0) continue;
      const double x = weights[row[v]];
      if (x > 1e-6) strongest[v].offer(bone, static_cast<float>(std::min(x, 1.0)), max_influences);
    }
  };
  for (std::uint32_t bone = 0; bone < bone_count; ++bone) {
    if (!heats[bone]) continue;
    rhs.setZero();
    for (std::uint32_t v = 0; v < n; ++v) {
      if (row[v] < 0) continue;
      const std::size_t k = sources.source_count(v);
      if (std::find(sources.sources[v].begin(), sources.sources[v].begin() + static_cast<std::ptrdiff_t>(k), bone) !=
          sources.sources[v].begin() + static_cast<std::ptrdiff_t>(k))
        rhs[row[v]] = system.mass[v] * sources.heat[v] / static_cast<double>(k);  // H_jj · p_j, p_j = 1/k
    }
    w = solver.solve(rhs);
    if (kept[bone]) solution[bone] = w;
    else offer(bone, w);
  }
  for (const ChainJoint& j : joints)
    if (kept[j.incoming] && kept[j.continuing])
      share_across_chain_joint(j, position, row, solution[j.incoming], solution[j.continuing]);
  for (std::uint32_t bone = 0; bone < bone_count; ++bone)
    if (kept[bone]) offer(bone, solution[bone]);
  return strongest;
}

// --- islands without heat: the bone nearest most of their points, rigidly; a warning for each ---
std::vector<std::uint32_t> rigid_bones(const Surface& s, const HeatSources& sources, const Islands& islands,
                                       const Skeleton& skeleton, std::vector<std::string>& warnings) {
  std::vector<std::uint32_t> rigid_bone(s.island_count, UINT32_MAX);
  std::vector<std::vector<std::uint32_t>> votes(s.island_count);
  for (std::uint32_t v = 0; v < s.size(); ++v) {
    if (islands.heated[s.island[v]]) continue;
    if (votes[s.island[v]].empty()) votes[s.island[v]].assign(skeleton.bone_count(), 0u);
    ++votes[s.island[v]][sources.nearest_any[v]];
  }
  for (std::uint32_t i = 0; i < s.island_count; ++i) {
    if (islands.heated[i]) continue;
    const auto bone = static_cast<std::uint32_t>(std::max_element(votes[i].begin(), votes[i].end()) - votes[i].begin());
    rigid_bone[i] = bone;
    warnings.push_back(islands.text(i) + " sees no bone: bound rigidly to the nearest, " + bone_label(skeleton, bone));
    votes[i] = {};
  }
  return rigid_bone;
}

// Each point's weights: its surface vertex's strongest bones (store), or its island's rigid bone.
SkinWeights point_weights(const Surface& s, const HeatSources& sources, const Islands& islands,
                          const std::vector<Strongest>& strongest, const std::vector<std::uint32_t>& rigid_bone) {
  SkinWeights weights;
  weights.bones.reserve(s.welded.size());
  weights.weights.reserve(s.welded.size());
  for (std::uint32_t p = 0; p < s.welded.size(); ++p) {
    const std::uint32_t v = s.welded[p];
    const std::uint32_t i = s.island[v];
    if (!islands.heated[i]) {
      append_influences(weights, {}, {}, static_cast<std::uint16_t>(rigid_bone[i]));
      continue;
    }
    const std::uint32_t fallback = sources.heated_by[v] != UINT32_MAX ? sources.heated_by[v] : sources.nearest_any[v];
    store(strongest[v], fallback, weights);
  }
  return weights;
}

}  // namespace

WeightsResult compute_heat_weights(const Mesh& mesh, const Skeleton& skeleton, const HeatWeightsOptions& options) {
  check_options(options);
  const detail::VolumetricInput input = detail::volumetric_input(mesh, skeleton, options.deforming);
  WeightsResult result;
  if (input.point_count == 0) {
    detail::warn_of_unused_bones(result, skeleton, options.deforming);
    return result;
  }
  Surface surface;
  weld_points(mesh, surface);
  connect_triangles(input.corners, surface);

  std::vector<detail::BoneShape> shapes = detail::bone_shapes(skeleton, options.leaf_length);
  HeatFinder finder(surface, shapes, input.deforming, options, input.bone_count);
  std::vector<std::int32_t> parent;
  parent.reserve(skeleton.bone_count());
  for (const Bone& b : skeleton.bones()) parent.push_back(b.parent);
  heat_past_whole_mesh(finder, shapes, parent);
  Islands islands = describe_islands(surface, finder.sources);
  if (options.visibility && options.island_visibility) heat_past_own_triangles(finder, islands, result.warnings);

  std::vector<Strongest> strongest;
  {
    const HeatSystem system = heat_system(surface, finder.sources, islands);
    strongest = solve_heat(system, finder.sources, chain_joints(finder), surface.position, input.bone_count,
                           options.max_influences);
  }
  const std::vector<std::uint32_t> rigid_bone =
      rigid_bones(surface, finder.sources, islands, skeleton, result.warnings);
  result.weights = point_weights(surface, finder.sources, islands, strongest, rigid_bone);
  if (options.smoothing_iterations > 0) {
    SmoothWeightsOptions smooth;
    smooth.iterations = options.smoothing_iterations;
    smooth.max_influences = options.max_influences;
    smooth_weights(result.weights, mesh, smooth);
    prune_weights(result.weights, min_weight);
  }
  detail::warn_of_unused_bones(result, skeleton, options.deforming);
  return result;
}

}  // namespace deform
