#pragma once
// Lattice binding: which points a lattice moves and their lattice parameters, computed once (runtime/lattice.hpp
// evaluates them per frame).
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/export.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Binds `positions[c]` for every candidate c whose (u, v, w) of `to_lattice · positions[c]` lies in [0, 1]³; other
// candidates are left out (so never deformed). `to_lattice` maps the positions' space into the frame's space (identity
// for a free lattice, the bone's inverse bind world matrix for a bone-bound one). Throws deform::Error for a candidate
// out of range or a non-finite position. O(candidates), allocates the binding.
DEFORM_OFFLINE_API LatticeBinding bind_lattice(const BezierLattice& lattice, std::span<const glm::vec3> positions,
                                               std::span<const std::uint32_t> candidates,
                                               const glm::mat4& to_lattice = glm::mat4(1.0f));
// Every point is a candidate.
DEFORM_OFFLINE_API LatticeBinding bind_lattice(const BezierLattice& lattice, std::span<const glm::vec3> positions,
                                               const glm::mat4& to_lattice = glm::mat4(1.0f));
// As for a Bézier lattice; vertices are grouped by cell so that a block of 16 shares its 64 control points.
DEFORM_OFFLINE_API LatticeBinding bind_lattice(const BsplineLattice& lattice, std::span<const glm::vec3> positions,
                                               std::span<const std::uint32_t> candidates,
                                               const glm::mat4& to_lattice = glm::mat4(1.0f));
DEFORM_OFFLINE_API LatticeBinding bind_lattice(const BsplineLattice& lattice, std::span<const glm::vec3> positions,
                                               const glm::mat4& to_lattice = glm::mat4(1.0f));

// --- vertex selection (candidates for bind) ---

// The points a bone's skin weights select: weight of `bone` > `threshold` (thesis §9.4.1). Ascending order.
DEFORM_OFFLINE_API std::vector<std::uint32_t> select_by_weight(const SkinWeights& weights, std::uint16_t bone,
                                                               float threshold);
// The points inside a frame's box, (u, v, w) of `to_lattice · p` in [0, 1]³. Ascending order.
DEFORM_OFFLINE_API std::vector<std::uint32_t> select_inside(const LatticeFrame& frame,
                                                            std::span<const glm::vec3> positions,
                                                            const glm::mat4& to_lattice = glm::mat4(1.0f));

}  // namespace deform
