// Picking benchmarks: pick/ray — one ray against a 100k-triangle BVH; pick/refit — refit for deformed positions;
// pick/build. Items = rays, or triangles for refit and build.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "deform/offline/picking.hpp"
namespace {

// A closed, bumpy sphere of about `triangles` triangles (a UV sphere), radius about 1.
void sphere(int triangles, std::vector<glm::vec3>& positions, std::vector<std::uint32_t>& indices) {
  const int rings = static_cast<int>(std::sqrt(triangles / 2.0)), segments = rings;
  positions.clear();
  indices.clear();
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const float theta = 3.14159265f * float(r) / float(rings), phi = 6.2831853f * float(s) / float(segments);
      const float radius = 1.0f + 0.05f * std::sin(7.0f * phi) * std::sin(5.0f * theta);
      positions.emplace_back(radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta),
                             radius * std::sin(theta) * std::sin(phi));
    }
  const auto at = [segments](int r, int s) { return static_cast<std::uint32_t>(r * segments + (s % segments)); };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s)
      indices.insert(indices.end(),
                     {at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s), at(r + 1, s + 1), at(r, s + 1)});
}

std::vector<deform::Ray> rays(int count) {
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<deform::Ray> out;
  for (int i = 0; i < count; ++i) {
    const glm::vec3 origin = 4.0f * glm::normalize(glm::vec3{unit(random), unit(random), unit(random)} + 1e-3f);
    out.push_back({origin, glm::vec3{unit(random), unit(random), unit(random)} * 0.7f - origin});
  }
  return out;
}

void pick_ray(benchmark::State& state) {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  sphere(static_cast<int>(state.range(0)), positions, indices);
  deform::TriangleBvh bvh;
  bvh.build(positions, indices);
  const std::vector<deform::Ray> queries = rays(1024);
  std::size_t i = 0;
  long hits = 0;
  for (auto _ : state) {
    const deform::RayHit hit = bvh.intersect(queries[i++ & 1023]);
    hits += hit.hit;
    benchmark::DoNotOptimize(hit);
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["triangles"] = static_cast<double>(bvh.triangle_count());
  state.counters["hit_rate"] = static_cast<double>(hits) / static_cast<double>(state.iterations());
}

void pick_brute_force(benchmark::State& state) {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  sphere(static_cast<int>(state.range(0)), positions, indices);
  const std::vector<deform::Ray> queries = rays(1024);
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(deform::intersect_triangles(queries[i++ & 1023], positions, indices));
  state.SetItemsProcessed(state.iterations());
}

void pick_refit(benchmark::State& state) {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  sphere(static_cast<int>(state.range(0)), positions, indices);
  deform::TriangleBvh bvh;
  bvh.build(positions, indices);
  std::vector<glm::vec3> moved = positions;
  float phase = 0.0f;
  for (auto _ : state) {
    phase += 0.01f;
    for (std::size_t p = 0; p < moved.size(); ++p)
      moved[p] = positions[p] * (1.0f + 0.1f * std::sin(phase + positions[p].y));
    benchmark::DoNotOptimize(bvh.refit(moved));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<long>(bvh.triangle_count()));
}

void pick_build(benchmark::State& state) {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;
  sphere(static_cast<int>(state.range(0)), positions, indices);
  deform::TriangleBvh bvh;
  for (auto _ : state) bvh.build(positions, indices);
  state.SetItemsProcessed(state.iterations() * static_cast<long>(indices.size() / 3));
}

}  // namespace

BENCHMARK(pick_ray)->Name("pick/ray")->Arg(100000)->Arg(1000000);
BENCHMARK(pick_brute_force)->Name("pick/brute_force")->Arg(100000);
BENCHMARK(pick_refit)->Name("pick/refit")->Arg(100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(pick_build)->Name("pick/build")->Arg(100000)->Unit(benchmark::kMillisecond);
