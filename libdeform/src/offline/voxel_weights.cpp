// Geodesic voxel weights (voxel_weights.hpp): voxelise, flood the outside, one Dijkstra per bone through the
// volume, hierarchy-restricted inverse-distance falloff, one-ring smoothing.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "deform/offline/picking.hpp"
#include "deform/offline/topology.hpp"
#include "deform/offline/voxel_weights.hpp"
#include "deform/runtime/error.hpp"
#include "finite.hpp"
#include "volumetric_weights.hpp"
namespace deform {
namespace {

constexpr float min_weight = 1e-3f;
constexpr float unreached = std::numeric_limits<float>::infinity();

struct Influence {
  std::uint32_t bone;
  float weight;
};

void check_options(const VoxelWeightsOptions& o) {
  auto fail = [](const char* what, const char* rule) { throw Error::invalid_argument(what, rule); };
  if (o.resolution < 8 || o.resolution > 1024) fail("resolution", "must be 8 to 1024");
  if (!std::isfinite(o.falloff_power) || o.falloff_power <= 0.0f) fail("falloff_power", "must be finite and > 0");
  detail::check_leaf_length(o.leaf_length);
  detail::check_max_influences(o.max_influences, max_influences);
  if (o.smoothing_iterations < 0) fail("smoothing_iterations", "must be >= 0");
}

// Keeps the `keep` strongest (ties: lower bone), drops those under min_weight of the total, normalises, strongest
// first; unused slots (bone 0, weight 0). `list` must not be empty.
void store_strongest(std::vector<Influence>& list, int keep, glm::u16vec4& bones, glm::vec4& weights) {
  std::sort(list.begin(), list.end(), [](const Influence& a, const Influence& b) {
    return a.weight != b.weight ? a.weight > b.weight : a.bone < b.bone;
  });
  if (list.size() > static_cast<std::size_t>(keep)) list.resize(static_cast<std::size_t>(keep));
  float total = 0.0f;
  for (const Influence& i : list) total += i.weight;
  std::size_t used = 0;
  for (const Influence& i : list)
    if (i.weight >= min_weight * total) ++used;
  used = std::max<std::size_t>(used, 1);
  total = 0.0f;
  for (std::size_t k = 0; k < used; ++k) total += list[k].weight;
  bones = glm::u16vec4(0);
  weights = glm::vec4(0.0f);
  for (std::size_t k = 0; k < used; ++k) {
    bones[static_cast<int>(k)] = static_cast<std::uint16_t>(list[k].bone);
    weights[static_cast<int>(k)] = total > 0.0f ? list[k].weight / total : (k == 0 ? 1.0f : 0.0f);
  }
}

// A voxel grid over a box: index = x + dims.x · (y + dims.y · z).
struct Grid {
  glm::vec3 origin{0.0f};
  float size = 1.0f;
  glm::ivec3 dims{0};
  std::size_t count() const { return std::size_t(dims.x) * std::size_t(dims.y) * std::size_t(dims.z); }
  // The cell holding p, clamped to the grid. Clamped as floats: a point far outside the grid (a bone's end) or not
  // finite never converts an out-of-range float to int.
  glm::ivec3 cell(glm::vec3 p) const {
    const glm::vec3 f = glm::floor((p - origin) / size);
    glm::ivec3 c(0);
    for (int a = 0; a < 3; ++a)
      c[a] = f[a] >= 0.0f ? (f[a] < static_cast<float>(dims[a] - 1) ? static_cast<int>(f[a]) : dims[a] - 1) : 0;
    return c;
  }
  std::size_t index(glm::ivec3 c) const {
    return std::size_t(c.x) + std::size_t(dims.x) * (std::size_t(c.y) + std::size_t(dims.y) * std::size_t(c.z));
  }
};

// Samples along a length at under half a voxel apart, at least 1 and at most 2^22 (a bone thousands of times longer
// than the mesh is sampled more sparsely away from it, never with an overflowing count).
int sample_steps(float length, float voxel) {
  const float steps = std::ceil(2.0f * length / voxel);
  return steps >= 1.0f ? (steps < 4194304.0f ? static_cast<int>(steps) : 4194304) : 1;
}

// --- the grid: the points' box, two voxels of margin all round ---
// A box the grid cannot divide is refused rather than voxelised: coordinates so large that the box's size or a
// squared distance overflows (±3e38), or points that all coincide (a box of no size, cells of no size: a bone would
// take 2^31 steps), or nearly so (a box within the coordinates' float resolution, or cells below float's range).
Grid voxel_grid(const Mesh& mesh, int resolution) {
  const Bounds bounds = compute_bounds(mesh.positions);
  const glm::vec3 extent = bounds.max - bounds.min;
  const float longest = std::max({extent.x, extent.y, extent.z});
  const float largest = std::max({glm::abs(bounds.min.x), glm::abs(bounds.min.y), glm::abs(bounds.min.z),
                                  glm::abs(bounds.max.x), glm::abs(bounds.max.y), glm::abs(bounds.max.z)});
  if (!std::isfinite(longest) || !(largest <= 1e18f)) {  // beyond, squared distances overflow a float
    char text[32];
    std::snprintf(text, sizeof text, "%g", double(largest));
    throw Error::invalid_argument("mesh", std::string("the points' bounding box is too large to voxelise: coordinates "
                                                      "up to ") +
                                              text + ", more than 1e18");
  }
  if (!(longest > 1e-7f * largest) || !(longest > 1e-30f))
    throw Error::invalid_argument("mesh", "the points' bounding box has no size (all " +
                                              std::to_string(mesh.point_count()) +
                                              " points at one place): nothing to voxelise");
  Grid grid;
  grid.size = longest / static_cast<float>(resolution);
  grid.origin = bounds.min - 2.0f * grid.size;
  grid.dims = glm::ivec3(glm::ceil(extent / grid.size)) + 5;
  return grid;
}

// --- the volume: the voxels of the surface and those inside it ---

// The mesh's volume in the grid: the voxels a triangle or point is in, and those the outside cannot reach.
struct Volume {
  std::vector<std::int32_t> id;  // per voxel: its volume id, -1 outside
  std::vector<glm::ivec3> cell;  // per volume id: its voxel
};

// 1 for every voxel a triangle passes through (sampled at under half a voxel) or a point lies in.
std::vector<std::uint8_t> surface_voxels(const Mesh& mesh, const std::vector<std::uint32_t>& corners,
                                         const Grid& grid) {
  std::vector<std::uint8_t> is_surface(grid.count(), 0);
  for (std::size_t t = 0; t + 2 < corners.size(); t += 3) {
    const glm::vec3 a = mesh.positions[corners[t]], b = mesh.positions[corners[t + 1]],
                    c = mesh.positions[corners[t + 2]];
    const float edge = std::max({glm::length(b - a), glm::length(c - a), glm::length(c - b)});
    const int steps = sample_steps(edge, grid.size);
    for (int i = 0; i <= steps; ++i)
      for (int j = 0; i + j <= steps; ++j) {
        const float u = static_cast<float>(i) / static_cast<float>(steps);
        const float v = static_cast<float>(j) / static_cast<float>(steps);
        is_surface[grid.index(grid.cell(a + u * (b - a) + v * (c - a)))] = 1;
      }
  }
  for (std::size_t i = 0; i < mesh.point_count(); ++i) is_surface[grid.index(grid.cell(mesh.positions[i]))] = 1;
  return is_surface;
}

// Per voxel, 1 outside: flooded from the grid's corner through voxels that are not surface (6 neighbours).
std::vector<std::uint8_t> outside_voxels(const std::vector<std::uint8_t>& is_surface, const Grid& grid) {
  std::vector<std::uint8_t> outside(grid.count(), 0);
  std::vector<std::size_t> stack{0};
  outside[0] = 1;
  const std::array<glm::ivec3, 6> steps{glm::ivec3(1, 0, 0),  glm::ivec3(-1, 0, 0), glm::ivec3(0, 1, 0),
                                        glm::ivec3(0, -1, 0), glm::ivec3(0, 0, 1),  glm::ivec3(0, 0, -1)};
  while (!stack.empty()) {
    const std::size_t at = stack.back();
    stack.pop_back();
    const glm::ivec3 c(static_cast<int>(at % std::size_t(grid.dims.x)),
                       static_cast<int>(at / std::size_t(grid.dims.x) % std::size_t(grid.dims.y)),
                       static_cast<int>(at / (std::size_t(grid.dims.x) * std::size_t(grid.dims.y))));
    for (const glm::ivec3& s : steps) {
      const glm::ivec3 n = c + s;
      if (glm::any(glm::lessThan(n, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(n, grid.dims))) continue;
      const std::size_t ni = grid.index(n);
      if (outside[ni] || is_surface[ni]) continue;
      outside[ni] = 1;
      stack.push_back(ni);
    }
  }
  return outside;
}

Volume voxelise(const Mesh& mesh, const std::vector<std::uint32_t>& corners, const Grid& grid) {
  const std::vector<std::uint8_t> outside = outside_voxels(surface_voxels(mesh, corners, grid), grid);
  Volume volume;
  volume.id.assign(grid.count(), -1);
  for (int z = 0; z < grid.dims.z; ++z)
    for (int y = 0; y < grid.dims.y; ++y)
      for (int x = 0; x < grid.dims.x; ++x) {
        const std::size_t i = grid.index({x, y, z});
        if (outside[i]) continue;
        volume.id[i] = static_cast<std::int32_t>(volume.cell.size());
        volume.cell.emplace_back(x, y, z);
      }
  return volume;
}

// --- bones and their seeds ---

// The bones' shapes, their guessed segments clipped where they leave the mesh.
std::vector<detail::BoneShape> clipped_bone_shapes(const Mesh& mesh, const std::vector<std::uint32_t>& corners,
                                                   const Skeleton& skeleton, float leaf_length) {
  std::vector<detail::BoneShape> shapes = detail::bone_shapes(skeleton, leaf_length);
  TriangleBvh bvh;
  std::vector<std::uint32_t> flat;
  for (std::size_t t = 0; t + 2 < corners.size(); t += 3)
    if (corners[t] != corners[t + 1] && corners[t + 1] != corners[t + 2] && corners[t] != corners[t + 2])
      flat.insert(flat.end(), {corners[t], corners[t + 1], corners[t + 2]});
  if (!flat.empty()) {
    bvh.build(mesh.positions, flat);
    detail::clip_guessed_segments(shapes, bvh);
  }
  return shapes;
}

// The volume ids a bone starts its Dijkstra from (ascending, unique): the volume voxels its segments pass through;
// else those beside it (a bone outside the volume); else, for a bone inside a leaking (open) mesh's shell, the volume
// voxels nearest to it. None for a bone wholly outside the grid.
std::vector<std::int32_t> seeds_of(const detail::BoneShape& shape, const Grid& grid, const Volume& volume) {
  std::vector<std::int32_t> seeds, near;
  bool within_grid = false;
  for (const auto& [a, b] : shape.segments) {
    const int steps = sample_steps(glm::length(b - a), grid.size);
    for (int k = 0; k <= steps; ++k) {
      const glm::vec3 p = a + (b - a) * (static_cast<float>(k) / static_cast<float>(steps));
      const glm::ivec3 c = grid.cell(p);
      const glm::vec3 local = (p - grid.origin) / grid.size;
      if (glm::any(glm::lessThan(local, glm::vec3(0.0f))) || glm::any(glm::greaterThan(local, glm::vec3(grid.dims))))
        continue;  // outside the grid: seeds nothing
      within_grid = true;
      const std::int32_t id = volume.id[grid.index(c)];
      if (id >= 0) {
        seeds.push_back(id);
        continue;
      }
      for (int dz = -1; dz <= 1; ++dz)  // a bone outside the volume seeds the volume voxels beside it
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const glm::ivec3 n = glm::clamp(c + glm::ivec3(dx, dy, dz), glm::ivec3(0), grid.dims - 1);
            const std::int32_t nid = volume.id[grid.index(n)];
            if (nid >= 0) near.push_back(nid);
          }
    }
  }
  if (seeds.empty()) seeds = std::move(near);
  if (seeds.empty() && within_grid) {  // inside a leaking (open) mesh's shell: the volume voxels nearest to it
    std::vector<float> gap(volume.cell.size(), unreached);
    float best = unreached;
    for (std::size_t v = 0; v < volume.cell.size(); ++v) {
      const glm::vec3 centre = grid.origin + (glm::vec3(volume.cell[v]) + 0.5f) * grid.size;
      for (const auto& [a, b] : shape.segments)
        gap[v] = std::min(gap[v], glm::length(centre - detail::nearest_on_segment(centre, a, b)));
      best = std::min(best, gap[v]);
    }
    for (std::size_t v = 0; v < volume.cell.size(); ++v)
      if (gap[v] <= best + grid.size) seeds.push_back(static_cast<std::int32_t>(v));
  }
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  return seeds;
}

// --- geodesic distances: one Dijkstra per deforming bone through the volume ---

// Each volume voxel's 26 neighbours (volume ids, -1 outside the volume) and the length of each step.
struct VolumeSteps {
  std::vector<std::array<std::int32_t, 26>> neighbours;
  std::array<float, 26> length{};
};

VolumeSteps volume_steps(const Grid& grid, const Volume& volume) {
  VolumeSteps steps;
  steps.neighbours.resize(volume.cell.size());
  int k = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        steps.length[static_cast<std::size_t>(k)] =
            grid.size * std::sqrt(static_cast<float>(dx * dx + dy * dy + dz * dz));
        for (std::size_t v = 0; v < volume.cell.size(); ++v) {
          const glm::ivec3 n = volume.cell[v] + glm::ivec3(dx, dy, dz);
          const bool in = glm::all(glm::greaterThanEqual(n, glm::ivec3(0))) && glm::all(glm::lessThan(n, grid.dims));
          steps.neighbours[v][static_cast<std::size_t>(k)] = in ? volume.id[grid.index(n)] : -1;
        }
        ++k;
      }
  return steps;
}

// Per point and bone (point · bone_count + bone): the distance from the bone to the point's voxel through the
// volume; `unreached` for a bone that does not deform, a point outside the volume or one the bone does not reach.
std::vector<float> geodesic_distances(const Mesh& mesh, const Grid& grid, const Volume& volume,
                                      const std::vector<detail::BoneShape>& shapes,
                                      const detail::VolumetricInput& input) {
  const std::size_t point_count = input.point_count, bone_count = input.bone_count;
  std::vector<std::int32_t> point_voxel(point_count);
  for (std::size_t i = 0; i < point_count; ++i) point_voxel[i] = volume.id[grid.index(grid.cell(mesh.positions[i]))];
  std::vector<float> distance(point_count * bone_count, unreached);
  std::vector<float> field(volume.cell.size());
  const VolumeSteps steps = volume_steps(grid, volume);
  using Entry = std::pair<float, std::int32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (std::uint32_t b : input.deforming) {
    std::fill(field.begin(), field.end(), unreached);
    for (std::int32_t s : seeds_of(shapes[b], grid, volume)) {
      field[static_cast<std::size_t>(s)] = 0.0f;
      queue.push({0.0f, s});
    }
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > field[static_cast<std::size_t>(v)]) continue;
      for (std::size_t k = 0; k < 26; ++k) {
        const std::int32_t n = steps.neighbours[static_cast<std::size_t>(v)][k];
        if (n < 0) continue;
        const float nd = d + steps.length[k];
        if (nd < field[static_cast<std::size_t>(n)]) {
          field[static_cast<std::size_t>(n)] = nd;
          queue.push({nd, n});
        }
      }
    }
    for (std::size_t i = 0; i < point_count; ++i)
      if (point_voxel[i] >= 0) distance[i * bone_count + b] = field[static_cast<std::size_t>(point_voxel[i])];
  }
  return distance;
}

// --- weights: geodesic nearest, its parent, its children; inverse-distance falloff ---

// Each point's weights from its geodesic distances; a point no bone reaches is bound rigidly to the bone nearest in a
// straight line, and counted in one warning.
void falloff_weights(const Mesh& mesh, const Skeleton& skeleton, const detail::VolumetricInput& input,
                     const std::vector<detail::BoneShape>& shapes, const std::vector<float>& distance, float half,
                     const VoxelWeightsOptions& options, WeightsResult& result) {
  const std::size_t point_count = input.point_count, bone_count = input.bone_count;
  auto deforms = [&](std::size_t b) { return input.deforms[b] != 0; };
  const float power = options.falloff_power;
  std::vector<Influence> list;
  std::size_t unreached_points = 0, first_unreached = 0;
  for (std::size_t i = 0; i < point_count; ++i) {
    const float* d = &distance[i * bone_count];
    std::size_t nearest = bone_count;
    for (std::size_t b = 0; b < bone_count; ++b)
      if (deforms(b) && d[b] < unreached && (nearest == bone_count || d[b] < d[nearest])) nearest = b;
    list.clear();
    if (nearest == bone_count) {  // no bone reaches it through the volume: the straight-line nearest, rigidly
      if (unreached_points++ == 0) first_unreached = i;
      float best = unreached;
      for (std::size_t b = 0; b < bone_count; ++b) {
        if (!deforms(b)) continue;
        for (const auto& [a, e] : shapes[b].segments) {
          const float dd = glm::length(mesh.positions[i] - detail::nearest_on_segment(mesh.positions[i], a, e));
          if (dd < best) {
            best = dd;
            nearest = b;
          }
        }
      }
      list.push_back({static_cast<std::uint32_t>(nearest), 1.0f});
    } else {
      const float reference = d[nearest] + half;
      auto add = [&](std::size_t b) {
        if (d[b] < unreached)
          list.push_back({static_cast<std::uint32_t>(b), std::pow(reference / (d[b] + half), power)});
      };
      add(nearest);
      const Bone& n = skeleton.bones()[nearest];
      std::int32_t up = n.parent;
      while (up >= 0 && !deforms(static_cast<std::size_t>(up)))
        up = skeleton.bones()[static_cast<std::size_t>(up)].parent;
      if (up >= 0) add(static_cast<std::size_t>(up));
      for (std::int32_t c : n.children)
        if (deforms(static_cast<std::size_t>(c))) add(static_cast<std::size_t>(c));
    }
    store_strongest(list, options.max_influences, result.weights.bones[i], result.weights.weights[i]);
  }
  if (unreached_points > 0)
    result.warnings.push_back(std::to_string(unreached_points) + " point" + (unreached_points == 1 ? "" : "s") +
                              " (the first: point " + std::to_string(first_unreached) +
                              ") reached by no bone through the volume: bound rigidly to the nearest bone");
}

// --- one-ring smoothing: each pass, half a point's own weights and half its neighbours' mean ---
void smooth_one_ring(const Mesh& mesh, const VoxelWeightsOptions& options, SkinWeights& weights) {
  const PointTopology topology = build_point_topology(mesh);
  SkinWeights next = weights;
  std::vector<Influence> list;
  for (int pass = 0; pass < options.smoothing_iterations; ++pass) {
    for (std::uint32_t i = 0; i < mesh.point_count(); ++i) {
      const auto ring = topology.point_neighbours(i);
      if (ring.empty()) continue;
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
      const float share = 0.5f / static_cast<float>(ring.size());
      for (std::uint32_t n : ring) accumulate(n, share);
      store_strongest(list, options.max_influences, next.bones[i], next.weights[i]);
    }
    std::swap(weights, next);
  }
}

}  // namespace

WeightsResult compute_voxel_weights(const Mesh& mesh, const Skeleton& skeleton, const VoxelWeightsOptions& options) {
  check_options(options);
  const detail::VolumetricInput input = detail::volumetric_input(mesh, skeleton, options.deforming);
  WeightsResult result;
  if (input.point_count == 0) {
    detail::warn_of_unused_bones(result, skeleton, options.deforming);
    return result;
  }
  result.weights.bones.assign(input.point_count, glm::u16vec4(0));
  result.weights.weights.assign(input.point_count, glm::vec4(0.0f));
  const Grid grid = voxel_grid(mesh, options.resolution);
  std::vector<float> distance;
  std::vector<detail::BoneShape> shapes;
  {
    const Volume volume = voxelise(mesh, input.corners, grid);
    shapes = clipped_bone_shapes(mesh, input.corners, skeleton, options.leaf_length);
    distance = geodesic_distances(mesh, grid, volume, shapes, input);
  }
  falloff_weights(mesh, skeleton, input, shapes, distance, 0.5f * grid.size, options, result);
  distance = {};
  if (options.smoothing_iterations > 0) smooth_one_ring(mesh, options, result.weights);
  detail::warn_of_unused_bones(result, skeleton, options.deforming);
  return result;
}

}  // namespace deform
