#pragma once
// Base (private to libdeform, not installed; docs/architecture.md, "Walls"): the hierarchy rules of docs/formats.md,
// shared by the Skeleton constructor (runtime, which names the bone) and the .sk reader (io, which also names the byte
// offset of the offending field). find_bone_problem is defined in skeleton.cpp and exported by deform::runtime, but
// is not in its public headers.
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "deform/runtime/skeleton.hpp"
namespace deform::detail {

// Largest bone count a skeleton (and a .sk file) may hold; skin weights store bone ids as 16 bits.
inline constexpr std::size_t max_bones = 65535;

struct BoneProblem {
  enum class Field { none, translation, rotation, limits, parent, children };
  std::int32_t bone = -1;  // -1 when about the whole skeleton
  Field field = Field::none;
  std::string message;
};

// The first rule `bones` breaks, or nothing. When it returns nothing, `order` (if given, bone_count() entries) holds
// the bone ids parent-before-child, breadth-first from bone 0 through the child lists. Cost O(bones + children).
DEFORM_RUNTIME_API std::optional<BoneProblem> find_bone_problem(std::span<const Bone> bones,
                                                                std::span<std::int32_t> order = {});

}  // namespace deform::detail
