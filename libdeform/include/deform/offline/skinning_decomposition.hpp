#pragma once
// Skinning decomposition (docs/gltf-export.md, "Baking bones"): an animated mesh approximated by linear blend
// skinning with a few extra rigid bones and sparse weights, after Le & Deng, "Smooth Skinning Decomposition with
// Rigid Bones" (ACM TOG 31(6), 2012). What the lattices, their jiggle or any other deformer did to a character
// becomes ordinary skeletal animation, which any engine plays, blends and retimes without libdeform.
//
// The body's own bones keep their animation; extra bones, each the child of a body bone so that it follows the body,
// carry what skinning alone does not explain. Points the deformers leave alone keep the artist's weights exactly;
// the others get at most `influences` weights, non-negative and summing to one, over their own bones and the extra
// ones. The two steps of the paper alternate: each extra bone's rigid transform per frame by weighted least
// squares (a Procrustes fit of what the other bones leave), then each moved point's weights by non-negative least
// squares. Bind time, not per frame: it allocates and throws.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/offline/export.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// One clip to approximate, frame by frame: where the body's bones are, and where every mesh point is.
struct DecompositionFrames {
  std::string name = "bake";  // the clip's name in the result
  std::vector<float> times;   // seconds, finite, >= 0, strictly increasing; one per frame
  // Per frame: each body bone's model-space matrix (Character::palette() times the bone's bind matrix). Only its
  // rotation and translation are kept (a Pose has no scale); what a scale did shows up as points to fit.
  std::vector<std::vector<glm::mat4>> bone_world;
  std::vector<std::vector<glm::vec3>> positions;  // per frame: one position per mesh point (Character::positions())
};

struct DecompositionOptions {
  std::size_t max_bones = 24;  // extra bones, in [0, 1000]; fewer when few points move (at least 4 points per bone)
  int influences = 4;          // per moved point, in [1, 8]: 4 for every engine, 8 for glTF's JOINTS_1 / WEIGHTS_1
  int iterations = 30;         // alternations of the weight and bone steps, in [1, 1000]; fewer once converged
  // A point whose every frame is within this of the artist's skinning (a fraction of the bind mesh's bounding-box
  // diagonal) counts as unmoved and keeps the artist's weights. In [0, 1].
  float moved_tolerance = 1e-5f;
  // Rest-space centres the extra bones start from (decomposition_seeds() gives one per lattice slice); empty, too
  // many or too few are all fine: each is kept only when points gather around it, and the rest of the budget goes to
  // the moved points farthest from every centre.
  std::vector<glm::vec3> seeds;
  unsigned threads = 0;  // 0: std::thread::hardware_concurrency(); the result is the same for every count
};

struct SkinningDecomposition {
  // The body's bones (same ids, same bind) followed by the extra bones, each named "<parent key>.bake<N>", bound
  // at the centroid of the points it started with, with its parent's orientation.
  Skeleton skeleton;
  SkinWeights weights;  // the artist's rows for unmoved points, bit for bit; new ones for the moved points
  // Per clip given, in order: every animated bone's local translation and rotation at the frames' times, linear,
  // named as the frames are. A bone that does not move in a clip has no channel there; one that holds another pose
  // throughout has one key.
  std::vector<Animation> clips;
  std::size_t extra_bones = 0;
  std::vector<std::uint32_t> moved_points;  // ascending
  // Distance from the frames' positions to the decomposition's skinning, as fractions of the bind mesh's bounding-box
  // diagonal: root mean square over every point of every frame, the largest, and both per frame (the clips' frames
  // one after the other).
  float rms_error = 0.0f;
  float max_error = 0.0f;
  std::vector<float> frame_rms_error;
  std::vector<float> frame_max_error;
  int iterations = 0;  // alternations run
};

// Decomposes the clips of `model` (its mesh's bind positions, skeleton and weights) together: one set of extra
// bones and weights for all of them, so that one file plays every clip. Throws deform::Error (kind argument) naming
// the field when the options are out of range, there are no clips or a clip has no frames or inconsistent ones (a
// bone_world or positions entry of the wrong size, times not increasing) or holds a non-finite number.
// Deterministic: the same input gives the same bits for any thread count. Cost per iteration: O(frames · moved
// points · candidates²), candidates = a moved point's own bones, the extra bones it uses and its nearest extra bones
// (16 at most).
DEFORM_OFFLINE_API SkinningDecomposition decompose_skinning(const Model& model,
                                                            std::span<const DecompositionFrames> clips,
                                                            const DecompositionOptions& options = {});
// One clip.
DEFORM_OFFLINE_API SkinningDecomposition decompose_skinning(const Model& model, const DecompositionFrames& frames,
                                                            const DecompositionOptions& options = {});

// Starting centres from a hierarchy's lattices: for each lattice, the centroid of each slice of its rest control
// points across the bone (degree.x + 1 per lattice), in the model's bind space.
DEFORM_OFFLINE_API std::vector<glm::vec3> decomposition_seeds(const DeformerHierarchy& hierarchy,
                                                              const Skeleton& skeleton);

// Non-negative least squares in normal-equation form, the weight step's solver: x >= 0 minimising
// ½ xᵀ G x − hᵀ x, for G (n × n, row-major, symmetric positive semidefinite) and h, n <= 32. Lawson & Hanson's
// active-set method (Solving Least Squares Problems, 1974, ch. 23). Writes x (n entries) and returns false only
// when it stopped at its iteration limit (3n) before the optimality conditions held to a relative 1e-10.
DEFORM_OFFLINE_API bool nonnegative_least_squares(std::span<const double> gram, std::span<const double> rhs,
                                                  std::span<double> x);

}  // namespace deform
