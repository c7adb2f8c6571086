#pragma once
// Hierarchy binding: the elastic lattices of a rig fitted around their bones and bound to a mesh, once.
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/export.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Fits and binds every lattice to the bind-pose points (`bind_positions`, one per mesh point; `weights` one entry per
// point) as runtime/hierarchy.hpp describes, and builds the hierarchy. Throws deform::Error (naming `source` and
// "lattice 'NAME'") for a bone out of range, a repeated name, a degree out of range, a bad threshold or margin, a
// listed point out of range, invalid elastic settings, or a lattice that selects no point inside its box.
// Allocates; O(lattices × points).
DEFORM_OFFLINE_API DeformerHierarchy bind_hierarchy(const Skeleton& skeleton, std::span<const glm::vec3> bind_positions,
                                                    const SkinWeights& weights, std::vector<LatticeSpec> specs,
                                                    const std::string& source = "<memory>");

}  // namespace deform
