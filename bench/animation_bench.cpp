// anim/*: the animation runtime on a 75-bone skeleton (mrfixit.iqm's joint count) with generated 2-second clips, a key
// every 1/30 s on every bone's rotation and translation:
//  anim/sample/I: SamplingJob, one clip into one pose (I: 0 step, 1 linear, 2 cubic_spline keys).
//  anim/blend/L: BlendingJob over L sampled poses (2 or 4), no masks; anim/blend_masked/L: the same with the first
//    layer masked to half the bones (the upper body from one clip, the rest from the others).
//  anim/blend_additive/W: one layer and one additive layer of weight W/100 (50: a slerp per bone; 100: the delta).
//  anim/root_motion: RootMotionJob over an interval that wraps one loop, with the in-place pose.
// Inputs are sampled once outside the loop: the blend figures are the blend alone.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "deform/runtime/animation.hpp"
#include "deform/runtime/blending.hpp"
#include "deform/runtime/skeleton.hpp"
namespace {

constexpr std::size_t bones = 75;
constexpr float duration = 2.0f;
constexpr int keys = 61;  // every 1/30 s over 2 s

deform::Animation make_clip(unsigned seed, deform::Interpolation interpolation) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  deform::Animation clip;
  clip.name = "clip" + std::to_string(seed);
  clip.duration = duration;
  const bool cubic = interpolation == deform::Interpolation::cubic_spline;
  for (std::size_t b = 0; b < bones; ++b) {
    deform::Channel c;
    c.bone = static_cast<std::int32_t>(b);
    c.rotation.interpolation = c.translation.interpolation = interpolation;
    for (int k = 0; k < keys; ++k) {
      const float t = duration * float(k) / float(keys - 1);
      c.rotation.times.push_back(t);
      c.translation.times.push_back(t);
      c.rotation.values.push_back(glm::normalize(glm::quat{2.0f + u(random), u(random), u(random), u(random)}));
      c.translation.values.push_back({u(random), u(random), u(random)});
      if (cubic) {
        c.rotation.in_tangents.push_back({u(random), u(random), u(random), u(random)});
        c.rotation.out_tangents.push_back({u(random), u(random), u(random), u(random)});
        c.translation.in_tangents.push_back({u(random), u(random), u(random)});
        c.translation.out_tangents.push_back({u(random), u(random), u(random)});
      }
    }
    clip.channels.push_back(std::move(c));
  }
  clip.require_valid(bones);
  return clip;
}

deform::Pose rest_pose() {
  return {std::vector<glm::quat>(bones, glm::quat(1, 0, 0, 0)), std::vector<glm::vec3>(bones, glm::vec3(0.0f))};
}

deform::Pose sampled(const deform::Animation& clip, float t) {
  deform::Pose pose = rest_pose();
  deform::SamplingJob job;
  job.animation = &clip;
  job.time = t;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.run();
  return pose;
}

void sample(benchmark::State& state) {
  const deform::Animation clip = make_clip(1, static_cast<deform::Interpolation>(state.range(0)));
  deform::Pose pose = rest_pose();
  deform::SamplingJob job;
  job.animation = &clip;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  float t = 0.0f;
  for (auto _ : state) {
    job.time = t;
    t += 1.0f / 60.0f;  // a different segment each call, as a game's frames
    job.run();
    benchmark::DoNotOptimize(pose.rotations.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(bones));
}
BENCHMARK(sample)->Name("anim/sample")->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void blend_layers(benchmark::State& state, int count, bool masked, bool additive, float additive_weight = 0.0f) {
  std::vector<deform::Pose> poses;
  for (int l = 0; l < count + (additive ? 1 : 0); ++l)
    poses.push_back(sampled(make_clip(10 + unsigned(l), deform::Interpolation::linear), 0.37f));
  std::vector<float> mask(bones, 0.0f);
  for (std::size_t b = 0; b < bones / 2; ++b) mask[b] = 1.0f;
  std::vector<deform::BlendLayer> layers, additive_layers;
  for (int l = 0; l < count; ++l)
    layers.push_back({poses[std::size_t(l)].rotations, poses[std::size_t(l)].translations, 1.0f / float(l + 1),
                      masked && l == 0 ? std::span<const float>(mask) : std::span<const float>()});
  if (additive) additive_layers.push_back({poses.back().rotations, poses.back().translations, additive_weight, {}});
  const deform::Pose rest = rest_pose();
  deform::Pose out = rest_pose();
  deform::BlendingJob job;
  job.layers = layers;
  job.additive_layers = additive_layers;
  job.rest_rotations = rest.rotations;
  job.rest_translations = rest.translations;
  job.rotations = out.rotations;
  job.translations = out.translations;
  if (!job.validate()) state.SkipWithError("invalid blend");
  for (auto _ : state) {
    job.run();
    benchmark::DoNotOptimize(out.rotations.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(bones));
}
void blend(benchmark::State& state) { blend_layers(state, int(state.range(0)), false, false); }
void blend_masked(benchmark::State& state) { blend_layers(state, int(state.range(0)), true, false); }
void blend_additive(benchmark::State& state) { blend_layers(state, 1, false, true, float(state.range(0)) / 100.0f); }
BENCHMARK(blend)->Name("anim/blend")->Arg(2)->Arg(4)->Unit(benchmark::kMicrosecond);
BENCHMARK(blend_masked)->Name("anim/blend_masked")->Arg(2)->Arg(4)->Unit(benchmark::kMicrosecond);
BENCHMARK(blend_additive)->Name("anim/blend_additive")->Arg(50)->Arg(100)->Unit(benchmark::kMicrosecond);

void root_motion(benchmark::State& state) {
  const deform::Animation clip = make_clip(3, deform::Interpolation::linear);
  deform::Pose pose = sampled(clip, 2.1f);
  deform::RootMotion motion;
  deform::RootMotionJob job;
  job.animation = &clip;
  job.bone = 0;
  job.from = 1.9f;
  job.to = 2.1f;
  job.motion = &motion;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  for (auto _ : state) {
    job.run();
    benchmark::DoNotOptimize(motion);
  }
}
BENCHMARK(root_motion)->Name("anim/root_motion")->Unit(benchmark::kMicrosecond);

}  // namespace
