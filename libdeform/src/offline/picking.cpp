// Ray picking: Möller–Trumbore triangle tests, and a binned-SAH bounding volume hierarchy that refits in place.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "deform/runtime/error.hpp"
#include "deform/offline/picking.hpp"
#include "finite.hpp"
namespace deform {
namespace {

constexpr std::uint32_t leaf_size = 4;
constexpr int bin_count = 16;
constexpr int max_depth = 64;  // traversal stack; SAH splits stop at depth 32, median splits add at most 31 levels

// Möller & Trumbore 1997, two-sided. Writes t (along the unit `direction`) and the barycentrics of corners 1 and 2.
inline bool hit_triangle(glm::vec3 origin, glm::vec3 direction, glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, float& t,
                         float& u, float& v) {
  const glm::vec3 e1 = p1 - p0, e2 = p2 - p0;
  const glm::vec3 p = glm::cross(direction, e2);
  const float det = glm::dot(e1, p);
  if (!(std::abs(det) > 1e-20f)) return false;
  const float inv = 1.0f / det;
  const glm::vec3 s = origin - p0;
  u = glm::dot(s, p) * inv;
  if (!(u >= 0.0f && u <= 1.0f)) return false;
  const glm::vec3 q = glm::cross(s, e1);
  v = glm::dot(direction, q) * inv;
  if (!(v >= 0.0f && u + v <= 1.0f)) return false;
  t = glm::dot(e2, q) * inv;
  return t >= 0.0f;
}

constexpr float miss = std::numeric_limits<float>::infinity();

// Slab test; returns the entry distance, or `miss` when the box is missed within [0, limit] (a visit test is then
// `t < miss`, since the limit itself may be infinite).
inline float hit_box(glm::vec3 origin, glm::vec3 inverse_direction, glm::vec3 min, glm::vec3 max, float limit) {
  const glm::vec3 t0 = (min - origin) * inverse_direction, t1 = (max - origin) * inverse_direction;
  const glm::vec3 near = glm::min(t0, t1), far = glm::max(t0, t1);
  const float enter = std::max(std::max(near.x, near.y), std::max(near.z, 0.0f));
  const float leave = std::min(std::min(far.x, far.y), std::min(far.z, limit));
  return enter <= leave ? enter : miss;
}

bool unit_direction(const Ray& ray, glm::vec3& direction) {
  const float length = glm::length(ray.direction);
  if (!(length > 0.0f) || !std::isfinite(length) || !finite(ray.origin)) return false;
  direction = ray.direction / length;
  return true;
}

struct Box {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};
  void grow(glm::vec3 p) { min = glm::min(min, p), max = glm::max(max, p); }
  void grow(const Box& b) { min = glm::min(min, b.min), max = glm::max(max, b.max); }
  float half_area() const {
    const glm::vec3 e = max - min;
    return e.x < 0.0f ? 0.0f : e.x * e.y + e.y * e.z + e.z * e.x;
  }
};

}  // namespace

Ray ray_from_pixel(const glm::mat4& view, const glm::mat4& projection, glm::vec2 pixel, glm::vec4 viewport) noexcept {
  const float x = 2.0f * (pixel.x - viewport.x) / viewport.z - 1.0f;
  const float y = 1.0f - 2.0f * (pixel.y - viewport.y) / viewport.w;
  const glm::mat4 unproject = glm::inverse(projection * view);
  const glm::vec4 near = unproject * glm::vec4(x, y, -1.0f, 1.0f);
  const glm::vec4 far = unproject * glm::vec4(x, y, 1.0f, 1.0f);
  const glm::vec3 origin = glm::vec3(near) / near.w;
  return Ray{origin, glm::normalize(glm::vec3(far) / far.w - origin)};
}

RayHit intersect_triangles(const Ray& ray, std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                           float max_distance) noexcept {
  RayHit best;
  glm::vec3 direction;
  if (!unit_direction(ray, direction)) return best;
  float limit = max_distance;
  for (std::size_t i = 0; i + 2 < indices.size(); i += 3) {
    float t, u, v;
    if (hit_triangle(ray.origin, direction, positions[indices[i]], positions[indices[i + 1]], positions[indices[i + 2]],
                     t, u, v) &&
        (t < limit || (t == limit && !best.hit))) {
      limit = t;
      best = RayHit{true, static_cast<std::uint32_t>(i / 3), glm::vec3(1.0f - u - v, u, v), t};
    }
  }
  return best;
}

void TriangleBvh::build(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices) {
  if (indices.size() % 3 != 0)
    throw Error::invalid_argument("", "index count " + std::to_string(indices.size()) + " is not a multiple of 3");
  if (indices.size() / 3 >= (std::size_t{1} << 31)) throw Error::invalid_argument("", "too many triangles");
  for (std::size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= positions.size())
      throw Error::invalid_argument(
          "triangle " + std::to_string(i / 3),
          "index " + std::to_string(indices[i]) + " out of range (" + std::to_string(positions.size()) + " points)");
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!finite(positions[i])) throw Error::invalid_argument("point " + std::to_string(i), "position is not finite");

  const auto triangles = static_cast<std::uint32_t>(indices.size() / 3);
  nodes_.clear();
  triangle_ids_.clear();
  corner_points_.clear();
  corners_.clear();
  point_count_ = positions.size();
  if (triangles == 0) return;  // no nodes: every query misses
  std::vector<Box> boxes(triangles);
  std::vector<glm::vec3> centres(triangles);
  for (std::uint32_t t = 0; t < triangles; ++t) {
    for (int c = 0; c < 3; ++c) boxes[t].grow(positions[indices[3 * t + static_cast<std::uint32_t>(c)]]);
    centres[t] = 0.5f * (boxes[t].min + boxes[t].max);
  }
  std::vector<std::uint32_t> ids(triangles);
  std::iota(ids.begin(), ids.end(), 0u);
  nodes_.reserve(2 * static_cast<std::size_t>(triangles));
  nodes_.push_back(Node{glm::vec3(0.0f), 0, glm::vec3(0.0f), triangles});

  struct Task {
    std::uint32_t node, depth;
  };
  std::vector<Task> tasks{{0, 0}};
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    const std::uint32_t first = nodes_[task.node].first, count = nodes_[task.node].count;
    if (count <= leaf_size) continue;
    Box centre_box;
    for (std::uint32_t i = first; i < first + count; ++i) centre_box.grow(centres[ids[i]]);
    const glm::vec3 extent = centre_box.max - centre_box.min;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    auto begin = ids.begin() + first, end = begin + count, middle = begin;
    if (extent[axis] > 0.0f && task.depth < max_depth / 2) {
      // Binned SAH (Wald 2007): cost of each of the bin_count - 1 planes from prefix and suffix boxes.
      Box bin_boxes[bin_count];
      std::uint32_t bin_counts[bin_count] = {};
      const float scale = bin_count / extent[axis];
      auto bin_of = [&](std::uint32_t id) {
        return std::min(bin_count - 1, static_cast<int>((centres[id][axis] - centre_box.min[axis]) * scale));
      };
      for (std::uint32_t i = first; i < first + count; ++i) {
        const int b = bin_of(ids[i]);
        bin_boxes[b].grow(boxes[ids[i]]);
        ++bin_counts[b];
      }
      float suffix_cost[bin_count];
      Box suffix;
      std::uint32_t suffix_count = 0;
      for (int b = bin_count - 1; b > 0; --b) {
        suffix.grow(bin_boxes[b]);
        suffix_count += bin_counts[b];
        suffix_cost[b] = suffix.half_area() * static_cast<float>(suffix_count);
      }
      Box prefix;
      std::uint32_t prefix_count = 0;
      float best_cost = std::numeric_limits<float>::infinity();
      int best_split = -1;
      for (int b = 1; b < bin_count; ++b) {
        prefix.grow(bin_boxes[b - 1]);
        prefix_count += bin_counts[b - 1];
        const float cost = prefix.half_area() * static_cast<float>(prefix_count) + suffix_cost[b];
        if (prefix_count > 0 && prefix_count < count && cost < best_cost) best_cost = cost, best_split = b;
      }
      if (best_split > 0)
        middle = std::partition(begin, end, [&](std::uint32_t id) { return bin_of(id) < best_split; });
    }
    if (middle == begin || middle == end) {  // all centres equal, or depth running out: split at the median
      middle = begin + count / 2;
      std::nth_element(begin, middle, end,
                       [&](std::uint32_t l, std::uint32_t r) { return centres[l][axis] < centres[r][axis]; });
    }
    const auto left_count = static_cast<std::uint32_t>(middle - begin);
    const auto left = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back(Node{glm::vec3(0.0f), first, glm::vec3(0.0f), left_count});
    nodes_.push_back(Node{glm::vec3(0.0f), first + left_count, glm::vec3(0.0f), count - left_count});
    nodes_[task.node].first = left;
    nodes_[task.node].count = 0;
    tasks.push_back({left, task.depth + 1});
    tasks.push_back({left + 1, task.depth + 1});
  }

  triangle_ids_ = std::move(ids);
  corner_points_.resize(3 * static_cast<std::size_t>(triangles));
  for (std::uint32_t s = 0; s < triangles; ++s)
    for (std::uint32_t c = 0; c < 3; ++c) corner_points_[3 * s + c] = indices[3 * triangle_ids_[s] + c];
  corners_.resize(corner_points_.size());
  refit(positions);
}

bool TriangleBvh::refit(std::span<const glm::vec3> positions) noexcept {
  if (positions.size() != point_count_) return false;
  for (std::size_t i = 0; i < corners_.size(); ++i) corners_[i] = positions[corner_points_[i]];
  // Children always come after their parent, so one backward pass sees every child before its parent.
  for (std::size_t n = nodes_.size(); n-- > 0;) {
    Node& node = nodes_[n];
    Box box;
    if (node.count > 0) {
      for (std::size_t i = 3 * std::size_t{node.first}; i < 3 * (std::size_t{node.first} + node.count); ++i)
        if (finite(corners_[i])) box.grow(corners_[i]);
    } else {
      const Node& l = nodes_[node.first];
      const Node& r = nodes_[node.first + 1];
      box.min = glm::min(l.min, r.min);
      box.max = glm::max(l.max, r.max);
    }
    node.min = box.min;
    node.max = box.max;
  }
  return true;
}

RayHit TriangleBvh::intersect(const Ray& ray, float max_distance, std::uint32_t skip_point) const noexcept {
  RayHit best;
  glm::vec3 direction;
  if (nodes_.empty() || triangle_ids_.empty() || !unit_direction(ray, direction)) return best;
  const glm::vec3 inverse_direction = 1.0f / direction;  // ±inf on an axis-parallel ray is what the slab test wants
  float limit = max_distance;
  std::uint32_t stack[max_depth];
  int top = 0;
  if (hit_box(ray.origin, inverse_direction, nodes_[0].min, nodes_[0].max, limit) < miss) stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (node.count > 0) {
      for (std::uint32_t s = node.first; s < node.first + node.count; ++s) {
        if (skip_point != no_point && (corner_points_[3 * s] == skip_point || corner_points_[3 * s + 1] == skip_point ||
                                       corner_points_[3 * s + 2] == skip_point))
          continue;
        float t, u, v;
        if (hit_triangle(ray.origin, direction, corners_[3 * s], corners_[3 * s + 1], corners_[3 * s + 2], t, u, v) &&
            (t < limit || (t == limit && best.hit && triangle_ids_[s] < best.triangle) || (t == limit && !best.hit))) {
          limit = t;
          best = RayHit{true, triangle_ids_[s], glm::vec3(1.0f - u - v, u, v), t};
        }
      }
      continue;
    }
    const Node& l = nodes_[node.first];
    const Node& r = nodes_[node.first + 1];
    const float tl = hit_box(ray.origin, inverse_direction, l.min, l.max, limit);
    const float tr = hit_box(ray.origin, inverse_direction, r.min, r.max, limit);
    // Push the farther child first so the nearer one is searched first and shrinks `limit` for the other.
    const bool left_first = tl <= tr;
    const float t_far = left_first ? tr : tl, t_near = left_first ? tl : tr;
    if (t_far < miss && top < max_depth) stack[top++] = left_first ? node.first + 1 : node.first;
    if (t_near < miss && top < max_depth) stack[top++] = left_first ? node.first : node.first + 1;
  }
  return best;
}

std::vector<std::uint32_t> point_triangles(const Mesh& mesh) {
  std::vector<std::uint32_t> points(mesh.triangles.size());
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = mesh.vertex_point[mesh.triangles[i]];
  return points;
}

}  // namespace deform
