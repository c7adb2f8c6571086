// normals/*: per-frame vertex normals (angle-weighted, mesh.hpp) of the built-in character (2,850 points, 3,068
// render vertices, 5,696 triangles) and of a 100,000-point torus (200,000 triangles, render vertices split along its
// UV seams), with the points warped so that no two frames are alike to the caches' eyes. Items are render vertices.
//   normals/builtin, normals/100k                    VertexNormalsJob::run, the kernel copy the CPU gets (isa_best)
//   normals/builtin_threads, normals/100k_threads    the same split over all threads (run_parallel)
//   normals/builtin_portable, normals/100k_portable  the portable copy forced (what a CPU without AVX2 runs)
//   normals/builtin_avx2, normals/100k_avx2          the AVX2 copy forced
//   normals/builtin_neon, normals/100k_neon          the NEON copy forced (aarch64)
//   normals/builtin_function, normals/100k_function  compute_vertex_normals, one triangle at a time
//   normals/builtin_atan2                            the former code (std::atan2 per corner), for the speed-up
//   normals/bind/builtin, normals/bind/100k          bind_vertex_normals (once per mesh)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "normals_reference.hpp"  // fixtures/: the plain reference normals
#include "fixtures.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/runtime/parallel.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
namespace {

using bench_fixtures::mesh;

void set_counters(benchmark::State& state, const deform::Mesh& m) {
  state.SetItemsProcessed(state.iterations() * std::int64_t(m.vertex_count()));
  state.counters["points"] = double(m.point_count());
  state.counters["triangles"] = double(m.triangle_count());
}

deform::ThreadPool& pool() {
  static deform::ThreadPool all(0);
  return all;
}

void bound(benchmark::State& state, bool builtin, deform::Isa isa, bool threads = false) {
  if (!deform::isa_available(isa)) {
    state.SkipWithError("instruction set not available");
    return;
  }
  const deform::Mesh& m = mesh(builtin);
  const deform::VertexNormalsBinding binding = deform::bind_vertex_normals(m);
  const std::vector<glm::vec3> poses[2] = {bench_fixtures::bent_points(m, 3), bench_fixtures::bent_points(m, 9)};
  std::vector<glm::vec3> out(m.vertex_count());
  std::vector<glm::vec4> scratch(binding.scratch_size());
  deform::VertexNormalsJob job;
  job.binding = &binding;
  job.normals = out;
  job.scratch = scratch;
  job.isa = isa;
  int frame = 0;
  for (auto _ : state) {
    job.positions = poses[frame++ & 1];
    if (threads) deform::run_parallel(job, pool());
    else job.run();
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state, m);
  state.counters["threads"] = threads ? double(pool().size()) : 1.0;
}

void function(benchmark::State& state, bool builtin) {
  const deform::Mesh& m = mesh(builtin);
  const std::vector<glm::vec3> poses[2] = {bench_fixtures::bent_points(m, 3), bench_fixtures::bent_points(m, 9)};
  std::vector<glm::vec3> scratch(m.point_count()), out(m.vertex_count());
  int frame = 0;
  for (auto _ : state) {
    deform::compute_vertex_normals(m, poses[frame++ & 1], scratch, out);
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state, m);
}

// The library's code before VertexNormals: std::atan2 for two corners of every triangle.
void atan2_former(benchmark::State& state) {
  const deform::Mesh& m = mesh(true);
  const std::vector<glm::vec3> poses[2] = {bench_fixtures::bent_points(m, 3), bench_fixtures::bent_points(m, 9)};
  std::vector<glm::vec3> scratch(m.point_count()), out(m.vertex_count());
  int frame = 0;
  for (auto _ : state) {
    normals_reference::atan2_vertex_normals(m, poses[frame++ & 1], scratch, out);
    benchmark::DoNotOptimize(out.data());
  }
  set_counters(state, m);
}

void bind(benchmark::State& state, bool builtin) {
  const deform::Mesh& m = mesh(builtin);
  for (auto _ : state) {
    const deform::VertexNormalsBinding binding = deform::bind_vertex_normals(m);
    benchmark::DoNotOptimize(&binding);
  }
  set_counters(state, m);
}

using deform::Isa;
BENCHMARK_CAPTURE(bound, builtin, true, Isa::automatic)->Name("normals/builtin")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, 100k, false, Isa::automatic)->Name("normals/100k")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, builtin_threads, true, Isa::automatic, true)
    ->Name("normals/builtin_threads")
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, 100k_threads, false, Isa::automatic, true)
    ->Name("normals/100k_threads")
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, builtin_portable, true, Isa::portable)
    ->Name("normals/builtin_portable")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, 100k_portable, false, Isa::portable)
    ->Name("normals/100k_portable")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, builtin_avx2, true, Isa::avx2)->Name("normals/builtin_avx2")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, 100k_avx2, false, Isa::avx2)->Name("normals/100k_avx2")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, builtin_neon, true, Isa::neon)->Name("normals/builtin_neon")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bound, 100k_neon, false, Isa::neon)->Name("normals/100k_neon")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(function, builtin, true)->Name("normals/builtin_function")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(function, 100k, false)->Name("normals/100k_function")->Unit(benchmark::kMicrosecond);
BENCHMARK(atan2_former)->Name("normals/builtin_atan2")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bind, builtin, true)->Name("normals/bind/builtin")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(bind, 100k, false)->Name("normals/bind/100k")->Unit(benchmark::kMicrosecond);

}  // namespace
