#include "deform/runtime/animation.hpp"
#include <algorithm>
#include <cmath>

#include "deform/runtime/error.hpp"
#include "finite.hpp"
namespace deform {
namespace {

template <class T>
void require_valid_track(const Track<T>& track, const char* what, const std::string& source,
                         const std::string& element) {
  auto fail = [&](const std::string& message) {
    throw Error::in_file(source, element, std::string(what) + " track: " + message);
  };
  if (track.values.size() != track.times.size()) fail("values and times differ in count");
  const bool cubic = track.interpolation == Interpolation::cubic_spline;
  const std::size_t tangents = cubic ? track.times.size() : 0;
  if (track.in_tangents.size() != tangents || track.out_tangents.size() != tangents)
    fail(cubic ? "cubic spline needs one in and one out tangent per key" : "tangents given for a non-cubic track");
  for (std::size_t k = 0; k < track.times.size(); ++k) {
    if (!finite(track.times[k])) fail("key " + std::to_string(k) + ": time is not finite");
    if (k > 0 && !(track.times[k] > track.times[k - 1])) fail("key " + std::to_string(k) + ": times not increasing");
    if (!finite(track.values[k])) fail("key " + std::to_string(k) + ": value is not finite");
    if (cubic && !(finite(track.in_tangents[k]) && finite(track.out_tangents[k])))
      fail("key " + std::to_string(k) + ": tangent is not finite");
  }
}

// The segment [k, k+1] holding `t` and the fraction u in [0, 1] along it; k = last key and u = 0 past the end.
struct Segment {
  std::size_t k;
  float u;
  float dt;
};

Segment find_segment(const std::vector<float>& times, float t) noexcept {
  if (t <= times.front()) return {0, 0.0f, 0.0f};
  if (t >= times.back()) return {times.size() - 1, 0.0f, 0.0f};
  const auto next = std::upper_bound(times.begin(), times.end(), t);
  const std::size_t k = static_cast<std::size_t>(next - times.begin()) - 1;
  const float dt = times[k + 1] - times[k];
  return {k, std::clamp((t - times[k]) / dt, 0.0f, 1.0f), dt};
}

// Cubic Hermite basis (glTF 2.0 spec, appendix C): p0, m0 (out tangent of key k), p1, m1 (in tangent of key k+1).
template <class T>
T hermite(T p0, T m0, T p1, T m1, float u, float dt) noexcept {
  const float u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * dt * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * dt * m1;
}

// The sizes a sampled track relies on: a value per time and, for a cubic spline, a tangent of each kind per time.
template <class T>
bool track_fits(const Track<T>& track) noexcept {
  const std::size_t tangents = track.interpolation == Interpolation::cubic_spline ? track.times.size() : 0;
  return track.values.size() == track.times.size() && track.in_tangents.size() >= tangents &&
         track.out_tangents.size() >= tangents;
}

// What SamplingJob::run checks for channels [begin, end).
Status run_checks(const SamplingJob& job, std::size_t begin, std::size_t end) noexcept {
  if (job.animation == nullptr) return Status::failure("no animation");
  if (!std::isfinite(job.time)) return Status::failure("time is not finite");
  if (begin > end || end > job.animation->channels.size()) return Status::failure("channel range out of bounds");
  const std::size_t bones = std::min(job.rotations.size(), job.translations.size());
  for (std::size_t c = begin; c < end; ++c) {
    const std::int32_t bone = job.animation->channels[c].bone;
    if (bone < 0 || static_cast<std::size_t>(bone) >= bones) return Status::failure("channel bone out of the pose");
  }
  return {};
}

}  // namespace

glm::vec3 sample_track(const Track<glm::vec3>& track, float seconds, glm::vec3 fallback) noexcept {
  if (track.empty()) return fallback;
  const Segment s = find_segment(track.times, seconds);
  if (s.dt == 0.0f || track.interpolation == Interpolation::step) return track.values[s.k];
  if (track.interpolation == Interpolation::linear) return glm::mix(track.values[s.k], track.values[s.k + 1], s.u);
  return hermite(track.values[s.k], track.out_tangents[s.k], track.values[s.k + 1], track.in_tangents[s.k + 1], s.u,
                 s.dt);
}

glm::quat sample_track(const Track<glm::quat>& track, float seconds, glm::quat fallback) noexcept {
  if (track.empty()) return fallback;
  const Segment s = find_segment(track.times, seconds);
  if (s.dt == 0.0f || track.interpolation == Interpolation::step) return track.values[s.k];
  const glm::quat a = track.values[s.k], b = track.values[s.k + 1];
  if (track.interpolation == Interpolation::linear) {
    // glm::slerp takes the shorter arc (it negates b when the dot product is negative).
    return glm::normalize(glm::slerp(a, b, s.u));
  }
  const glm::quat q = hermite(a, track.out_tangents[s.k], b, track.in_tangents[s.k + 1], s.u, s.dt);
  const float length = glm::length(q);
  return length > 0.0f ? q / length : a;
}

float sample_track(const Track<float>& track, float seconds, float fallback) noexcept {
  if (track.empty()) return fallback;
  const Segment s = find_segment(track.times, seconds);
  if (s.dt == 0.0f || track.interpolation == Interpolation::step) return track.values[s.k];
  if (track.interpolation == Interpolation::linear)
    return track.values[s.k] + (track.values[s.k + 1] - track.values[s.k]) * s.u;
  return hermite(track.values[s.k], track.out_tangents[s.k], track.values[s.k + 1], track.in_tangents[s.k + 1], s.u,
                 s.dt);
}

Status sample_morph_weights(const Animation& clip, float seconds, std::span<float> weights) noexcept {
  if (!std::isfinite(seconds)) return Status::failure("time is not finite");
  for (const MorphChannel& channel : clip.morph_channels) {
    if (channel.target < 0 || static_cast<std::size_t>(channel.target) >= weights.size())
      return Status::failure("morph channel target out of range");
    if (!track_fits(channel.weight)) return Status::failure("track values or tangents do not match its times");
  }
  const float t = clip.local_time(seconds);
  for (const MorphChannel& channel : clip.morph_channels) {
    float& w = weights[static_cast<std::size_t>(channel.target)];
    w = sample_track(channel.weight, t, w);
  }
  return {};
}

float Animation::local_time(float seconds) const noexcept {
  if (!(duration > 0.0f)) return 0.0f;
  if (!loop) return std::clamp(seconds, 0.0f, duration);
  float t = std::fmod(seconds, duration);
  if (t < 0.0f) t += duration;
  return t < duration ? t : 0.0f;  // t + duration can round up to duration for tiny negative t
}

std::size_t SamplingJob::count() const noexcept { return animation == nullptr ? 0 : animation->channels.size(); }

Status SamplingJob::validate() const noexcept {
  if (const Status status = run_checks(*this, 0, count()); !status) return status;
  for (const Channel& channel : animation->channels)
    if (!track_fits(channel.translation) || !track_fits(channel.rotation) || !track_fits(channel.scale))
      return Status::failure("track values or tangents do not match its times");
  return {};
}

Status SamplingJob::run() const noexcept { return run(0, count()); }

Status SamplingJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = run_checks(*this, begin, end); !status) return status;
  const float t = animation->local_time(time);
  for (std::size_t c = begin; c < end; ++c) {
    const Channel& channel = animation->channels[c];
    const auto b = static_cast<std::size_t>(channel.bone);
    translations[b] = sample_track(channel.translation, t, translations[b]);
    rotations[b] = sample_track(channel.rotation, t, rotations[b]);
  }
  return {};
}

void Animation::require_valid(std::size_t bone_count, const std::string& source) const {
  const std::string clip = "clip '" + name + "'";
  if (!std::isfinite(duration) || duration < 0.0f)
    throw Error::in_file(source, clip, "duration is not finite and >= 0");
  std::vector<bool> seen(bone_count, false);
  for (const Channel& channel : channels) {
    const std::string element = clip + ": bone " + std::to_string(channel.bone);
    if (channel.bone < 0 || static_cast<std::size_t>(channel.bone) >= bone_count)
      throw Error::in_file(source, element, "bone out of range (skeleton has " + std::to_string(bone_count) + ")");
    if (seen[static_cast<std::size_t>(channel.bone)])
      throw Error::in_file(source, element, "two channels for one bone");
    seen[static_cast<std::size_t>(channel.bone)] = true;
    require_valid_track(channel.translation, "translation", source, element);
    require_valid_track(channel.rotation, "rotation", source, element);
    require_valid_track(channel.scale, "scale", source, element);
  }
  std::vector<std::int32_t> targets;
  for (const MorphChannel& channel : morph_channels) {
    const std::string element = clip + ": morph target " + std::to_string(channel.target);
    if (channel.target < 0) throw Error::in_file(source, element, "morph target out of range");
    targets.push_back(channel.target);
    require_valid_track(channel.weight, "weight", source, element);
  }
  std::sort(targets.begin(), targets.end());
  if (std::adjacent_find(targets.begin(), targets.end()) != targets.end())
    throw Error::in_file(source, clip, "two morph channels for one target");
}

std::int32_t find_clip(const std::vector<Animation>& clips, const std::string& name) noexcept {
  for (std::size_t i = 0; i < clips.size(); ++i)
    if (clips[i].name == name) return static_cast<std::int32_t>(i);
  return -1;
}

}  // namespace deform
