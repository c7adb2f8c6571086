#include "deform/runtime/blending.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "finite.hpp"
namespace deform {
namespace {

constexpr float pi = 3.14159265358979323846f;

// Weights and the threshold stay within ranges where every weighted sum of finite poses stays finite and the
// threshold's share of the rest pose stays a normal float.
constexpr float max_weight = 1e6f, min_threshold = 1e-6f;
bool weight_ok(float w) noexcept { return w >= 0.0f && w <= max_weight; }  // false for NaN

// What run() checks (O(layers)): sizes and weights, never the per-bone values.
Status layer_checks(std::span<const BlendLayer> layers, std::size_t bones) noexcept {
  for (const BlendLayer& layer : layers) {
    if (layer.rotations.size() != bones || layer.translations.size() != bones)
      return Status::failure("layer pose size differs");
    if (!weight_ok(layer.weight)) return Status::failure("layer weight is not within [0, 1e6]");
    if (!layer.bone_weights.empty() && layer.bone_weights.size() != bones)
      return Status::failure("layer mask size differs");
  }
  return {};
}

Status run_checks(const BlendingJob& job, std::size_t begin, std::size_t end) noexcept {
  const std::size_t bones = job.rotations.size();
  if (!(job.threshold >= min_threshold && job.threshold <= max_weight))
    return Status::failure("threshold is not within [1e-6, 1e6]");
  if (job.translations.size() != bones) return Status::failure("output sizes differ");
  if (job.rest_rotations.size() != bones || job.rest_translations.size() != bones)
    return Status::failure("rest pose size differs");
  if (const Status s = layer_checks(job.layers, bones); !s) return s;
  if (const Status s = layer_checks(job.additive_layers, bones); !s) return s;
  if (begin > end || end > bones) return Status::failure("range outside the job");
  return {};
}

float bone_weight(const BlendLayer& layer, std::size_t b) noexcept {
  return layer.bone_weights.empty() ? layer.weight : layer.weight * layer.bone_weights[b];
}

// q^w for a unit quaternion: the slerp from the identity to q by w along the shorter arc.
glm::quat power(glm::quat q, float w) noexcept {
  if (q.w < 0.0f) q = glm::quat(-q.w, -q.x, -q.y, -q.z);
  const float s = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
  if (s < 1e-7f) {
    // Near the identity sin(wθ)/sin(θ) -> w: the first-order term, renormalised.
    const glm::quat r(1.0f, w * q.x, w * q.y, w * q.z);
    return r / std::sqrt(r.w * r.w + r.x * r.x + r.y * r.y + r.z * r.z);
  }
  const float half = std::atan2(s, q.w) * w;  // half angle, scaled
  const float k = std::sin(half) / s;
  return glm::quat(std::cos(half), k * q.x, k * q.y, k * q.z);
}

glm::quat normalized_or(glm::quat q, glm::quat fallback) noexcept {
  const float n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return n > 0.0f && std::isfinite(n) ? q / n : fallback;
}

}  // namespace

Status BlendingJob::validate() const noexcept {
  if (const Status s = run_checks(*this, 0, count()); !s) return s;
  const std::size_t bones = count();
  for (std::size_t b = 0; b < bones; ++b)
    if (!finite(rest_rotations[b]) || !finite(rest_translations[b])) return Status::failure("rest pose is not finite");
  for (const std::span<const BlendLayer> group : {layers, additive_layers})
    for (const BlendLayer& layer : group) {
      for (const float w : layer.bone_weights)
        if (!weight_ok(w)) return Status::failure("layer mask weight is not within [0, 1e6]");
      for (std::size_t b = 0; b < bones; ++b)
        if (!finite(layer.rotations[b]) || !finite(layer.translations[b]))
          return Status::failure("layer pose is not finite");
    }
  return {};
}

Status BlendingJob::run() const noexcept { return run(0, count()); }

// The bones go in chunks of `chunk`, each layer's contribution summed into per-chunk arrays (one array per
// component), so that a layer without a mask is one loop over the chunk with a uniform weight (the compiler keeps
// several bones in flight, or in vector lanes) instead of a dependent chain per bone. Each bone's arithmetic is the
// per-bone rule above in the same order (running sum, hemisphere test against it, rest fallback, normalisation,
// additive layers), so the result is the same bit for bit. Every input of a chunk is read before its outputs are
// written, which keeps in-place blending (an output that is a layer's input) correct.
Status BlendingJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status s = run_checks(*this, begin, end); !s) return s;
  constexpr std::size_t chunk = 16;
  for (std::size_t first = begin; first < end; first += chunk) {
    const std::size_t m = std::min(chunk, end - first);
    float qx[chunk] = {}, qy[chunk] = {}, qz[chunk] = {}, qw[chunk] = {};
    float tx[chunk] = {}, ty[chunk] = {}, tz[chunk] = {}, total[chunk] = {};
    auto add = [&](std::size_t j, glm::quat q, glm::vec3 t, float w) noexcept {
      const float d = qx[j] * q.x + qy[j] * q.y + qz[j] * q.z + qw[j] * q.w;
      const float s = d < 0.0f ? -w : w;
      qx[j] += s * q.x;
      qy[j] += s * q.y;
      qz[j] += s * q.z;
      qw[j] += s * q.w;
      tx[j] += w * t.x;
      ty[j] += w * t.y;
      tz[j] += w * t.z;
      total[j] += w;
    };
    for (const BlendLayer& layer : layers) {
      const glm::quat* rotation = layer.rotations.data() + first;
      const glm::vec3* translation = layer.translations.data() + first;
      if (layer.bone_weights.empty()) {
        const float w = layer.weight;
        if (!(w > 0.0f)) continue;
        for (std::size_t j = 0; j < m; ++j) add(j, rotation[j], translation[j], w);
      } else {
        const float* mask = layer.bone_weights.data() + first;
        for (std::size_t j = 0; j < m; ++j) {
          const float w = layer.weight * mask[j];
          if (w > 0.0f) add(j, rotation[j], translation[j], w);
        }
      }
    }
    for (std::size_t j = 0; j < m; ++j)
      if (total[j] < threshold) {
        add(j, rest_rotations[first + j], rest_translations[first + j], threshold - total[j]);
        total[j] = threshold;
      }
    // normalized_or and the division by the total as plain arithmetic over the chunk's arrays (a loop the compiler
    // runs in vector lanes); a sum that cannot be normalised (zero, or overflowed) takes the rest rotation below.
    int fallback[chunk];
    for (std::size_t j = 0; j < m; ++j) {
      const float n = std::sqrt(qx[j] * qx[j] + qy[j] * qy[j] + qz[j] * qz[j] + qw[j] * qw[j]);
      const bool ok = n > 0.0f && n <= std::numeric_limits<float>::max();  // positive and finite
      const float d = ok ? n : 1.0f;
      qx[j] /= d;
      qy[j] /= d;
      qz[j] /= d;
      qw[j] /= d;
      tx[j] /= total[j];
      ty[j] /= total[j];
      tz[j] /= total[j];
      fallback[j] = ok ? 0 : 1;
    }
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t b = first + j;
      glm::quat q = fallback[j] != 0 ? rest_rotations[b] : glm::quat(qw[j], qx[j], qy[j], qz[j]);
      glm::vec3 t(tx[j], ty[j], tz[j]);
      for (const BlendLayer& layer : additive_layers) {
        const float w = bone_weight(layer, b);
        if (!(w > 0.0f)) continue;
        // Weight 1 (the common case) is the delta itself: no trigonometry.
        q = normalized_or(q * (w == 1.0f ? layer.rotations[b] : power(layer.rotations[b], w)), q);
        t += w * layer.translations[b];
      }
      rotations[b] = q;
      translations[b] = t;
    }
  }
  return {};
}

Status additive_delta(std::span<const glm::quat> reference_rotations, std::span<const glm::vec3> reference_translations,
                      std::span<const glm::quat> rotations, std::span<const glm::vec3> translations,
                      std::span<glm::quat> out_rotations, std::span<glm::vec3> out_translations) noexcept {
  const std::size_t n = rotations.size();
  if (reference_rotations.size() != n || reference_translations.size() != n || translations.size() != n ||
      out_rotations.size() != n || out_translations.size() != n)
    return Status::failure("pose sizes differ");
  for (std::size_t b = 0; b < n; ++b) {
    const glm::quat q = glm::conjugate(reference_rotations[b]) * rotations[b];
    const glm::vec3 t = translations[b] - reference_translations[b];
    out_rotations[b] = q;
    out_translations[b] = t;
  }
  return {};
}

namespace {

// The channel's keys as deltas from (q_ref, t_ref); left-multiplication by q_ref⁻¹ is linear, so it maps tangents as it
// maps values.
Animation additive_from(const Animation& clip, auto&& reference_of) {
  Animation out = clip;
  for (Channel& channel : out.channels) {
    const auto [q_ref, t_ref] = reference_of(channel);
    const glm::quat inv = glm::conjugate(q_ref);
    for (glm::quat& q : channel.rotation.values) q = inv * q;
    for (glm::quat& q : channel.rotation.in_tangents) q = inv * q;
    for (glm::quat& q : channel.rotation.out_tangents) q = inv * q;
    for (glm::vec3& t : channel.translation.values) t -= t_ref;
  }
  return out;
}

}  // namespace

Animation make_additive_clip(const Animation& clip) {
  return additive_from(clip, [](const Channel& channel) {
    // The first frame; an empty track has no delta (identity reference leaves nothing to remove).
    return std::pair{sample_track(channel.rotation, 0.0f, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)),
                     sample_track(channel.translation, 0.0f, glm::vec3(0.0f))};
  });
}

Animation make_additive_clip(const Animation& clip, const Pose& reference) {
  return additive_from(clip, [&](const Channel& channel) {
    const auto bones = std::min(reference.rotations.size(), reference.translations.size());
    if (channel.bone < 0 || static_cast<std::size_t>(channel.bone) >= bones)
      throw Error::invalid_argument("clip '" + clip.name + "': bone " + std::to_string(channel.bone),
                                    "bone outside the reference pose");
    const auto b = static_cast<std::size_t>(channel.bone);
    return std::pair{glm::normalize(reference.rotations[b]), reference.translations[b]};
  });
}

void set_subtree_weight(const Skeleton& skeleton, std::int32_t bone, float weight, std::span<float> mask) {
  if (bone < 0 || static_cast<std::size_t>(bone) >= skeleton.bone_count())
    throw Error::invalid_argument("bone " + std::to_string(bone), "not in the skeleton");
  if (mask.size() != skeleton.bone_count())
    throw Error::invalid_argument("mask", "has " + std::to_string(mask.size()) + " entries for " +
                                              std::to_string(skeleton.bone_count()) + " bones");
  for (std::size_t b = 0; b < mask.size(); ++b)
    if (skeleton.is_ancestor(bone, static_cast<std::int32_t>(b))) mask[b] = weight;
}

// --- root motion ---

float twist_angle(glm::quat q, glm::vec3 up) noexcept {
  const float along = q.x * up.x + q.y * up.y + q.z * up.z;
  if (along == 0.0f && q.w == 0.0f) return 0.0f;
  float angle = 2.0f * std::atan2(along, q.w);  // (-2π, 2π]
  if (angle > pi) angle -= 2.0f * pi;
  if (angle <= -pi) angle += 2.0f * pi;
  return angle;
}

namespace {

glm::vec3 rotate_about(glm::vec3 v, glm::vec3 up, float angle) noexcept { return glm::angleAxis(angle, up) * v; }

float wrap_angle(float a) noexcept {
  a = std::remainder(a, 2.0f * pi);  // [-π, π]
  return a <= -pi ? a + 2.0f * pi : a;
}

}  // namespace

RootMotion compose(const RootMotion& first, const RootMotion& second, glm::vec3 up) noexcept {
  return {first.translation + rotate_about(second.translation, up, first.yaw), first.yaw + second.yaw};
}

RootMotion inverse(const RootMotion& motion, glm::vec3 up) noexcept {
  return {-rotate_about(motion.translation, up, -motion.yaw), -motion.yaw};
}

namespace {

RootMotion power(RootMotion m, std::int64_t n, glm::vec3 up) noexcept {
  if (n < 0) {
    m = inverse(m, up);
    n = -n;
  }
  RootMotion result;
  while (n > 0) {
    if (n & 1) result = compose(result, m, up);
    m = compose(m, m, up);
    n >>= 1;
  }
  return result;
}

struct RootSampler {
  const Channel* channel;
  glm::quat rest_rotation;
  glm::vec3 rest_translation;
  glm::vec3 up;
  float first_yaw;
  // G(0)⁻¹ G(s) = T(h(s) - h(0)) R(φ(s)) with φ(0) = 0: the motion from the first frame to clip-local time s.
  glm::vec3 first_horizontal;

  glm::vec3 horizontal(float s) const noexcept {
    const glm::vec3 p = channel != nullptr ? sample_track(channel->translation, s, rest_translation) : rest_translation;
    return p - glm::dot(p, up) * up;
  }
  float yaw(float s) const noexcept {
    const glm::quat q = channel != nullptr ? sample_track(channel->rotation, s, rest_rotation) : rest_rotation;
    return twist_angle(q, up);
  }
  RootMotion from_start(float s) const noexcept {
    return {horizontal(s) - first_horizontal, wrap_angle(yaw(s) - first_yaw)};
  }
};

Status root_checks(const RootMotionJob& job) noexcept {
  if (job.animation == nullptr) return Status::failure("no animation");
  if (job.motion == nullptr) return Status::failure("no output");
  if (!std::isfinite(job.from) || !std::isfinite(job.to)) return Status::failure("times are not finite");
  if (!finite(job.up) || std::abs(glm::dot(job.up, job.up) - 1.0f) > 1e-4f)
    return Status::failure("up axis is not a unit vector");
  if (!finite(job.rest_rotation) || !finite(job.rest_translation)) return Status::failure("rest values are not finite");
  if (job.bone < 0) return Status::failure("bone is negative");
  const bool pose = !job.rotations.empty() || !job.translations.empty();
  const auto b = static_cast<std::size_t>(job.bone);
  if (pose && (b >= job.rotations.size() || b >= job.translations.size()))
    return Status::failure("bone is outside the pose");
  return {};
}

// The loop index k of unwrapped time t = k·D + local_time(t), for a looping clip of duration D > 0.
double loop_index(const Animation& clip, float t) noexcept {
  const float s = clip.local_time(t);
  return std::round((static_cast<double>(t) - s) / clip.duration);
}

}  // namespace

Status RootMotionJob::validate() const noexcept {
  if (const Status s = root_checks(*this); !s) return s;
  const bool looping = animation->loop && animation->duration > 0.0f;
  if (looping && std::abs(loop_index(*animation, to) - loop_index(*animation, from)) > 1099511627776.0)
    return Status::failure("too many loops");
  return {};
}

Status RootMotionJob::run() const noexcept { return run(0, 1); }

Status RootMotionJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (begin > end || end > 1) return Status::failure("range outside the job");
  if (const Status s = validate(); !s) return s;
  if (begin == end) return {};
  const Channel* channel = nullptr;
  for (const Channel& c : animation->channels)
    if (c.bone == bone) channel = &c;
  RootSampler sampler{channel, rest_rotation, rest_translation, up, 0.0f, glm::vec3(0.0f)};
  sampler.first_yaw = sampler.yaw(0.0f);
  sampler.first_horizontal = sampler.horizontal(0.0f);

  const float s_from = animation->local_time(from), s_to = animation->local_time(to);
  RootMotion result = inverse(sampler.from_start(s_from), up);
  if (animation->loop && animation->duration > 0.0f) {
    const auto loops = static_cast<std::int64_t>(loop_index(*animation, to) - loop_index(*animation, from));
    result = compose(result, power(sampler.from_start(animation->duration), loops, up), up);
  }
  result = compose(result, sampler.from_start(s_to), up);
  *motion = result;

  if (!rotations.empty()) {
    const auto b = static_cast<std::size_t>(bone);
    const glm::vec3 p = translations[b];
    translations[b] = glm::dot(p, up) * up;
    const float phi = wrap_angle(twist_angle(rotations[b], up) - sampler.first_yaw);
    rotations[b] = glm::normalize(glm::angleAxis(-phi, up) * rotations[b]);
  }
  return {};
}

}  // namespace deform
