// decompose/*: the skinning decomposition of `deform bake --as bones` (offline/skinning_decomposition.hpp) on the
// built-in character running with the tuned jiggle of a lattice on every limb bone (builtin_full_rig, each at its
// part's tuned inertia), 30 frames a second,
// 24 extra bones, four influences, every thread. The target (issue 35): at most 60 s for 10 s of animation on two
// cores, growing linearly with the frames.
//   decompose/builtin_run/F      F frames (75, 150, 300: 2.5, 5 and 10 s); the recording is outside the timing
#include <benchmark/benchmark.h>

#include <map>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/skinning_decomposition.hpp"
#include "deform/runtime/animation.hpp"

namespace {

struct Recording {
  deform::Model model;
  deform::DecompositionFrames frames;
  std::vector<glm::vec3> seeds;
};

// The run clip played for `count` frames at 30 Hz (two simulation steps a frame), each frame recorded as the CLI's
// bake records it: the bones' model-space matrices after the springs, and the deformed points.
const Recording& recording(std::size_t count) {
  static std::map<std::size_t, Recording> cache;
  if (const auto it = cache.find(count); it != cache.end()) return it->second;
  Recording& r = cache[count];
  r.model = deform::builtin_character();
  deform::Rig rig = deform::builtin_full_rig(r.model);
  for (deform::LatticeSpec& spec : rig.lattices) spec.motion.inertia = deform::scaled_inertia(spec.motion.part, 1.0f);
  deform::Character c(r.model, rig);
  const std::vector<deform::Animation> clips = deform::builtin_clips(r.model);
  const deform::Animation& run = clips[std::size_t(deform::find_clip(clips, "run"))];
  deform::Pose pose = c.skeleton().bind_pose();
  deform::SamplingJob sampling;
  sampling.animation = &run;
  sampling.rotations = pose.rotations;
  sampling.translations = pose.translations;
  for (std::size_t k = 0; k < count; ++k) {
    for (int step = 0; step < 2; ++step) {
      sampling.time = (float(k) + 0.5f * float(step + 1)) / 30.0f;
      (void)sampling.run();
      (void)c.set_pose(pose);
      (void)c.update(1.0f / 60.0f);
    }
    std::vector<glm::mat4>& world = r.frames.bone_world.emplace_back(c.palette().size());
    for (std::size_t b = 0; b < world.size(); ++b) world[b] = c.palette()[b] * c.skeleton().bind_world()[b];
    r.frames.times.push_back(float(k) / 30.0f);
    r.frames.positions.emplace_back(c.positions().begin(), c.positions().end());
  }
  r.seeds = deform::decomposition_seeds(c.deformers(), c.skeleton());
  return r;
}

void decompose_builtin_run(benchmark::State& state) {
  const Recording& r = recording(std::size_t(state.range(0)));
  deform::DecompositionOptions options;
  options.seeds = r.seeds;
  float rms = 0.0f, largest = 0.0f;
  for (auto _ : state) {
    const deform::SkinningDecomposition fit = deform::decompose_skinning(r.model, r.frames, options);
    rms = fit.rms_error;
    largest = fit.max_error;
    benchmark::DoNotOptimize(fit.weights.bones.data());
  }
  state.counters["rms_error_pct"] = 100.0 * rms;
  state.counters["max_error_pct"] = 100.0 * largest;
  state.SetComplexityN(state.range(0));
}

}  // namespace

BENCHMARK(decompose_builtin_run)
    ->Name("decompose/builtin_run")
    ->Arg(75)
    ->Arg(150)
    ->Arg(300)
    ->Complexity(benchmark::oN)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);
