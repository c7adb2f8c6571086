// IK benchmarks: ik/ccd, ik/fabrik on 2- to 6-joint chains with random DOF limits, ik/two_bone (and ik/two_bone_rig
// with a pole point, swivel, soften, stretch and weight); random reachable
// targets (FK of random in-limit poses), tolerance 1e-4 of the chain length, from the bind pose each solve.
// Items = solves. Counters: mean iterations, reached (fraction), median_us (median time of one solve).
// ik/clamp: one joint's DOF clamp, the solvers' clamp_rotation against Skeleton::clamp_to_limits.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "ik_random_rigs.hpp"  // fixtures/: the random rigs the IK tests use too
#include "deform/runtime/ik.hpp"
#include "deform/runtime/skeleton.hpp"
namespace {

constexpr int rig_count = 32;
constexpr int targets_per_rig = 32;

struct Case {
  ik_rigs::RandomChain rig;
  std::vector<glm::vec3> targets;
  deform::Pose bind;
};

std::vector<Case> make_cases(std::size_t joints, std::uint32_t seed, bool free_joints = false) {
  std::mt19937 random(seed);
  std::vector<Case> cases;
  for (int r = 0; r < rig_count; ++r) {
    Case c{ik_rigs::random_chain(random, joints, free_joints), {}, {}};
    for (int t = 0; t < targets_per_rig; ++t) c.targets.push_back(ik_rigs::random_reachable_target(random, c.rig));
    c.bind = c.rig.skeleton.bind_pose();
    cases.push_back(std::move(c));
  }
  return cases;
}

// Each rig has its chain (made once) and the stall escape's generator state, carried from solve to solve as a
// solver object would; one scratch serves every solve. The timed solve includes its base (chain_base).
void solve_loop(benchmark::State& state, deform::IkMethod method, bool escape_stalls) {
  const auto joints = static_cast<std::size_t>(state.range(0));
  const std::vector<Case> cases = make_cases(joints, 1234);
  std::vector<deform::IkChain> chains;
  for (const Case& c : cases) chains.push_back(deform::make_chain(c.rig.skeleton, c.rig.root, c.rig.effector));
  std::vector<std::uint32_t> random_states(cases.size(), deform::ik_random_seed);
  std::vector<std::byte> scratch(deform::IkJob::scratch_size(joints));
  deform::Pose pose = cases[0].bind;
  std::vector<double> times;
  times.reserve(1 << 22);
  long iterations = 0, reached = 0, solves = 0;
  for (auto _ : state) {
    const auto i = static_cast<std::size_t>(solves % rig_count);
    const auto t = static_cast<std::size_t>((solves / rig_count) % targets_per_rig);
    const Case& c = cases[i];
    pose.rotations.assign(c.bind.rotations.begin(), c.bind.rotations.end());  // capacity kept: no allocation
    pose.translations.assign(c.bind.translations.begin(), c.bind.translations.end());
    deform::IkResult result;
    deform::IkJob job;
    job.method = method;
    job.chain = &chains[i];
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    job.target = c.targets[t];
    job.settings.tolerance = 1e-4f * c.rig.length;
    job.settings.max_iterations = 200;
    job.settings.escape_stalls = escape_stalls;
    job.scratch = scratch;
    job.random_state = &random_states[i];
    job.result = &result;
    const auto start = std::chrono::steady_clock::now();
    deform::chain_base(chains[i], pose.rotations, pose.translations, job.base);
    job.run();
    const auto stop = std::chrono::steady_clock::now();
    if (times.size() < times.capacity())
      times.push_back(std::chrono::duration<double, std::micro>(stop - start).count());
    benchmark::DoNotOptimize(pose.rotations.data());
    iterations += result.iterations;
    reached += result.reached;
    ++solves;
  }
  std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2), times.end());
  state.SetItemsProcessed(solves);
  state.counters["iterations"] = static_cast<double>(iterations) / static_cast<double>(solves);
  state.counters["reached"] = static_cast<double>(reached) / static_cast<double>(solves);
  state.counters["median_us"] = times.empty() ? 0.0 : times[times.size() / 2];
}

void ccd(benchmark::State& state) { solve_loop(state, deform::IkMethod::ccd, true); }
void ccd_plain(benchmark::State& state) { solve_loop(state, deform::IkMethod::ccd, false); }
void fabrik(benchmark::State& state) { solve_loop(state, deform::IkMethod::fabrik, true); }

// state.range(0): 1 = random DOF limits (the closed form, then clamps), 0 = free joints (the closed form alone).
// rig: 1 = a rigger's settings on top (pole point, swivel, soften, stretch, the stretched translations written),
// 2 = those and weight 0.7 (the blend and two more clamps); 0 = a pole direction only.
void two_bone_loop(benchmark::State& state, long rig) {
  const std::vector<Case> cases = make_cases(2, 99, state.range(0) == 0);
  std::vector<deform::IkChain> chains;
  std::vector<deform::Pose> poses;  // one per rig; each solve starts from its bind pose again
  for (const Case& c : cases) {
    chains.push_back(deform::make_chain(c.rig.skeleton, c.rig.root, c.rig.effector));
    poses.push_back(c.bind);
  }
  std::vector<std::vector<glm::vec3>> stretched;
  for (const deform::Pose& pose : poses) stretched.push_back(pose.translations);
  float stretch = 1.0f;
  long solves = 0, reached = 0;
  for (auto _ : state) {
    const auto i = static_cast<std::size_t>(solves % rig_count);
    const auto t = static_cast<std::size_t>((solves / rig_count) % targets_per_rig);
    const Case& c = cases[i];
    deform::Pose& pose = poses[i];
    // The solve writes only the two joints' rotations: put those back (not the whole pose, whose copy would be
    // timed as well: ~15 ns of vector assignment).
    for (const std::int32_t joint : {c.rig.root, c.rig.root + 1}) {
      const auto b = static_cast<std::size_t>(joint);
      pose.rotations[b] = c.bind.rotations[b];
    }
    deform::IkResult result;
    deform::TwoBoneIkJob job;
    job.chain = &chains[i];
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    job.target = c.targets[t];
    job.pole = glm::vec3(0, 0, 1);
    job.tolerance = 1e-4f * c.rig.length;
    job.result = &result;
    if (rig >= 1) {
      job.pole = c.targets[(t + 1) % targets_per_rig];  // a point somewhere near the limb
      job.pole_kind = deform::PoleKind::point;
      job.swivel_degrees = 10.0f;
      job.soften = 0.1f;
      job.max_stretch = 1.5f;
      job.stretched_translations = stretched[i];
      job.stretch = &stretch;
      job.target *= 1.2f;  // some targets beyond the rest reach, to stretch to
    }
    if (rig >= 2) job.weight = 0.7f;
    deform::chain_base(chains[i], pose.rotations, pose.translations, job.base);
    job.run();
    benchmark::DoNotOptimize(pose.rotations.data());
    reached += result.reached;
    ++solves;
  }
  state.SetItemsProcessed(solves);
  state.counters["iterations"] = 1.0;
  state.counters["reached"] = static_cast<double>(reached) / static_cast<double>(solves);
}

void two_bone(benchmark::State& state) { two_bone_loop(state, 0); }
// state.range(0) as two_bone's, state.range(1) the rig settings (two_bone_loop).
void two_bone_rig(benchmark::State& state) { two_bone_loop(state, state.range(1)); }

// One joint clamp on random rotations and the tests' random limits: state.range(0) = 1 the solvers' clamp_rotation,
// 0 the double-precision Skeleton::clamp_to_limits (convert, clamp, convert back). Items = clamps.
void clamp(benchmark::State& state) {
  constexpr std::size_t count = 1024;
  std::mt19937 random(5);
  std::normal_distribution<float> normal;
  std::vector<deform::Bone> bones(count);
  for (std::size_t b = 0; b < count; ++b) {
    bones[b].name = "b" + std::to_string(b);
    bones[b].parent = static_cast<std::int32_t>(b) - 1;
    if (b + 1 < count) bones[b].children = {static_cast<std::int32_t>(b + 1)};
    bones[b].limits = ik_rigs::random_limits(random);
  }
  const deform::Skeleton skeleton(bones);
  std::vector<deform::EulerLimits> limits;
  for (const deform::Bone& bone : skeleton.bones()) limits.push_back(deform::prepare_limits(bone.limits));
  deform::Pose rotations = skeleton.bind_pose(), pose = rotations;
  for (glm::quat& q : rotations.rotations)
    q = glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
  const bool fast = state.range(0) == 1;
  long clamps = 0;
  for (auto _ : state) {
    pose.rotations.assign(rotations.rotations.begin(), rotations.rotations.end());
    for (std::size_t b = 0; b < count; ++b) {
      if (fast) deform::clamp_rotation(limits[b], pose.rotations[b]);
      else skeleton.clamp_to_limits(pose, static_cast<std::int32_t>(b));
    }
    benchmark::DoNotOptimize(pose.rotations.data());
    clamps += count;
  }
  state.SetItemsProcessed(clamps);
}

}  // namespace

BENCHMARK(ccd)->Name("ik/ccd")->DenseRange(2, 6);
BENCHMARK(ccd_plain)->Name("ik/ccd_plain")->DenseRange(2, 6);
BENCHMARK(fabrik)->Name("ik/fabrik")->DenseRange(2, 6);
BENCHMARK(two_bone)->Name("ik/two_bone")->Arg(1)->Arg(0);
BENCHMARK(two_bone_rig)->Name("ik/two_bone_rig")->ArgsProduct({{1, 0}, {1, 2}})->ArgNames({"limits", "rig"});
BENCHMARK(clamp)->Name("ik/clamp")->Arg(1)->Arg(0);
