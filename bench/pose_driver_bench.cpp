// pose_driver/*: the pose-space correctives' driver per frame (runtime/pose_driver.hpp), one thread. The target
// (issue 33): at most 1 µs for 8 sample poses on 4 bones.
//   pose_driver/bones:4/poses/8      8 samples of the built-in character's arms, 8 shapes, the gaussian kernel
//   pose_driver/bones:4/poses/32     32 samples, 32 shapes: how it grows (samples × (bones + shapes))
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/offline/pose_driver.hpp"
#include "deform/runtime/pose_driver.hpp"

namespace {

void pose_driver(benchmark::State& state) {
  const std::size_t poses = std::size_t(state.range(0));
  const deform::Model model = deform::builtin_character();
  const deform::Skeleton& skeleton = model.skeleton;
  std::vector<std::int32_t> bones;
  for (const char* name : {"upperarm_l", "forearm_l", "upperarm_r", "forearm_r"}) bones.push_back(skeleton.find(name));
  std::mt19937 rng(33);
  std::uniform_real_distribution<float> angle(-90.0f, 90.0f);
  std::vector<deform::Pose> samples;
  std::vector<float> targets;
  for (std::size_t k = 0; k < poses; ++k) {
    deform::Pose pose = skeleton.bind_pose();
    for (const std::int32_t b : bones)
      pose.rotations[std::size_t(b)] = deform::quat_from_euler({angle(rng), angle(rng), angle(rng)});
    samples.push_back(pose);
    for (std::size_t s = 0; s < poses; ++s) targets.push_back(s == k ? 1.0f : 0.0f);
  }
  const deform::PoseDriverBinding binding = deform::bind_pose_driver(skeleton, bones, samples, targets, poses);
  // Frames: poses between the samples, one after another.
  std::vector<deform::Pose> frames;
  for (int f = 0; f < 64; ++f) {
    deform::Pose pose = skeleton.bind_pose();
    for (const std::int32_t b : bones)
      pose.rotations[std::size_t(b)] = deform::quat_from_euler({angle(rng), angle(rng), angle(rng)});
    frames.push_back(pose);
  }
  std::vector<float> weights(poses);
  deform::PoseDriverJob job;
  job.binding = &binding;
  job.weights = weights;
  std::size_t f = 0;
  for (auto _ : state) {
    job.rotations = frames[f++ & 63].rotations;
    benchmark::DoNotOptimize(job.run());
    benchmark::DoNotOptimize(weights.data());
  }
}

}  // namespace

BENCHMARK(pose_driver)->Name("pose_driver/bones:4/poses")->Arg(8)->Arg(32)->Unit(benchmark::kNanosecond);
