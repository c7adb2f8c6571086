// memory/*: this machine's memory speed, the bound for kernels that stream large arrays (docs/performance.md,
// "The bandwidth bound"). memory/add: out[i] = a[i] + b[i] over arrays far larger than the caches — two bytes read
// for each byte written, the proportions of skinning positions and normals (48 bytes read, 24 written per vertex).
// memory/read: a sum over one array (reads only). Bytes per second count what the program reads and writes, as
// skin/lbs's do, so the two compare directly; the write-allocate traffic both incur is in the time, not the count.
#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "widest_vectors.hpp"

namespace {

constexpr std::size_t floats = std::size_t{1} << 25;  // 128 MiB per array

std::vector<float>& array(int which) {
  static std::vector<float> arrays[3] = {std::vector<float>(floats, 1.0f), std::vector<float>(floats, 2.0f),
                                         std::vector<float>(floats, 0.0f)};
  return arrays[which];
}

DEFORM_WIDEST_VECTORS void add_arrays(const float* a, const float* b, float* out, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] = a[i] + b[i];
}

DEFORM_WIDEST_VECTORS std::uint32_t sum_array(const std::uint32_t* a, std::size_t n) {
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += a[i];
  return sum;
}

void memory_add(benchmark::State& state) {
  const float* a = array(0).data();
  const float* b = array(1).data();
  float* out = array(2).data();
  for (auto _ : state) {
    add_arrays(a, b, out, floats);
    benchmark::DoNotOptimize(out);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * 3 * floats * sizeof(float)));
}

void memory_read(benchmark::State& state) {
  // Summed as integers, which the compiler may reorder into vector adds (a float sum it must keep in order).
  const auto* a = reinterpret_cast<const std::uint32_t*>(array(0).data());
  for (auto _ : state) {
    std::uint32_t sum = sum_array(a, floats);
    benchmark::DoNotOptimize(sum);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * floats * sizeof(float)));
}

}  // namespace

BENCHMARK(memory_add)->Name("memory/add")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(memory_read)->Name("memory/read")->Unit(benchmark::kMillisecond)->UseRealTime();
