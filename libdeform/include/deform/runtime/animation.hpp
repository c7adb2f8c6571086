#pragma once
// Animation clips (thesis RV03F01, bone animation): per-bone keyframe tracks sampled into a Pose.
//
// A clip drives the pose; IK and the elastic deformers then act on top of it. Tracks are in the skeleton's own
// space: a bone's translation and rotation keys are the local values a Pose holds (relative to the parent bone).
// Animation::validate checks a clip once, at bind time; SamplingJob is the per-frame path: a binary search per track
// (or, with a cursor, a look at the segment found last frame), no allocation, no I/O.
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <span>
#include <string>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// How a track moves between two keys.
//  - step: holds a key's value until the next key.
//  - linear: lerp for vectors, shortest-path slerp for rotations (normalised; evaluated without acos and sin, by a
//    polynomial angle and sinc: within 1e-6 per component of the exact slerp of the same keys, docs/animation.md).
//  - cubic_spline: cubic Hermite with per-key in/out tangents (glTF CUBICSPLINE: tangents are per second, scaled by
//    the key interval); a rotation result is normalised.
enum class Interpolation : std::uint8_t { step, linear, cubic_spline };

// One animated property of a bone: key times (seconds, strictly increasing) and values, same size. For cubic_spline,
// `in_tangents` and `out_tangents` have one entry per key too; otherwise they are empty. Before the first key the
// track holds the first value, after the last it holds the last. An empty track does not animate its property.
template <class T>
struct Track {
  Interpolation interpolation = Interpolation::linear;
  std::vector<float> times;
  std::vector<T> values;
  std::vector<T> in_tangents;
  std::vector<T> out_tangents;
  bool empty() const noexcept { return times.empty(); }
};

// The tracks of one bone. `scale` is kept as the file gave it (relative to the bone's bind scale, 1 = unchanged) but
// is not applied by SamplingJob, because a Pose has no scale.
struct Channel {
  std::int32_t bone = -1;  // skeleton bone id
  Track<glm::vec3> translation;
  Track<glm::quat> rotation;
  Track<glm::vec3> scale;
};

// The weight of one morph target over time (glTF `weights` channels, one track per target). `target` indexes
// Model::morph_targets.
struct MorphChannel {
  std::int32_t target = -1;
  Track<float> weight;
};

// A clip: named channels over [0, duration] seconds. Bones without a channel are not touched by SamplingJob.
struct DEFORM_RUNTIME_API Animation {
  std::string name;
  float duration = 0.0f;  // seconds, >= 0
  bool loop = true;       // sampling wraps time into [0, duration) when true, clamps into [0, duration] otherwise
  std::vector<Channel> channels;
  // Morph-target weights (blend shapes), sampled by sample_morph_weights; empty for skeleton-only clips.
  // validate() checks their tracks as it checks the bones' (target >= 0, at most one channel per target).
  std::vector<MorphChannel> morph_channels;

  // Checks the clip against a skeleton with `bone_count` bones: duration finite and >= 0, bones in range and at most
  // one channel per bone, every track with times finite and strictly increasing, values (and tangents, sized as
  // above) finite. Throws deform::Error naming `source`, the clip and the bone.
  void require_valid(std::size_t bone_count, const std::string& source = "<memory>") const;

  // The clip-local time `seconds` maps to: wrapped into [0, duration) when looping (negative times too), clamped
  // into [0, duration] otherwise; 0 for a zero-length clip.
  float local_time(float seconds) const noexcept;
};

// Samples a clip at one time into a pose's spans (the per-frame job): the local rotation and translation of every
// animated bone; other bones keep their values (start from Skeleton::bind_pose()). The elements are the clip's
// channels: run(begin, end) samples channels [begin, end), each writing only its own bone (and its own cursor
// entries), so disjoint ranges run on different threads. Assumes the clip passed Animation::validate for the skeleton
// (keys finite and increasing).
//
// Cursor (optional): a caller-owned index per sampled track, cursor_size() = 2 · channels entries (channel c's
// translation at 2c, its rotation at 2c + 1), holding the key segment each track found last run. With one, a track
// first looks at that segment and the next before searching, and only on the side of it that holds the time: O(1)
// for playback forwards by less than a key per frame, the binary search's cost otherwise (backwards, jumps, loops).
// The result is bit for bit the result without a cursor, whatever the cursor holds (zeros, a stale or another clip's
// values: any entry is safe), so one may be shared across clips of a blend only at the cost of searching. Give each
// (instance, clip) pair its own, zero-filled or not, once at bind time.
struct DEFORM_RUNTIME_API SamplingJob {
  const Animation* animation = nullptr;
  float time = 0.0f;                  // seconds, any finite value: Animation::local_time maps it into the clip
  std::span<glm::quat> rotations;     // out: local rotations, index = bone id
  std::span<glm::vec3> translations;  // out: local translations, as many
  std::span<std::uint32_t> cursor{};  // in/out, optional: empty, or cursor_size() entries (see above)

  // The clip is set, the time finite, every channel's bone within both spans, the cursor empty or cursor_size()
  // entries, and every track's values (and tangents) as many as its times. O(channels).
  Status validate() const noexcept;
  // The time, the cursor's size and the bones of the channels it samples (one comparison per channel, a fraction of
  // the searches); on failure writes nothing. O(channels · log keys) without a cursor, O(channels) with one when the
  // time moved forward by less than a key; no allocation.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
  // The clip's channel count, 0 without a clip.
  std::size_t count() const noexcept;
  // The entries a cursor needs: 2 · count().
  std::size_t cursor_size() const noexcept;
};

// One track's value at clip-local time `seconds` (no wrapping). `fallback` is returned for an empty track.
DEFORM_RUNTIME_API glm::vec3 sample_track(const Track<glm::vec3>& track, float seconds, glm::vec3 fallback) noexcept;
DEFORM_RUNTIME_API glm::quat sample_track(const Track<glm::quat>& track, float seconds, glm::quat fallback) noexcept;

DEFORM_RUNTIME_API float sample_track(const Track<float>& track, float seconds, float fallback) noexcept;

// Samples the clip's morph channels at `seconds` (mapped by Animation::local_time) into `weights` (one per morph
// target): each animated target's weight is written, the others are left as they are (start from the targets'
// default weights). Refuses, writing nothing, when the time is not finite or a channel's target is not below
// weights.size() ("morph channel target out of range"). O(channels · log keys), no allocation.
DEFORM_RUNTIME_API Status sample_morph_weights(const Animation& clip, float seconds, std::span<float> weights) noexcept;

// Index of the clip named `name` in `clips`, or -1.
DEFORM_RUNTIME_API std::int32_t find_clip(const std::vector<Animation>& clips, const std::string& name) noexcept;

}  // namespace deform
