// crowd/builtin_1000/threads:N — one frame of a crowd: 1,000 instances of the built-in character (Character::instance,
// sharing the bind data), each walking at its own clip time and with its own springs (the left arm's three lattices
// stretched by a different amount per instance and let go and stretched again at different frames), each updated
// as frame/builtin_whole is: walk sampled, set_pose, update, normals() (transported). Before each update the loop
// asks for the next instances' state (Character::prefetch on the next, prefetch_record on the one after), as an
// engine's crowd loop would (docs/performance.md has the effect). The instances are split into N contiguous ranges,
// one per thread, as an engine's job system would (here a ThreadPool; the library runs no threads of its own).
// Counters: bytes_first — heap bytes held by the first character (make_builtin_character);
// bytes_per_instance — held by each further instance (glibc's mallinfo2, live bytes after construction).
#include <benchmark/benchmark.h>

#include <cstddef>
#include <vector>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/parallel.hpp"
namespace {

constexpr std::size_t crowd_size = 1000;
constexpr float dt = 1.0f / 60.0f;

double heap_bytes() {
#if defined(__GLIBC__)
  return double(mallinfo2().uordblks);
#else
  return 0.0;
#endif
}

struct Crowd {
  std::vector<deform::Character> characters;
  std::vector<deform::Pose> poses;
  std::vector<float> times;
  std::vector<float> stretches;  // each instance's arm stretch (model units) when held
  deform::Animation walk;
  double bytes_first = 0.0;
  double bytes_per_instance = 0.0;
  int frame = 0;

  Crowd() {
    const double before = heap_bytes();
    deform::Character first = deform::make_builtin_character();
    bytes_first = heap_bytes() - before;
    walk = deform::builtin_walk(first.model());
    characters.reserve(crowd_size);
    const double instances_before = heap_bytes();
    for (std::size_t i = 1; i < crowd_size; ++i) characters.push_back(first.instance());
    bytes_per_instance = (heap_bytes() - instances_before) / double(crowd_size - 1);
    characters.push_back(std::move(first));
    poses.assign(crowd_size, characters.front().skeleton().bind_pose());
    for (std::size_t i = 0; i < crowd_size; ++i) {
      times.push_back(0.618034f * float(i));  // spread over the clip
      stretches.push_back(0.05f + 0.25f * float(i % 7) / 6.0f);
    }
  }

  // Instances [begin, end): their targets, then their frame. Touches nothing outside the range.
  void update(std::size_t begin, std::size_t end) {
    deform::SamplingJob sampling;
    sampling.animation = &walk;
    for (std::size_t i = begin; i < end; ++i) {
      deform::Character& c = characters[i];
      // Stretched for 2 s, let go for 2 s, each instance at its own phase.
      const int phase = (frame + int(i * 37)) % 240;
      if (phase == 0 || phase == 120) {
        for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l) {
          c.deformers().set_stretch_target(l, phase == 0 ? stretches[i] * c.deformers().length(l) : 0.0f);
        }
      }
      times[i] += dt;
      sampling.time = times[i];
      sampling.rotations = poses[i].rotations;
      sampling.translations = poses[i].translations;
      sampling.run();
      // The next characters' state on its way while this one computes: the record two ahead, the arrays one ahead.
      if (i + 2 < end) characters[i + 2].prefetch_record();
      if (i + 1 < end) characters[i + 1].prefetch();
      c.set_pose(poses[i]);
      c.update(dt);
      benchmark::DoNotOptimize(c.normals().data());
    }
  }
};

void crowd(benchmark::State& state) {
  Crowd crowd;
  // Every instance's springs under way: two seconds of frames, in which each instance is stretched or let go.
  for (int f = 0; f < 120; ++f, ++crowd.frame) crowd.update(0, crowd_size);
  deform::ThreadPool pool(unsigned(state.range(0)));
  const std::function<void(std::size_t, std::size_t)> range = [&](std::size_t begin, std::size_t end) {
    crowd.update(begin, end);
  };
  for (auto _ : state) {
    pool.parallel_for(crowd_size, 1, range);
    ++crowd.frame;
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(crowd_size));
  state.counters["bytes_first"] = crowd.bytes_first;
  state.counters["bytes_per_instance"] = crowd.bytes_per_instance;
}

BENCHMARK(crowd)
    ->Name("crowd/builtin_1000")
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
