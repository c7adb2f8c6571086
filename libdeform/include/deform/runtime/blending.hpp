#pragma once
// Animation blending, additive layers and root-motion extraction: the runtime half of an animation system after
// ozz-animation's BlendingJob and its additive and motion-extraction samples (docs/animation.md).
//
// Per frame:  SamplingJob per clip -> local poses (caller-owned arrays, one per layer)
//             -> BlendingJob (weighted layers with optional per-bone masks, then additive layers)
//             -> LocalToWorldJob -> SkinningJob.
// Every job here points at the caller's arrays (spans), validate() says whether the call is well formed and why
// not, run() computes, run(begin, end) computes a range of bones; nothing is allocated, locked or read outside the
// spans. The bind-time helpers (make_additive_clip, set_subtree_weight) allocate or throw as bind-time calls do.
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <span>

#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// One input of a BlendingJob: a local pose (rotations and translations, index = bone id, as SamplingJob writes them)
// with a weight and an optional per-bone mask. The weight of bone b is `weight · bone_weights[b]` (or `weight` when
// bone_weights is empty): a mask of 0 leaves the bone to the other layers, 1 gives it the layer's full weight.
struct BlendLayer {
  std::span<const glm::quat> rotations;
  std::span<const glm::vec3> translations;
  float weight = 1.0f;                  // within [0, 1e6]
  std::span<const float> bone_weights;  // empty, or one value within [0, 1e6] per bone
};

// Blends layers of local poses into one (the per-frame job). For bone b, with w_i = layer weight · mask of layer i
// and W = Σ w_i:
//  - normal layers: the normalised weighted average. Translations Σ w_i t_i / W; rotations the normalised Σ ±w_i q_i
//    (nlerp), each q_i's sign chosen to lie in the hemisphere of the running sum (q and -q are one rotation, and
//    without the alignment two near-opposite quaternions of nearly the same rotation would cancel). The result does
//    not change when every w_i is scaled by one factor (as long as W stays >= threshold).
//  - rest fallback: when W < threshold the rest pose (rest_rotations/rest_translations, usually
//    Skeleton::bind_pose()) joins the average with weight threshold - W, so a bone that no layer drives (W = 0)
//    takes the rest pose and one that layers drive weakly moves continuously towards it (ozz's rule).
//  - additive layers, after the blend, in order: each holds a delta pose (additive_delta, make_additive_clip) and
//    with a bone weight w (weight · mask, >= 0) turns the result (q, t) into (q · Δq^w, t + w · Δt): Δq^w is the
//    slerp from the identity to Δq by w (taken along the shorter arc; w > 1 extrapolates), so weight 1 applies the
//    delta whole and 0 leaves the pose.
// Output spans may be the same arrays as one layer's input (in place): each bone reads its inputs before writing.
// The elements are the bones: run(begin, end) writes bones [begin, end) only, so ranges run on different threads.
// Cost: O(bones · layers), float, a square root per bone (and an atan2, a sin and a cos per bone and additive layer
// of a weight other than 0 or 1).
struct DEFORM_RUNTIME_API BlendingJob {
  std::span<const BlendLayer> layers;            // normal layers (may be empty: the rest pose, then additive layers)
  std::span<const BlendLayer> additive_layers;   // delta poses applied on top, may be empty
  float threshold = 0.1f;                        // [1e-6, 1e6]: below this accumulated weight the rest pose joins
  std::span<const glm::quat> rest_rotations;     // one per bone
  std::span<const glm::vec3> rest_translations;  // one per bone
  std::span<glm::quat> rotations;                // out: one per bone (the bone count)
  std::span<glm::vec3> translations;             // out: as many

  // For run_parallel (parallel.hpp): ranges cut at multiples of 16 bones (whole cache lines of both outputs when
  // the arrays start on one), in chunks of at least 4096 bones by default: a bone costs a few nanoseconds per layer
  // and a thread wake-up several microseconds, so a skeleton (tens to hundreds of bones) stays on one thread, and a
  // crowd's poses laid end to end are what splitting is for.
  static constexpr std::size_t split_multiple = 16;
  static constexpr std::size_t min_parallel_chunk = 4096;

  // Ok when the call is well formed, else why not: "threshold is not within [1e-6, 1e6]", "rest pose size differs",
  // "output sizes differ", "layer pose size differs", "layer weight is not within [0, 1e6]", "layer mask size
  // differs", "layer mask weight is not within [0, 1e6]", "layer pose is not finite", "rest pose is not finite".
  // (The ranges keep every weighted sum of finite poses finite.)
  // O(bones · layers): at bind time, or after the inputs may have gone wrong.
  Status validate() const noexcept;
  // Checks what is O(layers) (sizes, weights, the threshold, the range: "range outside the job") and refuses,
  // writing nothing, when that fails; the per-bone checks of validate() are the caller's to have made.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  // The bone count: rotations.size().
  std::size_t count() const noexcept { return rotations.size(); }
};

// The delta pose that turns `reference` into `pose` as an additive layer: Δq = q_ref⁻¹ · q, Δt = t - t_ref, per
// bone. Applied with weight 1 on top of the reference (BlendingJob) it gives `pose` back; the delta of the reference
// itself is the identity (Δq = 1, Δt = 0). All six spans of one size ("pose sizes differ"); writes nothing on
// failure. O(bones), no allocation. `out_*` may be `pose`'s arrays.
DEFORM_RUNTIME_API Status additive_delta(std::span<const glm::quat> reference_rotations,
                                         std::span<const glm::vec3> reference_translations,
                                         std::span<const glm::quat> rotations, std::span<const glm::vec3> translations,
                                         std::span<glm::quat> out_rotations,
                                         std::span<glm::vec3> out_translations) noexcept;

// An additive clip from `clip` (bind time): every channel's keys become deltas from the reference, so sampling the
// result at any time gives additive_delta(reference, clip sampled at that time) for the channel's bone (to float
// rounding: left-multiplying by q_ref⁻¹ commutes with slerp, with the Hermite spline and with its normalisation).
// Sample it into a pose that starts as the identity (rotations 1, translations 0) — a bone without a channel has no
// delta — and give that pose to BlendingJob::additive_layers. The reference is the clip's first frame (each track
// at time 0) or, in the second form, `reference` (a pose of the skeleton the clip was validated for). Scale tracks
// are copied unchanged. Throws deform::Error (argument) naming the clip and bone when a channel's bone is outside
// `reference`.
DEFORM_RUNTIME_API Animation make_additive_clip(const Animation& clip);
DEFORM_RUNTIME_API Animation make_additive_clip(const Animation& clip, const Pose& reference);

// Sets `mask[b] = weight` for `bone` and every bone below it (bind time; e.g. the upper body from the spine up).
// Throws deform::Error (argument) when the bone is not in the skeleton or the mask is not one entry per bone.
DEFORM_RUNTIME_API void set_subtree_weight(const Skeleton& skeleton, std::int32_t bone, float weight,
                                           std::span<float> mask);

// --- root motion ---

// A planar rigid motion about the up axis: turn by `yaw` (radians, right-handed about up), after moving by
// `translation` (perpendicular to up). As a transform: T(translation) · R_up(yaw).
struct RootMotion {
  glm::vec3 translation{0.0f};
  float yaw = 0.0f;
};

// The rotation about unit axis `up` contained in q (the twist of its swing-twist decomposition, the same for
// q = twist · swing and q = swing · twist), as an angle in (-π, π]; 0 where the twist is undefined (a half turn about
// an axis perpendicular to up).
DEFORM_RUNTIME_API float twist_angle(glm::quat q, glm::vec3 up) noexcept;
// `first` then `second` (second expressed in the frame first ends in): T(t1) R(y1) · T(t2) R(y2).
DEFORM_RUNTIME_API RootMotion compose(const RootMotion& first, const RootMotion& second, glm::vec3 up) noexcept;
// The inverse motion.
DEFORM_RUNTIME_API RootMotion inverse(const RootMotion& motion, glm::vec3 up) noexcept;

// Extracts a clip's root motion over a time interval (the per-frame job, one element).
//
// Contract. Let p(s), q(s) be the root bone's local translation and rotation in the clip at clip-local time s (its
// tracks; the rest values where a track is missing), h(s) = p(s) - (p(s)·up) up its horizontal part and
// φ(s) = twist_angle(q(s)) - twist_angle(q(0)) its yaw relative to the first frame, wrapped into (-π, π] (so a clip
// may turn less than half a turn from its first frame at any time). The motion frame is G(s) = T(h(s)) · R_up(φ(s)),
// and the root splits into that frame and an in-place remainder:
//     T(p) · R(q) = G(s) · T((p·up) up) · R_up(-φ(s)) · q.
// The in-place remainder keeps the vertical part of the translation, has no horizontal translation and keeps the
// first frame's yaw: that is what run() writes into the optional pose spans (the extracted components held in place;
// φ is taken from the pose's own rotation there, so a blended pose is put in place the same way).
// Unwrapped time t = k·D + s (D the duration, s = Animation::local_time(t)) of a looping clip has the frame
// M(t) = L^k · G(0)⁻¹ G(s), with L = G(0)⁻¹ G(D) the motion of one whole loop (the clip's last frame, as its tracks
// give it at D). The motion over [from, to] is M(from)⁻¹ · M(to): the translation is expressed in the motion frame at
// `from` (apply it to the character as character = character · T(translation) · R_up(yaw)), the yaw is the sum of
// the turns (not wrapped: three loops of a quarter-turn clip give 3π/2), and intervals compose exactly, [a, b] then
// [b, c] is [a, c], across any number of loops and backwards (to < from). A clip that does not loop clamps both times
// into [0, D] (no loops). A character moved by these motions from G(0) (the root's horizontal first-frame position,
// often the origin) and posed with the in-place remainder reproduces the clip's root exactly.
// Cost: four track samples and O(log loops) compositions; no allocation.
struct DEFORM_RUNTIME_API RootMotionJob {
  const Animation* animation = nullptr;
  std::int32_t bone = 0;                            // the root bone whose motion is extracted (e.g. the hips)
  glm::vec3 up{0.0f, 1.0f, 0.0f};                   // unit axis in the bone's parent space; the ground is normal to it
  glm::quat rest_rotation{1.0f, 0.0f, 0.0f, 0.0f};  // the bone's values where the clip has no track for it
  glm::vec3 rest_translation{0.0f};
  float from = 0.0f;  // seconds, unwrapped (as SamplingJob::time)
  float to = 0.0f;
  RootMotion* motion = nullptr;  // out: the motion over [from, to]
  // Optional in/out: a pose (usually the clip sampled at `to`) whose bone `bone` is put in place as above; both
  // empty, or both holding `bone`.
  std::span<glm::quat> rotations;
  std::span<glm::vec3> translations;

  // Ok when the call is well formed: "no animation", "no output", "times are not finite", "up axis is not a unit
  // vector", "rest values are not finite", "bone is negative", "bone is outside the pose", "too many loops" (more than
  // 2^40 between the times). O(1) (the clip is assumed validated: Animation::validate).
  Status validate() const noexcept;
  Status run() const noexcept;
  // One element (the interval): run(0, 1) is run().
  Status run(std::size_t begin, std::size_t end) const noexcept;
  std::size_t count() const noexcept { return 1; }
};

}  // namespace deform
