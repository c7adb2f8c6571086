// Bind-time benchmarks of automatic weights (docs/performance.md, docs/weights.md): weights/heat, weights/voxel
// (resolution 128) and weights/distance on the built-in character (2,850 points, 33 bones) and on the same character
// with every triangle split in four twice (40k points: the "35,000-point mesh" of the targets, rounded up). Items =
// points.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/offline/picking.hpp"
#include "deform/offline/voxel_weights.hpp"
#include "deform/offline/weights.hpp"
namespace {

// The mesh with every triangle split in four at its edge midpoints (same surface, point space; render vertex =
// point in the result).
deform::Mesh split_in_four(const deform::Mesh& mesh) {
  deform::Mesh out;
  out.positions = mesh.positions;
  const std::vector<std::uint32_t> triangles = deform::point_triangles(mesh);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
  auto middle = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::minmax(a, b);
    const auto [it, added] = midpoint.try_emplace(key, static_cast<std::uint32_t>(out.positions.size()));
    if (added) out.positions.push_back(0.5f * (out.positions[a] + out.positions[b]));
    return it->second;
  };
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const std::uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
    const std::uint32_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
    out.triangles.insert(out.triangles.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  out.vertex_point.resize(out.positions.size());
  for (std::size_t i = 0; i < out.vertex_point.size(); ++i) out.vertex_point[i] = static_cast<std::uint32_t>(i);
  return out;
}

const deform::Model& character() {
  static const deform::Model model = deform::builtin_character();
  return model;
}

const deform::Mesh& mesh(int splits) {
  static const deform::Mesh once = split_in_four(character().mesh);
  static const deform::Mesh twice = split_in_four(once);
  return splits == 0 ? character().mesh : twice;
}

void weights_heat(benchmark::State& state) {
  const deform::Mesh& m = mesh(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    deform::WeightsResult r = deform::compute_heat_weights(m, character().skeleton);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.point_count()));
  state.counters["points"] = static_cast<double>(m.point_count());
}

void weights_voxel(benchmark::State& state) {
  const deform::Mesh& m = mesh(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    deform::WeightsResult r = deform::compute_voxel_weights(m, character().skeleton);
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.point_count()));
  state.counters["points"] = static_cast<double>(m.point_count());
}

void weights_distance(benchmark::State& state) {
  const deform::Mesh& m = mesh(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    deform::SkinWeights w = deform::compute_automatic_weights(m, character().skeleton);
    benchmark::DoNotOptimize(w);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(m.point_count()));
  state.counters["points"] = static_cast<double>(m.point_count());
}

}  // namespace

BENCHMARK(weights_heat)->Name("weights/heat_builtin")->Arg(0)->Unit(benchmark::kMillisecond);
BENCHMARK(weights_heat)->Name("weights/heat_40k")->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(weights_voxel)->Name("weights/voxel_builtin")->Arg(0)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(weights_voxel)->Name("weights/voxel_40k")->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(weights_distance)->Name("weights/distance_builtin")->Arg(0)->Unit(benchmark::kMillisecond);
BENCHMARK(weights_distance)->Name("weights/distance_40k")->Arg(2)->Unit(benchmark::kMillisecond);
