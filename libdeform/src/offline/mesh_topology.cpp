// Point topology from a triangle list: every triangle edge as a sorted 64-bit key (low point, high point); runs of
// equal keys give the boundary (edges used by exactly one triangle), and the distinct edges in both directions,
// sorted, give the one-rings (CSR). Works on any triangle soup, manifold or not.
#include <algorithm>
#include <numeric>
#include <string>
#include <utility>
#include <type_traits>

#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/offline/topology.hpp"
namespace deform {
namespace {

std::uint64_t edge_key(std::uint32_t from, std::uint32_t to) { return std::uint64_t(from) << 32 | to; }
std::uint32_t key_from(std::uint64_t key) { return std::uint32_t(key >> 32); }
std::uint32_t key_to(std::uint64_t key) { return std::uint32_t(key); }

}  // namespace

PointTopology build_point_topology(const Mesh& mesh) {
  const std::size_t point_count = mesh.point_count();
  const auto point_of = [&](std::uint32_t vertex) {
    if (vertex >= mesh.vertex_count() || mesh.vertex_point[vertex] >= point_count)
      throw Error::invalid_argument("mesh", "triangle or vertex_point index out of range");
    return mesh.vertex_point[vertex];
  };

  // One key per undirected edge per triangle: the count of a key is how many triangles use that edge.
  std::vector<std::uint64_t> edges;
  edges.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const std::uint32_t corners[3] = {point_of(mesh.triangles[t]), point_of(mesh.triangles[t + 1]),
                                      point_of(mesh.triangles[t + 2])};
    const std::size_t first = edges.size();
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = corners[i], b = corners[(i + 1) % 3];
      const std::uint64_t key = edge_key(std::min(a, b), std::max(a, b));
      // A triangle with a repeated point has one real edge, counted once.
      if (a != b && std::find(edges.begin() + std::ptrdiff_t(first), edges.end(), key) == edges.end())
        edges.push_back(key);
    }
  }
  std::sort(edges.begin(), edges.end());

  PointTopology topology;
  std::vector<std::uint64_t> directed;  // each distinct edge in both directions
  directed.reserve(edges.size());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    const std::uint32_t a = key_from(edges[i]), b = key_to(edges[i]);
    if (j - i == 1) topology.boundary_edges.insert(topology.boundary_edges.end(), {a, b});
    directed.push_back(edge_key(a, b));
    directed.push_back(edge_key(b, a));
    i = j;
  }
  std::sort(directed.begin(), directed.end());

  topology.neighbour_offsets.assign(point_count + 1, 0);
  topology.neighbours.reserve(directed.size());
  for (const std::uint64_t key : directed) {
    ++topology.neighbour_offsets[key_from(key) + 1];
    topology.neighbours.push_back(key_to(key));
  }
  for (std::size_t p = 0; p < point_count; ++p) topology.neighbour_offsets[p + 1] += topology.neighbour_offsets[p];
  return topology;
}

std::vector<std::uint32_t> order_vertices_by_point(Mesh& mesh) {
  const std::size_t points = mesh.point_count(), vertices = mesh.vertex_count();
  const auto check = [&](bool ok, const char* what) {
    if (!ok) throw Error::invalid_argument("mesh", what);
  };
  check(vertices < std::size_t(0xffffffffu), "2^32 - 1 render vertices or more");
  check(mesh.vertex_normals.empty() || mesh.vertex_normals.size() == vertices, "vertex_normals: one per render vertex");
  check(mesh.vertex_uvs.empty() || mesh.vertex_uvs.size() == vertices, "vertex_uvs: one per render vertex");
  for (const std::uint32_t p : mesh.vertex_point) check(p < points, "vertex_point entry out of range");
  for (const std::uint32_t v : mesh.triangles) check(v < vertices, "triangle corner out of range");
  for (const std::uint32_t v : mesh.face_corners) check(v < vertices, "face corner out of range");

  constexpr std::uint32_t none = 0xffffffffu;
  std::vector<std::uint32_t> slot_of(vertices, none);  // previous render vertex -> new index
  std::vector<std::uint8_t> taken(vertices, 0);        // new index in use
  std::vector<std::uint8_t> placed(points, 0);         // the point has its render vertex p (p < vertices)
  for (std::size_t v = 0; v < vertices; ++v) {
    const std::uint32_t p = mesh.vertex_point[v];
    if (p < vertices && !placed[p]) slot_of[v] = p, taken[p] = 1, placed[p] = 1;
  }
  std::size_t free_slot = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    if (slot_of[v] != none) continue;
    while (taken[free_slot]) ++free_slot;
    slot_of[v] = std::uint32_t(free_slot);
    taken[free_slot] = 1;
  }
  const auto permuted = [&](auto& values) {
    if (values.empty()) return;
    std::remove_reference_t<decltype(values)> out(values.size());
    for (std::size_t v = 0; v < vertices; ++v) out[slot_of[v]] = values[v];
    values = std::move(out);
  };
  permuted(mesh.vertex_point);
  permuted(mesh.vertex_normals);
  permuted(mesh.vertex_uvs);
  for (std::uint32_t& v : mesh.triangles) v = slot_of[v];
  for (std::uint32_t& v : mesh.face_corners) v = slot_of[v];
  return slot_of;
}

PointOrder order_points_first(Model& model, std::span<const std::uint32_t> first) {
  const std::size_t count = model.mesh.point_count();
  constexpr std::uint32_t unset = ~std::uint32_t(0);
  std::vector<std::uint32_t> new_point(count, unset);
  std::vector<std::uint32_t> source;  // per new point: its previous id
  source.reserve(count);
  for (const std::uint32_t p : first) {
    if (p >= count) throw Error::invalid_argument("first", "point " + std::to_string(p) + " out of range");
    if (new_point[p] != unset) throw Error::invalid_argument("first", "point " + std::to_string(p) + " listed twice");
    new_point[p] = std::uint32_t(source.size());
    source.push_back(p);
  }
  for (std::uint32_t p = 0; p < count; ++p) {
    if (new_point[p] != unset) continue;
    new_point[p] = std::uint32_t(source.size());
    source.push_back(p);
  }
  Model out = model;  // the model is changed only once nothing can throw
  for (std::uint32_t& p : out.mesh.vertex_point) {
    if (p >= count) throw Error::invalid_argument("mesh", "a vertex_point entry is out of range");
    p = new_point[p];
  }
  for (std::size_t i = 0; i < count; ++i) out.mesh.positions[i] = model.mesh.positions[source[i]];
  const SkinWeights& in = model.weights;
  if (in.size() == count) {
    SkinWeights& w = out.weights;
    w = SkinWeights();
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t p = source[i];
      w.bones.push_back(in.bones[p]);
      w.weights.push_back(in.weights[p]);
      const auto extra = std::lower_bound(in.extra_points.begin(), in.extra_points.end(), p);
      if (extra == in.extra_points.end() || *extra != p) continue;
      const std::size_t j = std::size_t(extra - in.extra_points.begin());
      if (w.extra_offsets.empty()) w.extra_offsets.push_back(0);
      w.extra_points.push_back(std::uint32_t(i));
      for (std::uint32_t e = in.extra_offsets[j]; e < in.extra_offsets[j + 1]; ++e) {
        w.extra_bones.push_back(in.extra_bones[e]);
        w.extra_weights.push_back(in.extra_weights[e]);
      }
      w.extra_offsets.push_back(std::uint32_t(w.extra_bones.size()));
    }
  } else if (in.size() != 0) {
    throw Error::invalid_argument("weights", "not one entry per point");
  }
  for (MorphTarget& target : out.morph_targets) {
    std::vector<std::size_t> order(target.points.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    for (const std::uint32_t p : target.points)
      if (p >= count) throw Error::invalid_argument("morph target '" + target.name + "'", "point out of range");
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return new_point[target.points[a]] < new_point[target.points[b]]; });
    const MorphTarget before = target;
    for (std::size_t k = 0; k < order.size(); ++k) {
      target.points[k] = new_point[before.points[order[k]]];
      if (k < before.position_deltas.size()) target.position_deltas[k] = before.position_deltas[order[k]];
      if (k < before.normal_deltas.size()) target.normal_deltas[k] = before.normal_deltas[order[k]];
    }
  }
  PointOrder result;
  result.vertex = order_vertices_by_point(out.mesh);
  result.point = std::move(new_point);
  model = std::move(out);
  return result;
}

}  // namespace deform
