#pragma once
// Delta Mush at bind time: the smoothing topology and each point's rest delta, for DeltaMushJob
// (deform/runtime/delta_mush.hpp; Mancewicz et al. 2014).
#include <cstdint>
#include <span>

#include "deform/offline/export.hpp"
#include "deform/runtime/delta_mush.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform {

struct DeltaMushSettings {
  // Smoothing steps, [0, max_delta_mush_iterations] (Maya's default 10). 0 makes the mush the input itself. More
  // iterations smooth wider folds and cost one pass over the points each.
  int iterations = 10;
  // λ, (0, 1] (Maya's default 0.5): the fraction of the way to its neighbours' mean a point moves per step.
  float step = 0.5f;
  // Empty (every point fully mushed) or one weight per point in [0, 1]: each point's smoothing scaled by it; 0 keeps
  // the input point exactly (bit for bit), e.g. a hand's fingers that should stay as skinned.
  std::span<const float> mask;
};

// Binds `mesh` (its points in the rest pose: Mesh::positions) for Delta Mush. The one-rings are the point topology's
// (build_point_topology: edges between points, so UV and normal seams do not split the smoothing); each point's frame
// comes from the triangles around it and the neighbour whose edge lies most in its tangent plane. A point whose frame
// would amplify rounding (its delta more than 8 times the scale of its smoothed neighbourhood: a small island smoothed
// to a dot — a lone triangle, a box, an eye — or a neighbourhood flattened to a line) is pinned: it keeps its input
// position, as under mask 0, so that the input's rounding (a skinned rest pose is within about 1e-7 of the model size
// of the rest) never turns into a visible move. The rest deltas are computed from the smoothed rest points exactly as
// DeltaMushJob computes them (the job's own passes), so that the rest pose comes back to within float rounding.
// Throws deform::Error (kind argument, element "delta mush") for iterations out of range ("iterations must be within
// [0, 10000]"), a step not within (0, 1], a mask not one per point or a mask weight not within [0, 1] (naming the
// point), rest points that are not finite (naming the point), and what build_point_topology throws. O(iterations ·
// (points + edges) + triangles · log triangles); allocates the binding.
DEFORM_OFFLINE_API DeltaMushBinding bind_delta_mush(const Mesh& mesh, const DeltaMushSettings& settings = {});

}  // namespace deform
