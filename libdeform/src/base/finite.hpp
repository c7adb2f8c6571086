#pragma once
// Base (private to libdeform, not installed; docs/architecture.md, "Walls"): whether a value's components are all
// finite, the check every layer makes on positions, rotations and transforms it is given. Header-only, so it
// inlines into per-frame code; O(components), no allocation.
#include <cmath>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace deform {

inline bool finite(float x) noexcept { return std::isfinite(x); }
inline bool finite(glm::vec2 v) noexcept { return std::isfinite(v.x) && std::isfinite(v.y); }
inline bool finite(glm::vec3 v) noexcept { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline bool finite(glm::vec4 v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}
inline bool finite(glm::quat q) noexcept {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}
// All sixteen entries, the bottom row included.
inline bool finite(const glm::mat4& m) noexcept { return finite(m[0]) && finite(m[1]) && finite(m[2]) && finite(m[3]); }

}  // namespace deform
