// skin/lbs and skin/dqs: positions + normals, 4 influences per vertex, a 28-bone palette, at 2,552 (the built-in
// character's size), 100k and 1M vertices; one thread and all threads. Also the forced instruction-set paths and
// a plain glm loop (skin/lbs_reference), so docs/performance.md can show what the SIMD kernels buy; skin/*_stream
// with SkinningJob::stream_outputs. Bytes per second count the 72 bytes a vertex reads and writes, to set against
// memory/add (memory_bench.cpp) and skin/same_bytes: a loop over the same arrays that reads the same 48 bytes and
// writes the same 24 bytes per vertex with almost no arithmetic, the bound a skinning kernel can at best reach.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>
#include <thread>
#include <vector>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "deform/runtime/parallel.hpp"
#include "deform/runtime/skinning.hpp"
#include "widest_vectors.hpp"
namespace {

constexpr int bone_count = 28;

struct SkinData {
  std::vector<glm::vec3> positions, normals, out_positions, out_normals;
  std::vector<glm::u16vec4> bones;
  std::vector<glm::vec4> weights;
  std::vector<glm::mat4> palette;
  std::vector<deform::DualQuat> dual_quats;
  std::vector<glm::mat3> scales;
};

// Deterministic random mesh data: every vertex has four distinct influences with weights summing to one.
const SkinData& data(std::size_t vertices) {
  static std::vector<std::unique_ptr<SkinData>> cache;
  for (const auto& d : cache)
    if (d->positions.size() == vertices) return *d;
  auto d = std::make_unique<SkinData>();
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), positive(0.1f, 1.0f);
  for (std::size_t i = 0; i < vertices; ++i) {
    d->positions.push_back({u(rng), u(rng), u(rng)});
    d->normals.push_back(glm::normalize(glm::vec3{u(rng), u(rng), u(rng)} + glm::vec3(0.0f, 0.0f, 2.0f)));
    const auto first = static_cast<std::uint16_t>(rng() % bone_count);
    d->bones.emplace_back(first, (first + 1) % bone_count, (first + 5) % bone_count, (first + 11) % bone_count);
    glm::vec4 w{positive(rng), positive(rng), positive(rng), positive(rng)};
    d->weights.push_back(w / (w.x + w.y + w.z + w.w));
  }
  d->out_positions.resize(vertices);
  d->out_normals.resize(vertices);
  for (int b = 0; b < bone_count; ++b) {
    const float turn = u(rng) * 3.0f;
    glm::mat4 m = glm::rotate(glm::mat4(1.0f), turn, glm::normalize(glm::vec3{u(rng), u(rng), 1.0f}));
    m[3] = glm::vec4{u(rng), u(rng), u(rng), 1.0f};
    d->palette.push_back(m);
  }
  d->dual_quats.resize(bone_count);
  d->scales.resize(bone_count);
  bool has_scale = false;
  deform::compute_dual_quat_palette(d->palette, d->dual_quats, d->scales, has_scale);
  cache.push_back(std::move(d));
  return *cache.back();
}

deform::ThreadPool& pool() {
  static deform::ThreadPool p;
  return p;
}

// state.range(0) = vertices, state.range(1) = threads (0: all).
// stream: SkinningJob::stream_outputs (non-temporal stores).
void run_skin(benchmark::State& state, deform::SkinningMethod method, deform::Isa isa, bool stream = false) {
  const auto vertices = static_cast<std::size_t>(state.range(0));
  SkinData& d = const_cast<SkinData&>(data(vertices));
  deform::SkinningJob job;
  job.method = method;
  job.isa = isa;
  job.stream_outputs = stream;
  job.matrices = d.palette;
  job.dual_quats = d.dual_quats;
  job.bone_indices = d.bones;
  job.bone_weights = d.weights;
  job.in_positions = deform::as_floats(d.positions);
  job.in_normals = deform::as_floats(d.normals);
  job.out_positions = deform::as_floats(d.out_positions);
  job.out_normals = deform::as_floats(d.out_normals);
  if (!job.validate()) {
    state.SkipWithError("invalid job (instruction set not available?)");
    return;
  }
  const bool all_threads = state.range(1) == 0;
  for (auto _ : state) {
    if (all_threads) deform::run_parallel(job, pool(), 4096);
    else job.run();
    benchmark::DoNotOptimize(d.out_positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
  // What a vertex moves: position, normal, 4 bone ids and 4 weights read (48 bytes), position and normal written
  // (24): the bytes memory/add's bandwidth is counted in (the bound, docs/performance.md).
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0) * 72);
  state.counters["threads"] = all_threads ? pool().size() : 1;
}

// The plain loop a first implementation would write: blend the four mat4 with glm, transform, inverse-transpose.
void skin_lbs_reference(benchmark::State& state) {
  const auto vertices = static_cast<std::size_t>(state.range(0));
  SkinData& d = const_cast<SkinData&>(data(vertices));
  for (auto _ : state) {
    for (std::size_t i = 0; i < vertices; ++i) {
      glm::mat4 m(0.0f);
      for (int k = 0; k < 4; ++k) m += d.weights[i][k] * d.palette[d.bones[i][k]];
      d.out_positions[i] = glm::vec3(m * glm::vec4(d.positions[i], 1.0f));
      d.out_normals[i] = glm::normalize(glm::inverseTranspose(glm::mat3(m)) * d.normals[i]);
    }
    benchmark::DoNotOptimize(d.out_positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}

// Every byte skinning reads (position, normal, four bone ids, four weights) and writes (position, normal), with
// one multiply per output component: a scale from the weights and ids, so that nothing read can be left out.
DEFORM_WIDEST_VECTORS void stream_skin_bytes(const float* positions, const float* normals, const std::uint16_t* bones,
                                             const float* weights, float* out_positions, float* out_normals,
                                             std::size_t vertices) {
  for (std::size_t i = 0; i < vertices; ++i) {
    const std::uint16_t* b = bones + 4 * i;
    const float* w = weights + 4 * i;
    const float scale = (w[0] + w[1]) + (w[2] + w[3]) + float((b[0] ^ b[1]) ^ (b[2] ^ b[3]));
    for (int k = 0; k < 3; ++k) {
      out_positions[3 * i + k] = positions[3 * i + k] * scale;
      out_normals[3 * i + k] = normals[3 * i + k] * scale;
    }
  }
}

void skin_same_bytes(benchmark::State& state) {
  const auto vertices = static_cast<std::size_t>(state.range(0));
  SkinData& d = const_cast<SkinData&>(data(vertices));
  for (auto _ : state) {
    stream_skin_bytes(&d.positions[0].x, &d.normals[0].x, &d.bones[0].x, &d.weights[0].x, &d.out_positions[0].x,
                      &d.out_normals[0].x, vertices);
    benchmark::DoNotOptimize(d.out_positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0) * 72);
}

void sizes_and_threads(benchmark::internal::Benchmark* b) {
  b->ArgNames({"vertices", "threads"})->ArgsProduct({{2552, 100'000, 1'000'000}, {1, 0}});
}
void sizes_one_thread(benchmark::internal::Benchmark* b) {
  b->ArgNames({"vertices", "threads"})->ArgsProduct({{2552, 100'000, 1'000'000}, {1}});
}

using deform::Isa;
using deform::SkinningMethod;
BENCHMARK_CAPTURE(run_skin, lbs, SkinningMethod::lbs, Isa::automatic)->Name("skin/lbs")->Apply(sizes_and_threads);
BENCHMARK_CAPTURE(run_skin, dqs, SkinningMethod::dqs, Isa::automatic)->Name("skin/dqs")->Apply(sizes_and_threads);
BENCHMARK_CAPTURE(run_skin, lbs_stream, SkinningMethod::lbs, Isa::automatic, true)
    ->Name("skin/lbs_stream")
    ->Apply(sizes_and_threads);
BENCHMARK_CAPTURE(run_skin, dqs_stream, SkinningMethod::dqs, Isa::automatic, true)
    ->Name("skin/dqs_stream")
    ->Apply(sizes_and_threads);
BENCHMARK_CAPTURE(run_skin, lbs_avx2, SkinningMethod::lbs, Isa::avx2)->Name("skin/lbs_avx2")->Apply(sizes_one_thread);
BENCHMARK_CAPTURE(run_skin, dqs_avx2, SkinningMethod::dqs, Isa::avx2)->Name("skin/dqs_avx2")->Apply(sizes_one_thread);
BENCHMARK_CAPTURE(run_skin, lbs_neon, SkinningMethod::lbs, Isa::neon)->Name("skin/lbs_neon")->Apply(sizes_one_thread);
BENCHMARK_CAPTURE(run_skin, dqs_neon, SkinningMethod::dqs, Isa::neon)->Name("skin/dqs_neon")->Apply(sizes_one_thread);
BENCHMARK_CAPTURE(run_skin, lbs_portable, SkinningMethod::lbs, Isa::portable)
    ->Name("skin/lbs_portable")
    ->Apply(sizes_one_thread);
BENCHMARK_CAPTURE(run_skin, dqs_portable, SkinningMethod::dqs, Isa::portable)
    ->Name("skin/dqs_portable")
    ->Apply(sizes_one_thread);
BENCHMARK(skin_lbs_reference)->Name("skin/lbs_reference")->Apply(sizes_one_thread);
BENCHMARK(skin_same_bytes)->Name("skin/same_bytes")->Apply(sizes_one_thread);

}  // namespace
