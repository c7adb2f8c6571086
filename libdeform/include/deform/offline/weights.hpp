#pragma once
// Automatic skin weights: per-point bone influences for a mesh and skeleton that come without a .skw.
//
// The method (docs/builtin-character.md, "Automatic weights"):
//  1. Each bone is a segment in the bind pose, from its head to its first child's head (order a bone's children so
//     that the first continues its chain). A leaf continues its parent's direction (parent head -> its head) for
//     `leaf_length` times that distance; a root without children is a point.
//  2. A point's distance to a bone is its distance to that segment, except that the part of it lying *behind* the
//     head of a non-root bone counts `behind_head_penalty` times: a point level with the shoulder but inside the
//     torso belongs to the chest, not to the upper arm.
//  3. Hierarchy: only the nearest bone, its parent and its children compete for a point, so a hand never pulls the
//     hip and the left leg never pulls the right one.
//  4. Falloff: each competitor gets (d_nearest / d_bone)^falloff_power (inverse-distance weighting).
//  5. The strongest `max_influences` are kept, those under 0.1% of their sum dropped, the rest normalised; then
//     `smoothing_iterations` passes of one-ring averaging over the mesh's edges (new = 1/2 own + 1/2 mean of the
//     neighbours, then the cut and normalisation again) soften the seams where the nearest bone changes.
// Every point gets at least one positive weight; ties resolve to the lower bone id, so the result is deterministic.
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// Parameters of compute_automatic_weights(); the defaults are what the built-in character uses.
struct AutoWeightsOptions {
  float falloff_power = 4.0f;        // > 0; higher = sharper transitions at the joints
  float behind_head_penalty = 2.0f;  // >= 1; 1 = plain segment distance
  float leaf_length = 1.0f;          // >= 0; a leaf bone's length as a multiple of its distance to its parent
  int max_influences = 4;            // 1 .. deform::max_influences
  int smoothing_iterations = 2;      // >= 0; passes of one-ring averaging (only with a mesh)
  // Per bone id, 0 for a bone that must get no weight (a control or end bone); empty = every bone deforms. Only
  // deforming bones are candidates for the nearest; a non-deforming parent is replaced by its nearest deforming
  // ancestor, non-deforming children are left out. At least one bone must deform.
  std::vector<std::uint8_t> deforming;
};

// A bone's bind-pose segment in world space (metres or whatever unit the skeleton uses).
struct BoneSegment {
  glm::vec3 head{0.0f};
  glm::vec3 tail{0.0f};
};

// The segment of every bone (index = bone id), as step 1 above describes. Cost O(bones).
// Throws deform::Error when leaf_length is negative or not finite.
DEFORM_OFFLINE_API std::vector<BoneSegment> bone_segments(const Skeleton& skeleton, float leaf_length = 1.0f);

// Automatic weights for a mesh's points (one entry per OBJ `v`, mesh.point_count()), smoothed over the edges of its
// triangles. Cost O(points × bones + smoothing_iterations × edges); allocates the result and the point adjacency.
// Throws deform::Error for invalid options or a non-finite point (naming the vertex).
DEFORM_OFFLINE_API SkinWeights compute_automatic_weights(const Mesh& mesh, const Skeleton& skeleton,
                                                         const AutoWeightsOptions& options = {});

// The same for bare points, without adjacency (smoothing_iterations is ignored). Cost O(points × bones).
DEFORM_OFFLINE_API SkinWeights compute_automatic_weights(std::span<const glm::vec3> points, const Skeleton& skeleton,
                                                         const AutoWeightsOptions& options = {});

}  // namespace deform
