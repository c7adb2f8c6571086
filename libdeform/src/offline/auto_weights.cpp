// Automatic skin weights: distance to bone segments, hierarchy-restricted inverse-distance falloff, one-ring smoothing.
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/offline/weights.hpp"
#include "finite.hpp"
namespace deform {
namespace {

// Influences below this fraction of a point's total are dropped: they move nothing visible and bloat the .skw.
constexpr float min_weight = 1e-3f;

struct Influence {
  std::uint32_t bone;
  float weight;
};

void check_options(const AutoWeightsOptions& o) {
  auto fail = [](const char* what, const char* rule) { throw Error::in_file("automatic weights", what, rule); };
  if (!std::isfinite(o.falloff_power) || o.falloff_power <= 0.0f) fail("falloff_power", "must be finite and > 0");
  if (!std::isfinite(o.behind_head_penalty) || o.behind_head_penalty < 1.0f)
    fail("behind_head_penalty", "must be finite and >= 1");
  if (!std::isfinite(o.leaf_length) || o.leaf_length < 0.0f) fail("leaf_length", "must be finite and >= 0");
  if (o.max_influences < 1 || o.max_influences > max_influences) fail("max_influences", "must be 1 to 4");
  if (o.smoothing_iterations < 0) fail("smoothing_iterations", "must be >= 0");
}

void check_deforming(const AutoWeightsOptions& o, std::size_t bone_count) {
  if (o.deforming.empty()) return;
  auto fail = [](const char* rule) { throw Error::in_file("automatic weights", "deforming", rule); };
  if (o.deforming.size() != bone_count) fail("must be empty or hold one entry per bone");
  if (std::none_of(o.deforming.begin(), o.deforming.end(), [](std::uint8_t d) { return d != 0; }))
    fail("no bone deforms");
}

// Keeps the `keep` strongest influences (ties: lower bone id), drops those under min_weight of the total, normalises,
// and stores them strongest first in slot `point` of `out`. `list` is scratch and is reordered.
void store_strongest(std::vector<Influence>& list, int keep, std::size_t point, SkinWeights& out) {
  std::sort(list.begin(), list.end(), [](const Influence& a, const Influence& b) {
    return a.weight != b.weight ? a.weight > b.weight : a.bone < b.bone;
  });
  if (list.size() > static_cast<std::size_t>(keep)) list.resize(static_cast<std::size_t>(keep));
  float total = 0.0f;
  for (const Influence& i : list) total += i.weight;
  std::size_t used = 0;
  for (const Influence& i : list)
    if (i.weight >= min_weight * total) ++used;
  used = std::max<std::size_t>(used, 1);  // the strongest always stays: every point is bound to some bone
  total = 0.0f;
  for (std::size_t k = 0; k < used; ++k) total += list[k].weight;
  glm::u16vec4 bones(0);
  glm::vec4 weights(0.0f);
  for (std::size_t k = 0; k < used; ++k) {
    bones[static_cast<int>(k)] = static_cast<std::uint16_t>(list[k].bone);
    weights[static_cast<int>(k)] = list[k].weight / total;
  }
  out.bones[point] = bones;
  out.weights[point] = weights;
}

// The per-bone data the distance test needs, computed once.
struct SegmentTest {
  glm::vec3 head;
  glm::vec3 axis;  // tail - head
  float length_squared;
  float behind_scale;  // behind_head_penalty for non-root bones, 1 for the root
};

// Squared distance from p to the bone, with the part behind the head scaled (see weights.hpp).
float distance_squared(const SegmentTest& s, glm::vec3 p) {
  const glm::vec3 v = p - s.head;
  const float v2 = glm::dot(v, v);
  if (s.length_squared <= 0.0f) return v2;
  const float along = glm::dot(v, s.axis);  // t * length_squared
  if (along <= 0.0f) {
    const float behind2 = along * along / s.length_squared;
    const float perp2 = std::max(v2 - behind2, 0.0f);
    return perp2 + s.behind_scale * s.behind_scale * behind2;
  }
  if (along >= s.length_squared) {
    const glm::vec3 w = v - s.axis;
    return glm::dot(w, w);
  }
  const glm::vec3 w = v - s.axis * (along / s.length_squared);
  return glm::dot(w, w);
}

SkinWeights unsmoothed_weights(std::span<const glm::vec3> points, const Skeleton& skeleton,
                               const AutoWeightsOptions& options) {
  check_options(options);
  check_deforming(options, skeleton.bone_count());
  auto deforms = [&](std::int32_t b) {
    return options.deforming.empty() || options.deforming[static_cast<std::size_t>(b)] != 0;
  };
  const std::vector<BoneSegment> segments = bone_segments(skeleton, options.leaf_length);
  const std::size_t bone_count = skeleton.bone_count();
  std::vector<SegmentTest> tests(bone_count);
  float scale = 0.0f;
  for (std::size_t b = 0; b < bone_count; ++b) {
    const glm::vec3 axis = segments[b].tail - segments[b].head;
    tests[b] = {segments[b].head, axis, glm::dot(axis, axis),
                skeleton.bones()[b].parent >= 0 ? options.behind_head_penalty : 1.0f};
    scale = std::max(scale, glm::length(segments[b].head - segments[0].head) + glm::length(axis));
  }
  // Keeps the falloff finite for a point exactly on a bone, far below any distance that matters.
  const float epsilon = std::max(scale, 1.0f) * 1e-5f;
  const float epsilon2 = epsilon * epsilon;
  const float half_power = 0.5f * options.falloff_power;

  SkinWeights out;
  out.bones.resize(points.size());
  out.weights.resize(points.size());
  std::vector<float> d2(bone_count);
  std::vector<Influence> list;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::vec3 p = points[i];
    if (!finite(p)) throw Error::in_file("automatic weights", "vertex " + std::to_string(i), "position is not finite");
    std::size_t nearest = bone_count;
    for (std::size_t b = 0; b < bone_count; ++b) {
      d2[b] = distance_squared(tests[b], p);
      if (deforms(static_cast<std::int32_t>(b)) && (nearest == bone_count || d2[b] < d2[nearest])) nearest = b;
    }
    const Bone& n = skeleton.bones()[nearest];
    const float reference = d2[nearest] + epsilon2;
    auto add = [&](std::size_t b) {
      list.push_back({static_cast<std::uint32_t>(b), std::pow(reference / (d2[b] + epsilon2), half_power)});
    };
    list.clear();
    add(nearest);
    std::int32_t up = n.parent;
    while (up >= 0 && !deforms(up)) up = skeleton.bones()[static_cast<std::size_t>(up)].parent;
    if (up >= 0) add(static_cast<std::size_t>(up));
    for (std::int32_t c : n.children)
      if (deforms(c)) add(static_cast<std::size_t>(c));
    store_strongest(list, options.max_influences, i, out);
  }
  return out;
}

}  // namespace

std::vector<BoneSegment> bone_segments(const Skeleton& skeleton, float leaf_length) {
  if (!std::isfinite(leaf_length) || leaf_length < 0.0f)
    throw Error::in_file("automatic weights", "leaf_length", "must be finite and >= 0");
  const std::span<const glm::mat4> world = skeleton.bind_world();
  auto head = [&](std::int32_t id) { return glm::vec3(world[static_cast<std::size_t>(id)][3]); };
  std::vector<BoneSegment> segments(skeleton.bone_count());
  for (std::size_t b = 0; b < segments.size(); ++b) {
    const Bone& bone = skeleton.bones()[b];
    const glm::vec3 h = head(static_cast<std::int32_t>(b));
    glm::vec3 tail = h;
    if (!bone.children.empty()) tail = head(bone.children.front());
    else if (bone.parent >= 0) tail = h + leaf_length * (h - head(bone.parent));
    segments[b] = {h, tail};
  }
  return segments;
}

SkinWeights compute_automatic_weights(std::span<const glm::vec3> points, const Skeleton& skeleton,
                                      const AutoWeightsOptions& options) {
  return unsmoothed_weights(points, skeleton, options);
}

SkinWeights compute_automatic_weights(const Mesh& mesh, const Skeleton& skeleton, const AutoWeightsOptions& options) {
  SkinWeights weights = unsmoothed_weights(mesh.positions, skeleton, options);
  if (options.smoothing_iterations == 0 || mesh.point_count() == 0) return weights;

  // Point adjacency (compressed rows) from the triangles' edges, through render vertex -> point.
  const std::size_t point_count = mesh.point_count();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(mesh.triangles.size() * 2);
  auto point_of = [&](std::uint32_t render_vertex, std::size_t triangle) {
    if (render_vertex >= mesh.vertex_point.size() || mesh.vertex_point[render_vertex] >= point_count)
      throw Error::in_file("automatic weights", "triangle " + std::to_string(triangle), "vertex index out of range");
    return mesh.vertex_point[render_vertex];
  };
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const std::uint32_t p[3] = {point_of(mesh.triangles[t], t / 3), point_of(mesh.triangles[t + 1], t / 3),
                                point_of(mesh.triangles[t + 2], t / 3)};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = p[k], b = p[(k + 1) % 3];
      if (a == b) continue;
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<std::size_t> first(point_count + 1, 0);
  for (const auto& e : edges) ++first[e.first + 1];
  for (std::size_t i = 0; i < point_count; ++i) first[i + 1] += first[i];

  // Each pass: new = 1/2 own + 1/2 mean of the neighbours, then the strongest max_influences, renormalised.
  SkinWeights next = weights;
  std::vector<Influence> list;
  for (int pass = 0; pass < options.smoothing_iterations; ++pass) {
    for (std::size_t i = 0; i < point_count; ++i) {
      const std::size_t degree = first[i + 1] - first[i];
      if (degree == 0) continue;
      list.clear();
      auto accumulate = [&](std::size_t point, float scale) {
        for (int k = 0; k < max_influences; ++k) {
          const float w = weights.weights[point][k];
          if (w <= 0.0f) continue;
          const std::uint32_t bone = weights.bones[point][k];
          auto it = std::find_if(list.begin(), list.end(), [&](const Influence& x) { return x.bone == bone; });
          if (it == list.end()) list.push_back({bone, scale * w});
          else it->weight += scale * w;
        }
      };
      accumulate(i, 0.5f);
      const float share = 0.5f / static_cast<float>(degree);
      for (std::size_t e = first[i]; e < first[i + 1]; ++e) accumulate(edges[e].second, share);
      store_strongest(list, options.max_influences, i, next);
    }
    std::swap(weights, next);
  }
  return weights;
}

}  // namespace deform
