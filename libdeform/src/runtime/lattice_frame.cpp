// Lattice frames: parameters of a point in a lattice's box and back (thesis eqs. 36 and 41).
#include <cmath>
#include <string>

#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "finite.hpp"

namespace deform {

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

void LatticeFrame::require_valid(const std::string& source, const std::string& element) const {
  if (!finite(origin) || !finite(u_axis) || !finite(v_axis) || !finite(w_axis))
    throw Error::in_file(source, element, "origin or axes are not finite");
  const double lu = glm::length(glm::dvec3(u_axis)), lv = glm::length(glm::dvec3(v_axis)),
               lw = glm::length(glm::dvec3(w_axis));
  const double volume = glm::dot(glm::cross(glm::dvec3(u_axis), glm::dvec3(v_axis)), glm::dvec3(w_axis));
  // Relative to the edge lengths, so a thin but valid box passes and a flat or inside-out one does not.
  if (!(volume > 1e-6 * lu * lv * lw) || !(lu > 0.0) || !(lv > 0.0) || !(lw > 0.0))
    throw Error::in_file(source, element, "the axes span no positive volume (zero size, flat or left-handed)");
  if (!std::isfinite(volume)) throw Error::in_file(source, element, "the axes are too large");
}

}  // namespace deform
