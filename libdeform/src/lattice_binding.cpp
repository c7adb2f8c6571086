// Lattice frames (thesis eqs. 36 and 41), vertex selection (inside the box, index lists, skin weights: §9.4.1) and the
// construction of bindings.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <string>

#include "deform/atomic_file.hpp"
#include "deform/error.hpp"
#include "deform/lattice.hpp"
#include "lattice_kernel.hpp"

namespace deform {

namespace detail {

bool finite(glm::vec3 v) noexcept { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

glm::mat3 cofactor(const glm::mat3& a) noexcept {
  // The rows of det(A)·A⁻¹ are the cross products of A's columns, so they are the columns of det(A)·A^-T.
  return glm::mat3(glm::cross(a[1], a[2]), glm::cross(a[2], a[0]), glm::cross(a[0], a[1]));
}

std::vector<BoundVertex> collect_inside(const LatticeFrame& frame, std::span<const glm::vec3> positions,
                                        std::span<const std::uint32_t> candidates, bool all,
                                        const glm::mat4& to_lattice) {
  const bool identity = to_lattice == glm::mat4(1.0f);
  const std::size_t count = all ? positions.size() : candidates.size();
  std::vector<BoundVertex> list;
  for (std::size_t c = 0; c < count; ++c) {
    const std::size_t p = all ? c : candidates[c];
    if (p >= positions.size() || p >= LatticeBinding::no_vertex)
      throw Error::in_file("<memory>", "candidate " + std::to_string(c),
                           "point " + std::to_string(p) + " is out of range (" + std::to_string(positions.size()) +
                               " points)");
    if (!finite(positions[p]))
      throw Error::in_file("<memory>", "vertex " + std::to_string(p), "position is not finite");
    const glm::vec3 x = identity ? positions[p] : glm::vec3(to_lattice * glm::vec4(positions[p], 1.0f));
    const glm::vec3 uvw = frame.to_lattice(x);
    if (glm::all(glm::greaterThanEqual(uvw, glm::vec3(0.0f))) && glm::all(glm::lessThanEqual(uvw, glm::vec3(1.0f))))
      list.push_back({static_cast<std::uint32_t>(p), 0, uvw});
  }
  return list;
}

LatticeBinding make_binding(LatticeKind kind, glm::ivec3 point_counts, const LatticeFrame& frame,
                            glm::vec3 parameter_scale, const glm::mat4& to_lattice, std::vector<BoundVertex> list) {
  std::stable_sort(list.begin(), list.end(),
                   [](const BoundVertex& a, const BoundVertex& b) { return a.first_point < b.first_point; });
  LatticeBinding binding;
  binding.kind = kind;
  binding.point_counts = point_counts;
  // Normals go into the frame's space by cof(to_lattice), into (u, v, w) by cof(M⁻¹) ∝ Mᵀ, into cell parameters by
  // cof(diag(scale)); the kernel then applies cof(∂Q/∂t). Positive factors are dropped: normals are normalised.
  const glm::mat3 axes(frame.u_axis, frame.v_axis, frame.w_axis);
  binding.normal_basis = cofactor(glm::mat3(glm::vec3(parameter_scale.x, 0, 0), glm::vec3(0, parameter_scale.y, 0),
                                            glm::vec3(0, 0, parameter_scale.z))) *
                         glm::transpose(axes) * cofactor(glm::mat3(to_lattice));
  binding.vertex_count = list.size();
  constexpr std::size_t lanes = LatticeBinding::block_size;
  for (std::size_t begin = 0; begin < list.size();) {
    std::size_t end = begin;
    while (end < list.size() && end - begin < lanes && list[end].first_point == list[begin].first_point) ++end;
    binding.block_first_point.push_back(list[begin].first_point);
    for (std::size_t i = begin; i < begin + lanes; ++i) {
      const bool real = i < end;
      binding.vertices.push_back(real ? list[i].vertex : LatticeBinding::no_vertex);
      binding.u.push_back(real ? list[i].param.x : 0.0f);
      binding.v.push_back(real ? list[i].param.y : 0.0f);
      binding.w.push_back(real ? list[i].param.z : 0.0f);
      if (real) binding.max_vertex = std::max(binding.max_vertex, list[i].vertex);
    }
    begin = end;
  }
  return binding;
}

}  // namespace detail

LatticeFrame LatticeFrame::axis_aligned(glm::vec3 origin, glm::vec3 size) noexcept {
  return {origin, glm::vec3(size.x, 0.0f, 0.0f), glm::vec3(0.0f, size.y, 0.0f), glm::vec3(0.0f, 0.0f, size.z)};
}

glm::vec3 LatticeFrame::to_lattice(glm::vec3 point) const noexcept {
  const glm::vec3 d = point - origin;
  if (u_axis.y == 0.0f && u_axis.z == 0.0f && v_axis.x == 0.0f && v_axis.z == 0.0f && w_axis.x == 0.0f &&
      w_axis.y == 0.0f)
    return d / glm::vec3(u_axis.x, v_axis.y, w_axis.z);  // eq. 41
  const glm::vec3 vw = glm::cross(v_axis, w_axis), wu = glm::cross(w_axis, u_axis), uv = glm::cross(u_axis, v_axis);
  return glm::vec3(glm::dot(vw, d) / glm::dot(vw, u_axis), glm::dot(wu, d) / glm::dot(wu, v_axis),
                   glm::dot(uv, d) / glm::dot(uv, w_axis));  // eq. 36
}

glm::vec3 LatticeFrame::to_world(glm::vec3 uvw) const noexcept {
  return origin + uvw.x * u_axis + uvw.y * v_axis + uvw.z * w_axis;
}

void LatticeFrame::validate(const std::string& source, const std::string& element) const {
  if (!detail::finite(origin) || !detail::finite(u_axis) || !detail::finite(v_axis) || !detail::finite(w_axis))
    throw Error::in_file(source, element, "origin or axes are not finite");
  const double lu = glm::length(glm::dvec3(u_axis)), lv = glm::length(glm::dvec3(v_axis)),
               lw = glm::length(glm::dvec3(w_axis));
  const double volume = glm::dot(glm::cross(glm::dvec3(u_axis), glm::dvec3(v_axis)), glm::dvec3(w_axis));
  // Relative to the edge lengths, so a thin but valid box passes and a flat or inside-out one does not.
  if (!(volume > 1e-6 * lu * lv * lw) || !(lu > 0.0) || !(lv > 0.0) || !(lw > 0.0))
    throw Error::in_file(source, element, "the axes span no positive volume (zero size, flat or left-handed)");
  if (!std::isfinite(volume)) throw Error::in_file(source, element, "the axes are too large");
}

std::vector<std::uint32_t> select_by_weight(const SkinWeights& weights, std::uint16_t bone, float threshold) {
  std::vector<std::uint32_t> out;
  const std::size_t count = std::min(weights.bones.size(), weights.weights.size());
  for (std::size_t p = 0; p < count; ++p) {
    float w = 0.0f;
    for (int s = 0; s < max_influences; ++s)
      if (weights.bones[p][s] == bone) w += weights.weights[p][s];
    if (w > threshold) out.push_back(static_cast<std::uint32_t>(p));
  }
  return out;
}

std::vector<std::uint32_t> select_inside(const LatticeFrame& frame, std::span<const glm::vec3> positions,
                                         const glm::mat4& to_lattice) {
  std::vector<std::uint32_t> out;
  for (const detail::BoundVertex& b : detail::collect_inside(frame, positions, {}, true, to_lattice))
    out.push_back(b.vertex);
  return out;
}

std::vector<std::uint32_t> parse_vertex_list(std::string_view text, std::size_t point_count, const std::string& name) {
  std::vector<std::uint32_t> out;
  std::vector<bool> seen(point_count, false);
  std::int64_t line = 1;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line, ++i;
    } else if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
    } else if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
    } else {
      std::size_t end = i;
      while (end < text.size() && text[end] != ' ' && text[end] != '\t' && text[end] != '\r' && text[end] != '\n' &&
             text[end] != '#')
        ++end;
      const std::string_view token = text.substr(i, end - i);
      const std::string element = "entry " + std::to_string(out.size());
      std::uint64_t value = 0;
      const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
      if (ec != std::errc() || ptr != token.data() + token.size())
        throw Error::at_line(name, line, element, "'" + std::string(token) + "' is not a vertex index (0-based)");
      if (value >= point_count)
        throw Error::at_line(name, line, element,
                             "vertex " + std::to_string(value) + " is out of range (" + std::to_string(point_count) +
                                 " vertices)");
      if (seen[value]) throw Error::at_line(name, line, element, "vertex " + std::to_string(value) + " is listed twice");
      seen[value] = true;
      out.push_back(static_cast<std::uint32_t>(value));
      i = end;
    }
  }
  return out;
}

std::vector<std::uint32_t> read_vertex_list(const std::string& path, std::size_t point_count) {
  return parse_vertex_list(read_file_text(path), point_count, path);
}

}  // namespace deform
