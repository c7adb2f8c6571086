// Free-form deformation: per-frame evaluation of bound lattices (docs/performance.md).
//   ffd/bezier333/VERTICES/THREADS/NORMALS   tricubic Bézier, THREADS 1 or 0 (= all), NORMALS 0 or 1
//   ffd/bspline/VERTICES/THREADS/NORMALS     uniform cubic B-spline, 10×10×10 control points (7³ cells)
//   ffd/bspline_random_order/...             the same with the vertices in random order (cache misses)
//   ffd/bezier333_portable, ffd/bspline_portable, ffd/*_avx2, ffd/*_neon   a kernel copy forced (isa.hpp), 100k,
//                                            one thread
//   ffd/bezier_degree/DEGREE                 degree sweep (d, d, d), 100k vertices, one thread, positions only
//   ffd/reference333/VERTICES                the equations as written (pow, binomials), one thread
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
#include "deform/runtime/parallel.hpp"
namespace {

using deform::LatticeFrame;

// A rotated box with its vertices spread uniformly inside, in a spatially coherent order as a mesh's vertices are
// (sorted by a 32³ grid, slice by slice), and the control points moved off rest. Random order costs the B-spline
// path cache misses (it groups vertices by cell, so it reads and writes them out of order): `random_order` shows it.
struct Scene {
  LatticeFrame frame;
  std::vector<glm::vec3> positions, normals;
  explicit Scene(std::size_t vertices, bool random_order = false) {
    frame.origin = {-1.0f, 0.5f, 2.0f};
    frame.u_axis = {2.0f, 0.3f, 0.0f};
    frame.v_axis = {-0.2f, 1.5f, 0.1f};
    frame.w_axis = {0.0f, 0.2f, 1.0f};
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (std::size_t i = 0; i < vertices; ++i) {
      positions.push_back(frame.to_world({unit(rng), unit(rng), unit(rng)}));
      normals.push_back(glm::normalize(glm::vec3{unit(rng) - 0.5f, unit(rng) - 0.5f, 1.0f}));
    }
    if (random_order) return;
    auto key = [&](const glm::vec3& p) {
      const glm::ivec3 c = glm::clamp(glm::ivec3(frame.to_lattice(p) * 32.0f), glm::ivec3(0), glm::ivec3(31));
      return c.x + 32 * (c.y + 32 * c.z);
    };
    std::sort(positions.begin(), positions.end(),
              [&](const glm::vec3& a, const glm::vec3& b) { return key(a) < key(b); });
  }
};

void jitter(std::span<glm::vec3> points) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> d(-0.2f, 0.2f);
  for (glm::vec3& p : points) p += glm::vec3{d(rng), d(rng), d(rng)};
}

deform::ThreadPool& pool() {
  static deform::ThreadPool all(0);
  return all;
}

template <class Lattice>
void run_lattice(benchmark::State& state, Lattice& lattice, const Scene& scene,
                 deform::Isa isa = deform::Isa::automatic) {
  if (!deform::isa_available(isa)) {
    state.SkipWithError("instruction set not available");
    return;
  }
  const auto binding = deform::bind_lattice(lattice, scene.positions);
  jitter(lattice.control_points());
  std::vector<glm::vec3> positions = scene.positions, normals = scene.normals;
  deform::LatticeEvaluateJob job;
  job.binding = &binding;
  job.control_points = lattice.control_points();
  job.positions = positions;
  job.isa = isa;
  if (state.range(2)) {
    job.normals_in = scene.normals;
    job.normals_out = normals;
  }
  const bool threaded = state.range(1) == 0;
  for (auto _ : state) {
    if (threaded) deform::run_parallel(job, pool());
    else job.run();
    benchmark::DoNotOptimize(positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(binding.vertex_count));
  state.counters["threads"] = threaded ? static_cast<double>(pool().size()) : 1.0;
}

void bezier333(benchmark::State& state, deform::Isa isa) {
  const Scene scene(static_cast<std::size_t>(state.range(0)));
  deform::BezierLattice lattice(scene.frame);
  run_lattice(state, lattice, scene, isa);
}

void bspline(benchmark::State& state, deform::Isa isa) {
  const Scene scene(static_cast<std::size_t>(state.range(0)));
  deform::BsplineLattice lattice(scene.frame, glm::ivec3(10));
  run_lattice(state, lattice, scene, isa);
}

void bspline_random_order(benchmark::State& state) {
  const Scene scene(static_cast<std::size_t>(state.range(0)), true);
  deform::BsplineLattice lattice(scene.frame, glm::ivec3(10));
  run_lattice(state, lattice, scene);
}

void bezier_degree(benchmark::State& state) {
  const Scene scene(100000);
  deform::BezierLattice lattice(scene.frame, glm::ivec3(static_cast<int>(state.range(0))));
  state.SetLabel("degree " + std::to_string(state.range(0)));
  const auto binding = deform::bind_lattice(lattice, scene.positions);
  jitter(lattice.control_points());
  std::vector<glm::vec3> positions = scene.positions;
  deform::LatticeEvaluateJob job;
  job.binding = &binding;
  job.control_points = lattice.control_points();
  job.positions = positions;
  for (auto _ : state) {
    job.run();
    benchmark::DoNotOptimize(positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) *
                          static_cast<std::int64_t>(binding.vertex_count));
}

// The thesis' equation 35 as written, per vertex: (u, v, w) stored, Bernstein weights from pow and binomials.
void reference333(benchmark::State& state) {
  const Scene scene(static_cast<std::size_t>(state.range(0)));
  deform::BezierLattice lattice(scene.frame);
  jitter(lattice.control_points());
  std::vector<glm::vec3> uvw;
  for (const glm::vec3& p : scene.positions) uvw.push_back(scene.frame.to_lattice(p));
  std::vector<glm::vec3> positions = scene.positions;
  const auto points = lattice.control_points();
  auto binomial = [](int n, int k) {
    float r = 1.0f;
    for (int i = 1; i <= k; ++i) r = r * static_cast<float>(n - k + i) / static_cast<float>(i);
    return r;
  };
  auto bernstein = [&](int i, float t) {
    return binomial(3, i) * std::pow(t, static_cast<float>(i)) * std::pow(1.0f - t, static_cast<float>(3 - i));
  };
  for (auto _ : state) {
    for (std::size_t v = 0; v < uvw.size(); ++v) {
      glm::vec3 q(0.0f);
      for (int i = 0; i <= 3; ++i)
        for (int j = 0; j <= 3; ++j)
          for (int k = 0; k <= 3; ++k)
            q += points[lattice.index(i, j, k)] * bernstein(i, uvw[v].x) * bernstein(j, uvw[v].y) *
                 bernstein(k, uvw[v].z);
      positions[v] = q;
    }
    benchmark::DoNotOptimize(positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(uvw.size()));
}

void sizes(benchmark::internal::Benchmark* b) {
  for (const std::int64_t normals : {0, 1})
    for (const std::int64_t threads : {1, 0})
      for (const std::int64_t vertices : {1500, 100000, 1000000}) b->Args({vertices, threads, normals});
  b->ArgNames({"vertices", "threads", "normals"})->UseRealTime()->Unit(benchmark::kMicrosecond);
}

void one_thread(benchmark::internal::Benchmark* b) {
  b->Args({100000, 1, 0})->Args({100000, 1, 1});
  b->ArgNames({"vertices", "threads", "normals"})->UseRealTime()->Unit(benchmark::kMicrosecond);
}

using deform::Isa;
BENCHMARK_CAPTURE(bezier333, automatic, Isa::automatic)->Name("ffd/bezier333")->Apply(sizes);
BENCHMARK_CAPTURE(bspline, automatic, Isa::automatic)->Name("ffd/bspline")->Apply(sizes);
BENCHMARK_CAPTURE(bezier333, portable, Isa::portable)->Name("ffd/bezier333_portable")->Apply(one_thread);
BENCHMARK_CAPTURE(bspline, portable, Isa::portable)->Name("ffd/bspline_portable")->Apply(one_thread);
BENCHMARK_CAPTURE(bezier333, avx2, Isa::avx2)->Name("ffd/bezier333_avx2")->Apply(one_thread);
BENCHMARK_CAPTURE(bspline, avx2, Isa::avx2)->Name("ffd/bspline_avx2")->Apply(one_thread);
BENCHMARK_CAPTURE(bezier333, neon, Isa::neon)->Name("ffd/bezier333_neon")->Apply(one_thread);
BENCHMARK_CAPTURE(bspline, neon, Isa::neon)->Name("ffd/bspline_neon")->Apply(one_thread);
BENCHMARK(bspline_random_order)
    ->Name("ffd/bspline_random_order")
    ->Args({1000000, 1, 0})
    ->Args({1000000, 1, 1})
    ->ArgNames({"vertices", "threads", "normals"})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(bezier_degree)->Name("ffd/bezier_degree")->DenseRange(1, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(reference333)->Name("ffd/reference333")->Arg(1500)->Arg(100000)->Unit(benchmark::kMicrosecond);

}  // namespace
