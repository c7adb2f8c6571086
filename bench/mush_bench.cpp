// mush/*: Delta Mush per frame (DeltaMushJob, positions only) on the built-in character (2,850 points) and on a
// 100,000-point torus, the points bent a little differently each frame. The target (issue 33) is per point and per
// iteration, so the items of the smoothing benchmarks are points × iterations:
//   mush/smooth/builtin, mush/smooth/100k      one smoothing pass (run_pass of an inner iteration): items = points
//   mush/frames/builtin, mush/frames/100k      the last pass (frames and deltas): items = points
//   mush/run/builtin/10, mush/run/100k/10      the whole job at 10 iterations (Maya's default): items = points × 10
//   mush/run_threads/100k/10                   the same split over all threads, a barrier per pass (run(pool))
//   mush/bind/builtin                          bind_delta_mush at 10 iterations (once per mesh)
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "deform/offline/delta_mush.hpp"
#include "deform/runtime/delta_mush.hpp"
#include "deform/runtime/parallel.hpp"
#include "fixtures.hpp"

namespace {

using bench_fixtures::mesh;

// 16 frames of the points bent a little differently.
std::vector<std::vector<glm::vec3>> frames(const deform::Mesh& m) {
  std::vector<std::vector<glm::vec3>> out;
  for (int f = 0; f < 16; ++f) out.push_back(bench_fixtures::bent_points(m, f));
  return out;
}

struct Setup {
  deform::DeltaMushBinding binding;
  std::vector<std::vector<glm::vec3>> in;
  std::vector<glm::vec3> out;
  std::vector<glm::vec4> scratch;
  deform::DeltaMushJob job(int frame) {
    deform::DeltaMushJob j;
    j.binding = &binding;
    j.in_positions = in[std::size_t(frame % 16)];
    j.out_positions = out;
    j.scratch = scratch;
    return j;
  }
};

Setup setup(bool builtin, int iterations) {
  Setup s;
  const deform::Mesh& m = mesh(builtin);
  s.binding = deform::bind_delta_mush(m, {iterations, 0.5f, {}});
  s.in = frames(m);
  s.out.resize(m.point_count());
  s.scratch.resize(deform::DeltaMushJob::scratch_size(s.binding));
  return s;
}

// One inner smoothing pass (pass 1 reads the scratch and writes it: the steady state of every pass after the first).
void smooth(benchmark::State& state, bool builtin) {
  Setup s = setup(builtin, 3);
  (void)s.job(0).run();
  int frame = 0;
  for (auto _ : state) {
    (void)s.job(frame++).run_pass(1, 0, s.binding.point_count());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(s.binding.point_count()));
}

void frames_pass(benchmark::State& state, bool builtin) {
  Setup s = setup(builtin, 2);
  (void)s.job(0).run();
  int frame = 0;
  for (auto _ : state) {
    (void)s.job(frame++).run_pass(2, 0, s.binding.point_count());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(s.binding.point_count()));
}

void run(benchmark::State& state, bool builtin, bool threads) {
  const int iterations = int(state.range(0));
  Setup s = setup(builtin, iterations);
  deform::ThreadPool pool;
  int frame = 0;
  for (auto _ : state) {
    if (threads) {
      (void)s.job(frame++).run(pool, 4096);
    } else {
      (void)s.job(frame++).run();
    }
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(s.binding.point_count()) * iterations);
}

void bind(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(deform::bind_delta_mush(mesh(true), {}));
}

}  // namespace

BENCHMARK_CAPTURE(smooth, builtin, true)->Name("mush/smooth/builtin");
BENCHMARK_CAPTURE(smooth, 100k, false)->Name("mush/smooth/100k");
BENCHMARK_CAPTURE(frames_pass, builtin, true)->Name("mush/frames/builtin");
BENCHMARK_CAPTURE(frames_pass, 100k, false)->Name("mush/frames/100k");
BENCHMARK_CAPTURE(run, builtin, true, false)->Name("mush/run/builtin")->Arg(10);
BENCHMARK_CAPTURE(run, 100k, false, false)->Name("mush/run/100k")->Arg(10);
BENCHMARK_CAPTURE(run, 100k_threads, false, true)->Name("mush/run_threads/100k")->Arg(10)->UseRealTime();
BENCHMARK(bind)->Name("mush/bind/builtin")->Unit(benchmark::kMillisecond);
