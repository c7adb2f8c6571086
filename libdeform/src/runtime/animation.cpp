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

Segment segment_at(const float* times, std::size_t k, float t) noexcept {
  const float dt = times[k + 1] - times[k];
  return {k, std::clamp((t - times[k]) / dt, 0.0f, 1.0f), dt};
}

Segment find_segment(const std::vector<float>& times, float t) noexcept {
  if (t <= times.front()) return {0, 0.0f, 0.0f};
  if (t >= times.back()) return {times.size() - 1, 0.0f, 0.0f};
  const auto next = std::upper_bound(times.begin(), times.end(), t);
  return segment_at(times.data(), static_cast<std::size_t>(next - times.begin()) - 1, t);
}

// find_segment starting from `hint` (the segment found last time; any value is safe, a stale or foreign one only
// costs the search): the segment is unique (times strictly increase), so this finds the same k and computes the same
// u, bit for bit. Checks the hint's segment and the next one, then searches only the side of the hint that holds t.
// Writes the segment found back into `hint`.
Segment find_segment(const std::vector<float>& times, float t, std::uint32_t& hint) noexcept {
  const std::size_t n = times.size();
  if (t <= times.front()) {
    hint = 0;
    return {0, 0.0f, 0.0f};
  }
  if (t >= times.back()) {
    hint = static_cast<std::uint32_t>(n - 1);
    return {n - 1, 0.0f, 0.0f};
  }
  // Here times[0] < t < times[n - 1], so n >= 2 and the segment k is in [0, n - 2].
  const float* T = times.data();
  const std::size_t h = hint;
  std::size_t k;
  if (h + 1 < n && T[h] <= t) {
    if (t < T[h + 1]) k = h;
    else if (t < T[h + 2]) k = h + 1;  // t >= T[h + 1] and t < T[n - 1]: h + 2 <= n - 1
    else k = static_cast<std::size_t>(std::upper_bound(T + h + 3, T + n, t) - T) - 1;
  } else {
    // t is before T[h] (or h is out of range): the first time after t is in (0, min(h, n - 1)].
    k = static_cast<std::size_t>(std::upper_bound(T + 1, T + std::min(h, n - 1), t) - T) - 1;
  }
  hint = static_cast<std::uint32_t>(k);
  return segment_at(T, k, t);
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
  if (!job.cursor.empty() && job.cursor.size() != job.cursor_size())
    return Status::failure("cursor is neither empty nor two entries per channel");
  const std::size_t bones = std::min(job.rotations.size(), job.translations.size());
  for (std::size_t c = begin; c < end; ++c) {
    const std::int32_t bone = job.animation->channels[c].bone;
    if (bone < 0 || static_cast<std::size_t>(bone) >= bones) return Status::failure("channel bone out of the pose");
  }
  return {};
}

}  // namespace

namespace {

// The shortest-path slerp from a to b by u in [0, 1], normalised: what glm::normalize(glm::slerp(a, b', u)) gives
// (b' = ±b, the sign that makes the dot product >= 0), without acos and sin. With c = a·b' = cos θ (θ <= π/2), the
// slerp is (sin((1 - u)θ) a + sin(uθ) b') / sin θ; the result is normalised, so the common factor 1/(θ sin θ) can go
// and the weights become (1 - u) sinc((1 - u)θ) and ±u sinc(uθ), sinc(x) = sin(x)/x, which tend to the lerp's 1 - u
// and u as θ -> 0 (no division, no special case near 0). θ = acos(c) = sqrt(1 - c) P(c) with Hastings' degree-7
// polynomial P (Abramowitz & Stegun 4.4.46; error <= 2.2e-8 on [0, 1]); sinc(x) by its Taylor series to x^10
// (relative error <= 5.7e-8 for x <= π/2). Against a double-precision slerp of the same keys the result is within
// 1.8e-7 per component (test_animation checks 1e-6 over 200,000 seeded pairs, angles near 0 and near 180° included).
// Without a branch (the sign and the normalisation by selects), so that SamplingJob's loop over a block of pairs
// keeps several in flight; the polynomials by Estrin's scheme (shorter dependency chains than Horner's).
// On plain floats, so that SamplingJob can run it over arrays of pairs in vector lanes; shortest_slerp runs the same
// operations on one pair (the same bits).
struct Quat4 {
  float x, y, z, w;
};
[[gnu::always_inline]] inline Quat4 slerp_components(Quat4 a, Quat4 b, float u) noexcept {
  const float dot = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
  const float sign = dot < 0.0f ? -1.0f : 1.0f;  // b' = sign · b (exact)
  // Non-unit keys may read a little above 1: the lerp there, as glm's slerp takes.
  const float c = std::min(std::abs(dot), 1.0f);
  const float c2 = c * c, c4 = c2 * c2;
  const float p01 = 1.5707963050f - 0.2145988016f * c, p23 = 0.0889789874f - 0.0501743046f * c;
  const float p45 = 0.0308918810f - 0.0170881256f * c, p67 = 0.0066700901f - 0.0012624911f * c;
  const float theta = std::sqrt(1.0f - c) * ((p01 + p23 * c2) + (p45 + p67 * c2) * c4);
  auto sinc = [](float x) noexcept {
    const float y = x * x, y2 = y * y, y4 = y2 * y2;
    const float q01 = 1.0f - y * (1.0f / 6.0f), q23 = 1.0f / 120.0f - y * (1.0f / 5040.0f);
    const float q45 = 1.0f / 362880.0f - y * (1.0f / 39916800.0f);
    return (q01 + q23 * y2) + q45 * y4;
  };
  const float v = 1.0f - u;
  const float wa = v * sinc(v * theta), wb = sign * (u * sinc(u * theta));
  const Quat4 q{wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z, wa * a.w + wb * b.w};
  // glm::normalize's rule: q times 1 / |q|, the identity for a zero q.
  const float length = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  const bool positive = length > 0.0f;
  const float inverse = 1.0f / (positive ? length : 1.0f);
  return {positive ? q.x * inverse : 0.0f, positive ? q.y * inverse : 0.0f, positive ? q.z * inverse : 0.0f,
          positive ? q.w * inverse : 1.0f};
}

glm::quat shortest_slerp(glm::quat a, glm::quat b, float u) noexcept {
  const Quat4 q = slerp_components({a.x, a.y, a.z, a.w}, {b.x, b.y, b.z, b.w}, u);
  return glm::quat(q.w, q.x, q.y, q.z);
}

glm::vec3 value_at(const Track<glm::vec3>& track, const Segment& s) noexcept {
  if (s.dt == 0.0f || track.interpolation == Interpolation::step) return track.values[s.k];
  if (track.interpolation == Interpolation::linear) return glm::mix(track.values[s.k], track.values[s.k + 1], s.u);
  return hermite(track.values[s.k], track.out_tangents[s.k], track.values[s.k + 1], track.in_tangents[s.k + 1], s.u,
                 s.dt);
}

glm::quat value_at(const Track<glm::quat>& track, const Segment& s) noexcept {
  if (s.dt == 0.0f || track.interpolation == Interpolation::step) return track.values[s.k];
  const glm::quat a = track.values[s.k], b = track.values[s.k + 1];
  if (track.interpolation == Interpolation::linear) return shortest_slerp(a, b, s.u);
  const glm::quat q = hermite(a, track.out_tangents[s.k], b, track.in_tangents[s.k + 1], s.u, s.dt);
  const float length = glm::length(q);
  return length > 0.0f ? q / length : a;
}

}  // namespace

glm::vec3 sample_track(const Track<glm::vec3>& track, float seconds, glm::vec3 fallback) noexcept {
  if (track.empty()) return fallback;
  return value_at(track, find_segment(track.times, seconds));
}

glm::quat sample_track(const Track<glm::quat>& track, float seconds, glm::quat fallback) noexcept {
  if (track.empty()) return fallback;
  return value_at(track, find_segment(track.times, seconds));
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

std::size_t SamplingJob::cursor_size() const noexcept { return 2 * count(); }

Status SamplingJob::validate() const noexcept {
  if (const Status status = run_checks(*this, 0, count()); !status) return status;
  for (const Channel& channel : animation->channels)
    if (!track_fits(channel.translation) || !track_fits(channel.rotation) || !track_fits(channel.scale))
      return Status::failure("track values or tangents do not match its times");
  return {};
}

Status SamplingJob::run() const noexcept { return run(0, count()); }

// Channels go in blocks: the translations and the rotations that are not a slerp are written as each channel's
// segments are found; the slerps' keys and fractions are gathered and computed after the block in a loop without
// branches, where the processor overlaps them (a slerp is a long chain of dependent operations). The slerp is the
// same function sample_track calls, on the same inputs: the same bits.
Status SamplingJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = run_checks(*this, begin, end); !status) return status;
  const float t = animation->local_time(time);
  const bool with_cursor = !cursor.empty();
  auto segment = [&](const std::vector<float>& times, std::size_t slot) noexcept {
    return with_cursor ? find_segment(times, t, cursor[slot]) : find_segment(times, t);
  };
  constexpr std::size_t block = 16;
  // The pairs of a block, one array per component (the slerp loop reads them in vector lanes).
  float ax[block], ay[block], az[block], aw[block], bx[block], by[block], bz[block], bw[block], fraction[block];
  std::size_t bone[block];
  for (std::size_t first = begin; first < end; first += block) {
    const std::size_t last = std::min(end, first + block);
    std::size_t pending = 0;
    for (std::size_t c = first; c < last; ++c) {
      const Channel& channel = animation->channels[c];
      const auto b = static_cast<std::size_t>(channel.bone);
      if (!channel.translation.empty())
        translations[b] = value_at(channel.translation, segment(channel.translation.times, 2 * c));
      const Track<glm::quat>& rotation = channel.rotation;
      if (rotation.empty()) continue;
      const Segment s = segment(rotation.times, 2 * c + 1);
      if (rotation.interpolation == Interpolation::linear && s.dt != 0.0f) {
        const glm::quat from = rotation.values[s.k], to = rotation.values[s.k + 1];
        ax[pending] = from.x, ay[pending] = from.y, az[pending] = from.z, aw[pending] = from.w;
        bx[pending] = to.x, by[pending] = to.y, bz[pending] = to.z, bw[pending] = to.w;
        fraction[pending] = s.u;
        bone[pending++] = b;
      } else {
        rotations[b] = value_at(rotation, s);
      }
    }
    for (std::size_t i = 0; i < pending; ++i) {
      const Quat4 q = slerp_components({ax[i], ay[i], az[i], aw[i]}, {bx[i], by[i], bz[i], bw[i]}, fraction[i]);
      ax[i] = q.x, ay[i] = q.y, az[i] = q.z, aw[i] = q.w;
    }
    for (std::size_t i = 0; i < pending; ++i) rotations[bone[i]] = glm::quat(aw[i], ax[i], ay[i], az[i]);
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
