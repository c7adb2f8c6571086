// Secondary motion per step. spring/chain/LINKS/HZ: one frame of a spring chain of LINKS bones following a swinging
// root at HZ frames per second (at 60 Hz a frame is four 1/240 s sub-steps and the leftover; at 240 Hz one), the
// bent pose written back; items are bones, so items_per_second inverts to the time per spring bone per frame.
// elastic/inertial_step: the built-in character's three arm lattices stepped with the bones' motion and rates
// (inertia 1), next to elastic/still_step, the same lattices stepped in their bones' frames.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/parallel.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/spring_chain.hpp"
namespace {

glm::mat4 swing(double t) {
  return glm::rotate(glm::mat4(1.0f), float(0.6 * std::sin(2.0 * 3.14159265 * 0.8 * t)), glm::vec3(0, 0, 1));
}

void spring_chain(benchmark::State& state) {
  const auto links = int(state.range(0));
  const double hz = double(state.range(1));
  std::vector<deform::Bone> bones(std::size_t(links) + 1);
  bones[0] = {"root", -1, {1}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
  for (int i = 1; i <= links; ++i)
    bones[std::size_t(i)] = {"link" + std::to_string(i),
                             i - 1,
                             i < links ? std::vector<std::int32_t>{i + 1} : std::vector<std::int32_t>{},
                             glm::vec3(0.1f, 0.0f, 0.0f),
                             glm::vec3(0.0f),
                             {}};
  const deform::Skeleton skeleton(bones);
  deform::SpringChainSpec chain;
  chain.name = "tail";
  for (int i = 1; i <= links; ++i) chain.bones.push_back(i);
  chain.frequency = 4.0f;
  chain.damping_ratio = 0.4f;
  chain.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  chain.radius = 0.01f;
  chain.colliders = {0};
  deform::SpringChains springs(skeleton, {chain},
                               {{0, glm::vec3(0.3f, -0.25f, 0.0f), glm::vec3(0.6f, -0.25f, 0.0f), 0.1f}});
  std::vector<glm::mat4> world(skeleton.bone_count()), rate(world.size()), palette(world.size());
  int frame = 0;
  for (auto _ : state) {
    const double t = frame++ / hz;
    const glm::mat4 root = swing(t), root_rate = (swing(t + 1e-3) - root) / 1e-3f;
    for (std::size_t b = 0; b < world.size(); ++b) {  // part of what an engine's FK would do anyway
      world[b] = root * skeleton.bind_world()[b];
      rate[b] = root_rate * skeleton.bind_world()[b];
    }
    springs.run(float(1.0 / hz), world, rate, palette);
    benchmark::DoNotOptimize(palette.data());
  }
  state.SetItemsProcessed(state.iterations() * links);
}

void lattices_step(benchmark::State& state) {
  const bool inertial = state.range(0) != 0;
  deform::Character character = deform::make_builtin_character();
  deform::DeformerHierarchy hierarchy = character.deformers();
  if (inertial)
    for (std::size_t l = 0; l < hierarchy.lattice_count(); ++l) hierarchy.set_motion(l, {1.0f, glm::vec3(0.0f), 1.0f});
  const deform::Skeleton& skeleton = character.skeleton();
  std::vector<glm::mat4> world(skeleton.bone_count()), rate(world.size());
  int frame = 0;
  for (auto _ : state) {
    const double t = frame++ / 60.0;
    const glm::mat4 root = swing(t), root_rate = (swing(t + 1e-3) - root) / 1e-3f;
    for (std::size_t b = 0; b < world.size(); ++b) {
      world[b] = root * skeleton.bind_world()[b];
      rate[b] = root_rate * skeleton.bind_world()[b];
    }
    if (inertial) {
      hierarchy.step(1.0f / 60.0f, world, rate);
    } else {
      hierarchy.step(1.0f / 60.0f);
    }
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(hierarchy.lattice_count()));
}

// spring/crowd_1000x32/threads:N (issue #36's target: at most 4 ms a frame on 2 threads): 1,000 characters, each
// with 32 spring bones (four strands of eight, hair or a skirt, hanging from a chest bone) and two capsule colliders
// on the chest, at 60 Hz with the bones' rates, every character swinging at its own phase. The characters are
// split into N contiguous ranges on a ThreadPool, as crowd/builtin_1000 does. Items are characters.
constexpr std::size_t spring_crowd_size = 1000;
constexpr int strands = 4, strand_links = 8;

deform::Skeleton strand_skeleton() {
  std::vector<deform::Bone> bones;
  bones.push_back({"hips", -1, {1}, glm::vec3(0.0f), glm::vec3(0.0f), {}});
  std::vector<std::int32_t> strand_roots;
  for (int s = 0; s < strands; ++s) strand_roots.push_back(2 + s * strand_links);
  bones.push_back({"chest", 0, strand_roots, glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0.0f), {}});
  for (int s = 0; s < strands; ++s) {
    const float angle = 6.2831853f * float(s) / float(strands);
    for (int k = 0; k < strand_links; ++k) {
      const auto id = std::int32_t(2 + s * strand_links + k);
      const glm::vec3 offset =
          k == 0 ? glm::vec3(0.12f * std::cos(angle), 0.1f, 0.12f * std::sin(angle)) : glm::vec3(0.0f, -0.05f, 0.0f);
      bones.push_back({"strand" + std::to_string(s) + "_" + std::to_string(k),
                       k == 0 ? 1 : id - 1,
                       k + 1 < strand_links ? std::vector<std::int32_t>{id + 1} : std::vector<std::int32_t>{},
                       offset,
                       glm::vec3(0.0f),
                       {}});
    }
  }
  return deform::Skeleton(bones);
}

void spring_crowd(benchmark::State& state) {
  const deform::Skeleton skeleton = strand_skeleton();
  std::vector<deform::SpringChainSpec> chains;
  for (int s = 0; s < strands; ++s) {
    deform::SpringChainSpec chain;
    chain.name = "strand" + std::to_string(s);
    for (int k = 0; k < strand_links; ++k) chain.bones.push_back(2 + s * strand_links + k);
    chain.frequency = 3.0f;
    chain.damping_ratio = 0.3f;
    chain.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
    chain.radius = 0.01f;
    chain.colliders = {0, 1};
    chains.push_back(chain);
  }
  const std::vector<deform::SpringCollider> colliders = {
      {1, glm::vec3(-0.08f, -0.1f, 0.0f), glm::vec3(0.08f, -0.1f, 0.0f), 0.1f},
      {1, glm::vec3(0.0f, -0.3f, -0.05f), glm::vec3(0.0f, -0.3f, 0.05f), 0.12f}};
  struct Instance {
    deform::SpringChains springs;
    std::vector<glm::mat4> world, rate, palette;
    double phase;
  };
  std::vector<Instance> crowd;
  crowd.reserve(spring_crowd_size);
  const std::size_t bones = skeleton.bone_count();
  for (std::size_t i = 0; i < spring_crowd_size; ++i) {
    crowd.push_back({deform::SpringChains(skeleton, chains, colliders), std::vector<glm::mat4>(bones),
                     std::vector<glm::mat4>(bones), std::vector<glm::mat4>(bones), 0.37 * double(i)});
  }
  const double hz = 60.0;
  int frame = 0;
  const std::function<void(std::size_t, std::size_t)> range = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Instance& c = crowd[i];
      const double t = frame / hz + c.phase;
      const glm::mat4 root = swing(t), root_rate = (swing(t + 1e-3) - root) / 1e-3f;
      for (std::size_t b = 0; b < bones; ++b) {  // what the character's FK gives
        c.world[b] = root * skeleton.bind_world()[b];
        c.rate[b] = root_rate * skeleton.bind_world()[b];
      }
      c.springs.run(float(1.0 / hz), c.world, c.rate, c.palette);
      benchmark::DoNotOptimize(c.palette.data());
    }
  };
  deform::ThreadPool pool(unsigned(state.range(0)));
  for (int f = 0; f < 60; ++f, ++frame) range(0, spring_crowd_size);  // every instance under way
  for (auto _ : state) {
    pool.parallel_for(spring_crowd_size, 1, range);
    ++frame;
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(spring_crowd_size));
}

// spring/crowd_job_1000x32/threads:N/group:G: the same crowd and motion through SpringCrowdJob (G instances' sub-steps
// together in lanes; group 1 runs each alone), the bone matrices in flat arrays, instance after instance. The same bits
// as spring/crowd_1000x32 computes.
void spring_crowd_job(benchmark::State& state) {
  const deform::Skeleton skeleton = strand_skeleton();
  std::vector<deform::SpringChainSpec> chains;
  for (int s = 0; s < strands; ++s) {
    deform::SpringChainSpec chain;
    chain.name = "strand" + std::to_string(s);
    for (int k = 0; k < strand_links; ++k) chain.bones.push_back(2 + s * strand_links + k);
    chain.frequency = 3.0f;
    chain.damping_ratio = 0.3f;
    chain.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
    chain.radius = 0.01f;
    chain.colliders = {0, 1};
    chains.push_back(chain);
  }
  const std::vector<deform::SpringCollider> colliders = {
      {1, glm::vec3(-0.08f, -0.1f, 0.0f), glm::vec3(0.08f, -0.1f, 0.0f), 0.1f},
      {1, glm::vec3(0.0f, -0.3f, -0.05f), glm::vec3(0.0f, -0.3f, 0.05f), 0.12f}};
  const std::size_t bones = skeleton.bone_count();
  std::vector<deform::SpringChains> springs(spring_crowd_size, deform::SpringChains(skeleton, chains, colliders));
  std::vector<glm::mat4> world(bones * spring_crowd_size), rate(world.size()), palette(world.size());
  const double hz = 60.0;
  int frame = 0;
  deform::SpringCrowdJob job;
  job.instances = springs;
  job.dt = float(1.0 / hz);
  job.world = world;
  job.world_rate = rate;
  job.palette = palette;
  job.group = std::size_t(state.range(1));
  if (!job.validate()) state.SkipWithError(job.validate().reason());
  const std::function<void(std::size_t, std::size_t)> range = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const double t = frame / hz + 0.37 * double(i);
      const glm::mat4 root = swing(t), root_rate = (swing(t + 1e-3) - root) / 1e-3f;
      for (std::size_t b = 0; b < bones; ++b) {  // what the character's FK gives
        world[i * bones + b] = root * skeleton.bind_world()[b];
        rate[i * bones + b] = root_rate * skeleton.bind_world()[b];
      }
    }
    if (!job.run(begin, end)) std::abort();
    benchmark::DoNotOptimize(palette.data());
  };
  deform::ThreadPool pool(unsigned(state.range(0)));
  for (int f = 0; f < 60; ++f, ++frame) range(0, spring_crowd_size);  // every instance under way
  for (auto _ : state) {
    pool.parallel_for(spring_crowd_size, 1, range);
    ++frame;
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(spring_crowd_size));
}

BENCHMARK(spring_chain)->Name("spring/chain")->ArgNames({"links", "hz"})->Args({6, 60})->Args({6, 240})->Args({24, 60});
BENCHMARK(lattices_step)->Name("elastic/builtin_lattices_step")->ArgName("inertial")->Arg(0)->Arg(1);

}  // namespace
BENCHMARK(spring_crowd)
    ->Name("spring/crowd_1000x32")
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(spring_crowd_job)
    ->Name("spring/crowd_job_1000x32")
    ->ArgNames({"threads", "group"})
    ->ArgsProduct({{1, 2}, {1, 4, 8}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
