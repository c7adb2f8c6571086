// Angle-weighted vertex normals (Thürmer & Wüthrich, "Computing vertex normals from polygonal facets", 1998) and
// bounds: per-frame safe (no allocation, no exceptions) but for bind_vertex_normals. VertexNormalsJob runs the kernel
// of mesh_normals_kernel.inl: the portable, AVX2, AVX-512 or NEON copy, as its Isa says (isa.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>
#include <string>

#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "simd/mesh_normals_kernel.hpp"

namespace deform {
namespace {

using KernelEntry = void (*)(const detail::NormalsKernelArgs&) noexcept;

// The copy for `isa`, which isa_available() has accepted.
KernelEntry kernel_for(Isa isa) noexcept {
  if (isa == Isa::automatic) isa = isa_best();
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return detail::vertex_normals_avx512;
  if (isa == Isa::avx2) return detail::vertex_normals_avx2;
#endif
#if defined(DEFORM_NEON_KERNELS)
  if (isa == Isa::neon) return detail::vertex_normals_neon;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  if (isa == Isa::simd128) return detail::vertex_normals_simd128;
#endif
  return detail::vertex_normals_portable;
}

// Everything validate() checks that costs O(1).
Status layout_ok(const VertexNormalsJob& job) noexcept {
  const VertexNormalsBinding* b = job.binding;
  if (!b) return Status::failure("no binding");
  const std::size_t corners = 3 * b->triangle_count;
  if (b->triangle_points.size() != corners || b->triangle_corners.size() != corners ||
      b->corner_triangle.size() != corners || b->triangle_offsets.size() != b->point_count + 1 ||
      b->corner_offsets.size() != b->point_count + 1 || b->vertex_offsets.size() != b->point_count + 1 ||
      b->point_vertices.size() != b->vertex_count)
    return Status::failure("binding arrays differ in size");
  if (b->triangle_offsets.front() != 0 || b->triangle_offsets.back() != b->triangle_count ||
      b->corner_offsets.front() != 0 || b->corner_offsets.back() != corners || b->vertex_offsets.front() != 0 ||
      b->vertex_offsets.back() != b->vertex_count)
    return Status::failure("binding offsets invalid");
  if (job.positions.size() != b->point_count) return Status::failure("positions: one per point");
  if (job.normals.size() != b->vertex_count) return Status::failure("normals: one per render vertex");
  if (job.scratch.size() != b->point_count + corners) return Status::failure("scratch: one per point and corner");
  if (!isa_available(job.isa)) return Status::failure("instruction set not available");
  return {};
}

}  // namespace

Status compute_vertex_normals(const Mesh& mesh, std::span<const glm::vec3> positions, std::span<glm::vec3> scratch,
                              std::span<glm::vec3> out_vertex_normals) noexcept {
  const std::size_t point_count = mesh.point_count();
  const std::size_t vertex_count = mesh.vertex_count();
  if (positions.size() != point_count) return Status::failure("positions: one per point");
  if (scratch.size() != point_count) return Status::failure("scratch: one per point");
  if (out_vertex_normals.size() != vertex_count) return Status::failure("normals: one per render vertex");
  if (mesh.triangles.size() % 3 != 0) return Status::failure("triangle index count not a multiple of 3");

  for (glm::vec3& n : scratch) n = glm::vec3(0.0f);
  const std::uint32_t* triangle = mesh.triangles.data();
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t, triangle += 3) {
    if (triangle[0] >= vertex_count || triangle[1] >= vertex_count || triangle[2] >= vertex_count)
      return Status::failure("triangle vertex out of range");
    const std::uint32_t a = mesh.vertex_point[triangle[0]];
    const std::uint32_t b = mesh.vertex_point[triangle[1]];
    const std::uint32_t c = mesh.vertex_point[triangle[2]];
    if (a >= point_count || b >= point_count || c >= point_count) return Status::failure("vertex point out of range");
    const glm::vec3 ab = positions[b] - positions[a];
    const glm::vec3 ac = positions[c] - positions[a];
    const glm::vec3 bc = positions[c] - positions[b];
    const glm::vec3 area_normal = glm::cross(ab, ac);  // |area_normal| = 2 * area = |e1||e2| sin(corner angle)
    const float twice_area = glm::length(area_normal);
    if (!(twice_area > 0.0f)) continue;  // degenerate: no direction to contribute
    const glm::vec3 unit_normal = area_normal / twice_area;
    const float angle_a = detail::corner_angle(twice_area, glm::dot(ab, ac));
    const float angle_b = detail::corner_angle(twice_area, -glm::dot(ab, bc));
    const float angle_c = std::numbers::pi_v<float> - angle_a - angle_b;
    scratch[a] += angle_a * unit_normal;
    scratch[b] += angle_b * unit_normal;
    scratch[c] += std::max(angle_c, 0.0f) * unit_normal;
  }
  for (glm::vec3& n : scratch) {
    const float length = glm::length(n);
    n = length > detail::cancelled_normal_sum ? n / length : glm::vec3(0.0f);
  }
  for (std::size_t r = 0; r < vertex_count; ++r) {
    const std::uint32_t point = mesh.vertex_point[r];
    if (point >= point_count) return Status::failure("vertex point out of range");
    out_vertex_normals[r] = scratch[point];
  }
  return {};
}

VertexNormalsBinding bind_vertex_normals(const Mesh& mesh) {
  const std::size_t point_count = mesh.point_count(), vertex_count = mesh.vertex_count();
  if (mesh.triangles.size() % 3 != 0) throw Error::invalid_argument("mesh", "triangle index count not a multiple of 3");
  for (const std::uint32_t point : mesh.vertex_point)
    if (point >= point_count) throw Error::invalid_argument("mesh", "vertex_point index out of range");
  if (mesh.triangles.size() >= std::numeric_limits<std::uint32_t>::max())
    throw Error::invalid_argument("mesh", "2^32 triangle corners or more");
  if (point_count >= std::numeric_limits<std::uint32_t>::max() ||
      vertex_count >= std::numeric_limits<std::uint32_t>::max())
    throw Error::invalid_argument("mesh", "2^32 points or render vertices or more");

  VertexNormalsBinding binding;
  binding.point_count = point_count;
  binding.vertex_count = vertex_count;
  std::vector<std::uint32_t> kept;  // 3 points per triangle without a repeated point
  kept.reserve(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::uint32_t p[3];
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t vertex = mesh.triangles[3 * t + k];
      if (vertex >= vertex_count) throw Error::invalid_argument("mesh", "triangle index out of range");
      p[k] = mesh.vertex_point[vertex];
    }
    if (p[0] != p[1] && p[1] != p[2] && p[0] != p[2]) kept.insert(kept.end(), {p[0], p[1], p[2]});
  }
  binding.triangle_count = kept.size() / 3;

  // Each triangle from its lowest point, the winding kept, the triangles ordered by that point (stable).
  const std::size_t triangles = binding.triangle_count;
  for (std::size_t t = 0; t < triangles; ++t) {
    std::uint32_t* p = kept.data() + 3 * t;
    const std::size_t lowest = p[0] < p[1] ? (p[0] < p[2] ? 0 : 2) : (p[1] < p[2] ? 1 : 2);
    std::rotate(p, p + lowest, p + 3);
  }
  binding.triangle_offsets.assign(point_count + 1, 0);
  for (std::size_t t = 0; t < triangles; ++t) ++binding.triangle_offsets[kept[3 * t] + 1];
  for (std::size_t p = 0; p < point_count; ++p) binding.triangle_offsets[p + 1] += binding.triangle_offsets[p];
  std::vector<std::uint32_t> fill(binding.triangle_offsets.begin(), binding.triangle_offsets.end() - 1);
  binding.triangle_points.resize(3 * triangles);
  for (std::size_t t = 0; t < triangles; ++t) {
    const std::size_t slot = fill[kept[3 * t]]++;
    std::copy(kept.begin() + std::ptrdiff_t(3 * t), kept.begin() + std::ptrdiff_t(3 * t + 3),
              binding.triangle_points.begin() + std::ptrdiff_t(3 * slot));
  }
  // The corners of each point, in the order of the sorted triangles.
  binding.corner_offsets.assign(point_count + 1, 0);
  for (const std::uint32_t p : binding.triangle_points) ++binding.corner_offsets[p + 1];
  for (std::size_t p = 0; p < point_count; ++p) binding.corner_offsets[p + 1] += binding.corner_offsets[p];
  fill.assign(binding.corner_offsets.begin(), binding.corner_offsets.end() - 1);
  binding.triangle_corners.resize(3 * triangles);
  binding.corner_triangle.resize(3 * triangles);
  for (std::size_t i = 0; i < 3 * triangles; ++i) {
    const std::uint32_t corner = fill[binding.triangle_points[i]]++;
    binding.triangle_corners[i] = corner;
    binding.corner_triangle[corner] = std::uint32_t(i / 3);
  }

  binding.vertex_offsets.assign(point_count + 1, 0);
  for (const std::uint32_t p : mesh.vertex_point) ++binding.vertex_offsets[p + 1];
  for (std::size_t p = 0; p < point_count; ++p) binding.vertex_offsets[p + 1] += binding.vertex_offsets[p];
  binding.point_vertices.resize(vertex_count);
  fill.assign(binding.vertex_offsets.begin(), binding.vertex_offsets.end() - 1);
  for (std::size_t r = 0; r < vertex_count; ++r)
    binding.point_vertices[fill[mesh.vertex_point[r]]++] = std::uint32_t(r);
  return binding;
}

Status VertexNormalsJob::validate() const noexcept {
  if (Status s = layout_ok(*this); !s) return s;
  const VertexNormalsBinding& b = *binding;
  for (std::size_t p = 0; p < b.point_count; ++p)
    if (b.triangle_offsets[p] > b.triangle_offsets[p + 1] || b.corner_offsets[p] > b.corner_offsets[p + 1] ||
        b.vertex_offsets[p] > b.vertex_offsets[p + 1])
      return Status::failure("binding offsets invalid");
  // Triangle t lies in its lowest point's run, its points above that one, and its corners are corners of its points
  // that name t back.
  for (std::size_t p = 0; p < b.point_count; ++p)
    for (std::size_t t = b.triangle_offsets[p]; t < b.triangle_offsets[p + 1]; ++t)
      for (std::size_t k = 0; k < 3; ++k) {
        const std::size_t point = b.triangle_points[3 * t + k], corner = b.triangle_corners[3 * t + k];
        if (point >= b.point_count || (k == 0 ? point != p : point <= p) || corner < b.corner_offsets[point] ||
            corner >= b.corner_offsets[point + 1] || b.corner_triangle[corner] != t)
          return Status::failure("binding triangle invalid");
      }
  for (const std::uint32_t vertex : b.point_vertices)
    if (vertex >= b.vertex_count) return Status::failure("binding vertex out of range");
  return {};
}

Status VertexNormalsJob::run() const noexcept { return run(0, count()); }

Status VertexNormalsJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (Status s = layout_ok(*this); !s) return s;
  if (begin > end || end > binding->point_count) return Status::failure("range outside the job");
  if (begin < end) kernel_for(isa)({binding, positions.data(), normals.data(), scratch.data(), begin, end});
  return {};
}

Bounds compute_bounds(std::span<const glm::vec3> points) {
  if (points.empty()) return {};
  Bounds bounds{points[0], points[0]};
  for (const glm::vec3& p : points) {
    bounds.min = glm::min(bounds.min, p);
    bounds.max = glm::max(bounds.max, p);
  }
  return bounds;
}

}  // namespace deform

namespace deform {

InPlaceGather plan_in_place_gather(std::span<const std::uint32_t> map, std::size_t sources) {
  const std::size_t count = map.size();
  constexpr std::uint32_t none = 0xffffffffu;
  if (count >= std::size_t(none)) throw Error::invalid_argument("map", "2^32 - 1 entries or more");
  if (sources > count) throw Error::invalid_argument("map", "more sources than destinations");
  for (std::size_t v = 0; v < count; ++v) {
    if (map[v] >= sources)
      throw Error::invalid_argument("map", "entry " + std::to_string(v) + " is not below the source count");
  }
  InPlaceGather plan;
  plan.sources = sources;
  plan.destinations = count;
  // Slot s may be overwritten once every other destination reading it has been written (readers[s] = 0). Writing a
  // destination frees one read of its source. What is left when nothing is free are cycles (each slot read by the
  // one before it): one slot's value is held (in the scratch slot), which frees that slot, and its cycle unwinds to
  // the move from the held value before another cycle is broken, so one scratch slot suffices.
  std::vector<std::uint32_t> readers(count, 0);
  std::vector<std::uint8_t> pending(count, 0);
  std::size_t remaining = 0;
  for (std::size_t v = 0; v < count; ++v) {
    if (map[v] == v) continue;
    ++readers[map[v]];
    pending[v] = 1;
    ++remaining;
  }
  // Ready destinations are taken lowest first, so that most writes go up through the array.
  std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> ready;
  for (std::size_t v = 0; v < count; ++v)
    if (pending[v] && readers[v] == 0) ready.push(std::uint32_t(v));
  plan.moves.reserve(2 * (remaining + remaining / 8 + 1));
  const auto held = std::uint32_t(count);  // the slot past the destinations
  std::uint32_t saved = none;              // the slot whose value is held
  std::size_t scan = 0;
  while (remaining > 0) {
    while (!ready.empty()) {
      const std::uint32_t v = ready.top();
      ready.pop();
      const std::uint32_t s = map[v];
      plan.moves.push_back(v);
      plan.moves.push_back(s == saved ? held : s);
      pending[v] = 0;
      --remaining;
      if (s != saved && --readers[s] == 0 && pending[s]) ready.push(s);
    }
    if (remaining == 0) break;
    while (!pending[scan]) ++scan;
    // Every pending slot is on a cycle now: hold this one's value and write it.
    plan.moves.push_back(held);
    plan.moves.push_back(std::uint32_t(scan));
    saved = std::uint32_t(scan);
    readers[scan] = 0;
    ready.push(std::uint32_t(scan));
  }
  return plan;
}

Status InPlaceGatherJob::validate() const noexcept {
  if (plan == nullptr) return Status::failure("no plan");
  if (values.size() != plan->destinations + 1) return Status::failure("values: one per destination and one more");
  return {};
}

Status InPlaceGatherJob::run() const noexcept {
  if (const Status status = validate(); !status) return status;
  glm::vec3* const out = values.data();
  const std::uint32_t* move = plan->moves.data();
  const std::uint32_t* const end = move + plan->moves.size();
  for (; move != end; move += 2) out[move[0]] = out[move[1]];
  return {};
}

}  // namespace deform
