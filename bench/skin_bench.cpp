// skin/lbs and skin/dqs: positions + normals, 4 influences per vertex, a 28-bone palette, at 2,552 (the built-in
// character's size), 100k and 1M vertices; one thread and all threads. Also the forced instruction-set paths and
// a plain glm loop (skin/lbs_reference), so docs/performance.md can show what the SIMD kernels buy; skin/*_stream
// with SkinningJob::stream_outputs. Bytes per second count the 72 bytes a vertex reads and writes, to set against
// memory/add (memory_bench.cpp) and skin/same_bytes: a loop over the same arrays that reads the same 48 bytes and
// writes the same 24 bytes per vertex with almost no arithmetic, the bound a skinning kernel can at best reach.
#include <benchmark/benchmark.h>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

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

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// skin/avx512_pipes/N: how fast this CPU runs the two operations the AVX-512 skinning block is made of: vpermt2ps (the
// palette lookups and the packed vec3 shuffles) and vfmadd (the blend and the transforms). 16 independent chains, so
// that the rate is the pipes' and not a latency: N = 0 permutes alone, 1 FMAs alone, 2 permutes and FMAs alternating,
// 3 FMAs and adds alternating. items_per_second counts operations. Where permutes and FMAs share their pipes, mixing
// them (2) runs no faster than either alone; where they do not, as FMAs and adds (3), the mix runs at the sum of the
// rates (docs/performance.md, "the block's bound").
// Sixteen independent chains (zmm16 to zmm31), written as instructions so that the compiler can neither fold nor
// spill them: `even` on zmm16, 18, ..., `odd` on zmm17, 19, ...
#define DEFORM_PIPES_PAIR(even, odd, r) even ",%%zmm" #r "\n\t" odd ",%%zmm" DEFORM_PIPES_NEXT_##r "\n\t"
#define DEFORM_PIPES_NEXT_16 "17"
#define DEFORM_PIPES_NEXT_18 "19"
#define DEFORM_PIPES_NEXT_20 "21"
#define DEFORM_PIPES_NEXT_22 "23"
#define DEFORM_PIPES_NEXT_24 "25"
#define DEFORM_PIPES_NEXT_26 "27"
#define DEFORM_PIPES_NEXT_28 "29"
#define DEFORM_PIPES_NEXT_30 "31"
#define DEFORM_PIPES_ROUND(even, odd)                                                                                 \
  asm volatile(DEFORM_PIPES_PAIR(even, odd, 16) DEFORM_PIPES_PAIR(even, odd, 18) DEFORM_PIPES_PAIR(even, odd, 20)     \
                   DEFORM_PIPES_PAIR(even, odd, 22) DEFORM_PIPES_PAIR(even, odd, 24) DEFORM_PIPES_PAIR(even, odd, 26) \
                       DEFORM_PIPES_PAIR(even, odd, 28) DEFORM_PIPES_PAIR(even, odd, 30)                              \
               :                                                                                                      \
               : "v"(table), "v"(index)                                                                               \
               : "xmm16", "xmm17", "xmm18", "xmm19", "xmm20", "xmm21", "xmm22", "xmm23", "xmm24", "xmm25", "xmm26",   \
                 "xmm27", "xmm28", "xmm29", "xmm30", "xmm31")

template <int mix>
__attribute__((target("avx512f"))) void avx512_ops(std::int64_t rounds) {
  const __m512 table = _mm512_set1_ps(1.0f);
  const __m512i index = _mm512_setr_epi32(3, 17, 5, 30, 1, 8, 22, 14, 0, 31, 9, 12, 27, 6, 19, 2);
#define DEFORM_PERMUTE "vpermt2ps %0,%1"
#define DEFORM_FMA "vfmadd231ps %0,%0"
#define DEFORM_ADD "vaddps %0,%0"
  for (std::int64_t r = 0; r < rounds; ++r) {
    if constexpr (mix == 0) DEFORM_PIPES_ROUND(DEFORM_PERMUTE, DEFORM_PERMUTE);
    if constexpr (mix == 1) DEFORM_PIPES_ROUND(DEFORM_FMA, DEFORM_FMA);
    if constexpr (mix == 2) DEFORM_PIPES_ROUND(DEFORM_PERMUTE, DEFORM_FMA);
    if constexpr (mix == 3) DEFORM_PIPES_ROUND(DEFORM_ADD, DEFORM_FMA);
  }
#undef DEFORM_PERMUTE
#undef DEFORM_FMA
#undef DEFORM_ADD
}

template <int mix>
void avx512_pipes(benchmark::State& state) {
  if (!__builtin_cpu_supports("avx512f")) {
    state.SkipWithError("no AVX-512 on this CPU");
    return;
  }
  std::int64_t rounds = 1 << 16;
  benchmark::DoNotOptimize(rounds);
  for (auto _ : state) avx512_ops<mix>(rounds);
  state.SetItemsProcessed(state.iterations() * rounds * 16);
}
BENCHMARK(avx512_pipes<0>)->Name("skin/avx512_pipes/0");
BENCHMARK(avx512_pipes<1>)->Name("skin/avx512_pipes/1");
BENCHMARK(avx512_pipes<2>)->Name("skin/avx512_pipes/2");
BENCHMARK(avx512_pipes<3>)->Name("skin/avx512_pipes/3");
#endif

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
