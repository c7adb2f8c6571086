// bind_delta_mush: the one-rings (point topology), the triangle fans, the smoothing weights from the mask, then the
// rest points smoothed by DeltaMushJob's own passes and each point's delta in its frame.
#include <algorithm>
#include <cmath>
#include <string>

#include "deform/offline/delta_mush.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/error.hpp"

namespace deform {
namespace {

constexpr const char* element = "delta mush";

// The largest |delta| / frame scale a point may have (see below): beyond, the input's rounding (a skinned rest pose
// is within about 1e-7 of the model size of the rest) would move the point by more than 1e-6 of the model size. A
// point whose smoothed neighbourhood has shrunk so (a small island smoothed to a dot: a lone triangle, a box, an eye)
// keeps its input position. Typical points have about 1.
constexpr double max_amplification = 8.0;
// The smallest share of the tangent edge's squared length in the tangent plane.
constexpr double min_in_plane = 1e-2;

glm::dvec3 dvec(const glm::vec4& p) { return glm::dvec3(p.x, p.y, p.z); }

}  // namespace

DeltaMushBinding bind_delta_mush(const Mesh& mesh, const DeltaMushSettings& settings) {
  if (settings.iterations < 0 || std::uint32_t(settings.iterations) > max_delta_mush_iterations)
    throw Error::invalid_argument(element,
                                  "iterations must be within [0, " + std::to_string(max_delta_mush_iterations) + "]");
  if (!(settings.step > 0.0f && settings.step <= 1.0f))
    throw Error::invalid_argument(element, "step must be within (0, 1]");
  const std::size_t n = mesh.point_count();
  if (n >= std::size_t{0xffffffffu}) throw Error::invalid_argument(element, "2^32 - 1 points or more");
  if (!settings.mask.empty() && settings.mask.size() != n)
    throw Error::invalid_argument(
        element, "mask has " + std::to_string(settings.mask.size()) + " weights for " + std::to_string(n) + " points");
  for (std::size_t i = 0; i < settings.mask.size(); ++i)
    if (!(settings.mask[i] >= 0.0f && settings.mask[i] <= 1.0f))
      throw Error::invalid_argument(element, "point " + std::to_string(i) + ": mask weight not within [0, 1]");
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 p = mesh.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw Error::invalid_argument(element, "point " + std::to_string(i) + ": rest position is not finite");
  }

  DeltaMushBinding b;
  b.iterations = std::uint32_t(settings.iterations);
  b.step = settings.step;
  PointTopology topology = build_point_topology(mesh);  // throws for indices out of range
  b.ring_offsets = std::move(topology.neighbour_offsets);
  b.rings = std::move(topology.neighbours);

  // Fans: for each triangle (a, b, c) of distinct points, a gets (b, c), b gets (c, a), c gets (a, b), so that every
  // cross product turns the same way as the triangle.
  b.fan_offsets.assign(n + 1, 0);
  const auto corners = [&](std::size_t t, std::uint32_t(&p)[3]) {
    for (int c = 0; c < 3; ++c) p[c] = mesh.vertex_point[mesh.triangles[3 * t + std::size_t(c)]];
    return p[0] != p[1] && p[1] != p[2] && p[0] != p[2];
  };
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    std::uint32_t p[3];
    if (corners(t, p))
      for (const std::uint32_t q : p) ++b.fan_offsets[q + 1];
  }
  for (std::size_t i = 0; i < n; ++i) b.fan_offsets[i + 1] += b.fan_offsets[i];
  b.fans.resize(std::size_t{2} * b.fan_offsets[n]);
  {
    std::vector<std::uint32_t> next(b.fan_offsets.begin(), b.fan_offsets.end() - 1);
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
      std::uint32_t p[3];
      if (!corners(t, p)) continue;
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t f = next[p[c]]++;
        b.fans[2 * std::size_t(f)] = p[(c + 1) % 3];
        b.fans[2 * std::size_t(f) + 1] = p[(c + 2) % 3];
      }
    }
  }

  // Smoothing weights; a pinned point (mask 0) and a point with no neighbour do not move.
  b.smoothing.resize(n);
  b.pinned.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const float m = settings.mask.empty() ? 1.0f : settings.mask[i];
    const std::uint32_t ring = b.ring_offsets[i + 1] - b.ring_offsets[i];
    b.pinned[i] = m == 0.0f;
    b.smoothing[i] =
        ring == 0 || m == 0.0f ? glm::vec2(1.0f, 0.0f) : glm::vec2(1.0f - m * b.step, m * b.step / float(ring));
  }
  b.tangent_neighbour.assign(n, DeltaMushBinding::no_frame);
  b.deltas.assign(n, glm::vec3(0.0f));
  if (b.iterations == 0) return b;  // the mush is the input: no deltas, no frames

  // The smoothed rest points, by the job itself.
  std::vector<glm::vec4> scratch(DeltaMushJob::scratch_size(b));
  std::vector<glm::vec3> unused(n);
  DeltaMushJob job;
  job.binding = &b;
  job.in_positions = mesh.positions;
  job.out_positions = unused;
  job.scratch = scratch;
  for (std::size_t pass = 0; pass + 1 < job.passes(); ++pass)
    if (const Status status = job.run_pass(pass, 0, n); !status)
      throw Error::invalid_argument(element, status.reason());
  const std::span<const glm::vec4> s = job.smoothed();

  for (std::uint32_t i = 0; i < n; ++i) {
    if (b.pinned[i]) continue;
    const glm::dvec3 c = dvec(s[i]);
    glm::dvec3 normal(0.0);
    for (std::uint32_t f = b.fan_offsets[i]; f < b.fan_offsets[i + 1]; ++f)
      normal += glm::cross(dvec(s[b.fans[2 * f]]) - c, dvec(s[b.fans[2 * f + 1]]) - c);
    const double nl = glm::length(normal);
    // The neighbour whose edge lies most in the tangent plane (the first of equals).
    double best = -1.0, best_length2 = 0.0;
    std::uint32_t chosen = DeltaMushBinding::no_frame;
    if (nl > 0.0) {
      const glm::dvec3 unit = normal / nl;
      for (std::uint32_t r = b.ring_offsets[i]; r < b.ring_offsets[i + 1]; ++r) {
        const glm::dvec3 e = dvec(s[b.rings[r]]) - c;
        const double ee = glm::dot(e, e);
        if (!(ee > 0.0)) continue;
        const double in_plane = 1.0 - glm::dot(unit, e) * glm::dot(unit, e) / ee;
        if (in_plane > best) best = in_plane, best_length2 = ee, chosen = b.rings[r];
      }
    }
    const glm::dvec3 rest(mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z);
    glm::mat3 frame(1.0f);
    b.tangent_neighbour[i] = chosen;
    if (chosen == DeltaMushBinding::no_frame || best < min_in_plane || !delta_mush_frame(b, s, i, frame)) {
      b.tangent_neighbour[i] = DeltaMushBinding::no_frame;
      b.pinned[i] = 1;
      continue;
    }
    // delta = frameᵀ · (rest − smoothed).
    const glm::dvec3 offset = rest - c;
    const glm::dvec3 d(glm::dot(glm::dvec3(frame[0]), offset), glm::dot(glm::dvec3(frame[1]), offset),
                       glm::dot(glm::dvec3(frame[2]), offset));
    // How far the frame's rounding and the input's moves the result: a perturbation δ of the smoothed points turns
    // the frame by about δ / scale, and the point by |d| · δ / scale, scale the smaller of the fan's edge scale
    // (√(|normal| / triangles)) and the tangent edge's part in the plane.
    const double scale =
        std::min(std::sqrt(nl / double(b.fan_offsets[i + 1] - b.fan_offsets[i])), std::sqrt(best * best_length2));
    if (!(glm::length(d) <= max_amplification * scale)) {
      b.tangent_neighbour[i] = DeltaMushBinding::no_frame;
      b.pinned[i] = 1;
      continue;
    }
    b.deltas[i] = glm::vec3(d);
  }
  return b;
}

}  // namespace deform
