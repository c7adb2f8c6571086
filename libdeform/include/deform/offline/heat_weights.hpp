#pragma once
// Automatic skin weights by bone heat diffusion (Baran & Popović 2007, "Automatic Rigging and Animation of 3D
// Characters", section 4): weights that follow the surface of the body instead of straight-line distance, so a hand
// resting against a thigh keeps its arm's weights. docs/weights.md describes the method and measures it against the
// weights artists painted.
//
// The method, per point j of the mesh (points sharing one exact position are welded first, so a seam of split
// points is one surface):
//  1. Bones are segments in the bind pose: from the head to the head of *each* child (a bone that forks, such as a
//     pelvis, is the union of its segments); a leaf continues its parent's direction for `leaf_length` times its
//     distance to the parent (as bone_segments() does); a root without children is a point. A leaf's segment, and
//     each segment of a bone that forks, ends where it leaves the mesh (an IK goal parented to the spine and placed
//     at the hand must not make the spine reach along the arm).
//  2. Heat: among the bones, nearest first, the first one *visible* from the point heats it: p_j = that bone, H_jj =
//     heat / d². Bones as near (within 1e-5 of d: behind a joint, where a parent's segment ends at its child's head, as
//     at an elbow or a heel) tie with it: of a bone and its descendant the ancestor heats the point; k bones none of
//     which descends from another share it, p_j = 1/k each (the paper's rule for ties). The weights do not depend on
//     the bones' numbering. Nearest counts a bone seen obliquely as farther: at angle θ from the inward normal, its
//     distance times 1 + oblique_penalty · (1 − cos θ) (the bone straight behind a point is the one it lies on; one
//     beside it, a neighbouring part's). Visible: the bone lies behind the surface (the direction to its nearest point
//     within 78° of the inward normal; normals are turned per island so that most points have their nearest bone behind
//     them) and the straight segment from the point to it crosses no triangle of the mesh but the point's own. A point
//     that sees no bone gets no heat (H_jj = 0) and takes its weights from its neighbours; an island where no point
//     sees a bone behind it takes the nearest visible bone on either side.
//  3. For each bone i, solve (L + A·H) w_i = A·H·p_i over the surface, L the cotangent Laplacian (negative
//     cotangents clamped to 0, degenerate triangles skipped, plus 1e-3 of a uniform Laplacian over every edge so
//     that a surface of slivers stays connected), A the barycentric point areas. The matrix is the same for every
//     bone: it is factored once (sparse LDLᵀ), then each bone is one back-substitution. Each connected piece of the
//     surface (island) is solved on its own; the weights of a piece sum to 1 at every point.
//  4. An island where no point sees any bone past the rest of the mesh (a garment around a limb, a plate on a
//     tail: the body hides the bones) looks again past its own triangles only, with a warning naming it. An island
//     that still sees none is bound rigidly to the bone nearest most of its points, with a warning naming it.
//  5. The strongest `max_influences` weights are kept, those under 0.1% of their sum dropped, the rest normalised,
//     strongest first; past the fourth in SkinWeights' extras. Then `smoothing_iterations` passes of smoothing over
//     the surface (none by default).
// Cost: O(points × bones) for the nearest bones, a ray per point and tried bone (BVH, docs/performance.md), one
// sparse factorisation (about O(points^1.5) for a surface) and one solve per heated bone.
#include <cstdint>
#include <string>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

struct HeatWeightsOptions {
  int max_influences = 4;    // 1 .. deform::max_requested_influences (16); past 4 in SkinWeights' extras
  float heat = 1.0f;         // > 0: c of H = c / d²; 1 is the paper's value, higher = sharper joints
  float leaf_length = 1.0f;  // >= 0: a leaf bone's length as a multiple of its distance to its parent
  // >= 0: how much farther a bone seen obliquely counts when the nearest is chosen (step 2 above; 0 = the plain
  // distance, the paper's rule). docs/weights.md has the measurements behind 0.3.
  float oblique_penalty = 0.3f;
  bool visibility = true;  // false: the nearest bone heats each point whether it sees it or not
  // An island (a connected piece of the surface) none of whose points sees a bone past the rest of the mesh (a
  // garment around a limb, a plate on a tail) looks again past its own triangles only; false: it is bound rigidly.
  bool island_visibility = true;
  // 0 .. 100: passes of surface smoothing after the cut (smooth_weights, weight_tools.hpp: half own, half the mean
  // of the neighbours), keeping `max_influences`, then influences under 0.1% dropped again. 0, the default, is the
  // paper's method; a few passes soften the joints of a coarse mesh.
  int smoothing_iterations = 0;
  // Per bone id, 0 for a bone that must get no weight (a control or end bone); empty = every bone deforms. At
  // least one bone must deform.
  std::vector<std::uint8_t> deforming;
};

// Weights plus what a user should know about them: one line per bone that gets no vertex, per island that no bone
// sees, per point outside every triangle that no bone sees. Never silently empty.
struct WeightsResult {
  SkinWeights weights;
  std::vector<std::string> warnings;
};

// Bone heat weights for the mesh's points (mesh.point_count() entries). Throws deform::Error (kind argument) for
// invalid options, a non-finite point or a triangle index out of range. Allocates O(points · bones) while it works.
DEFORM_OFFLINE_API WeightsResult compute_heat_weights(const Mesh& mesh, const Skeleton& skeleton,
                                                      const HeatWeightsOptions& options = {});

// One warning per bone (of those `deforming` allows; empty = all) that has positive weight on no point:
// "bone 'NAME' (id N) gets no vertex". For any method's weights. O(points + bones).
DEFORM_OFFLINE_API std::vector<std::string> bones_without_vertices(const SkinWeights& weights, const Skeleton& skeleton,
                                                                   const std::vector<std::uint8_t>& deforming = {});

}  // namespace deform
