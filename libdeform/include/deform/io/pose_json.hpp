#pragma once
// Poses as JSON: {"bones": {"NAME": {"rotation": [x, y, z], "translation": [x, y, z]}}}, Euler degrees.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "deform/io/export.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Applies a JSON pose to a copy of the bind pose: listed bones take the given Euler rotation (clamped into the DOF
// limits when `clamp`) and/or translation. Unknown bones, non-finite numbers and wrong-length arrays throw
// deform::Error naming the key.
DEFORM_IO_API Pose parse_pose_json(std::string_view json, const Skeleton& skeleton, bool clamp = true,
                                   const std::string& name = "<memory>");
DEFORM_IO_API Pose read_pose_json(const std::string& path, const Skeleton& skeleton, bool clamp = true);
// Formats the given bones of a pose (all when `bones` is empty) as the JSON object {"NAME": {"rotation": [...],
// "translation": [...]}, ...} (without the outer {"bones": ...}), Euler degrees: each rotation as the triple its bone's
// DOF limits mean, within them (euler_within_limits), so that parse_pose_json reads back the same rotation when it is
// within the limits, and the clamped one it would make anyway when not. Without `within_limits`, the canonical triple
// (euler_from_quat), unclamped: the exact rotation, for a reader that does not clamp (parse_pose_json, clamp false).
DEFORM_IO_API std::string format_pose_bones_json(const Skeleton& skeleton, const Pose& pose,
                                                 std::span<const std::int32_t> bones = {}, bool within_limits = true);

}  // namespace deform
