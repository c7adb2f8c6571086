// skin_influences/*: the general influence path against the four-influence kernels, one thread, 10k vertices with
// positions and normals, a 28-bone palette: every vertex with 4 (the fast kernels), 8 or 16 influences (every
// vertex takes the general kernel), and "mixed": 10% of the vertices with 8 influences, scattered (the runs between
// them take the fast kernels). morph/*: MorphJob over 10k points (positions and normals), 8 targets each moving 20%
// of the points, and 64 targets each moving 2% (a face rig's many small shapes). Figures: docs/performance.md.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/runtime/morph.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
namespace {

constexpr int bone_count = 28;
constexpr std::size_t vertex_count = 10000;

struct InfluenceData {
  std::vector<glm::vec3> positions, normals, out_positions, out_normals;
  deform::SkinWeights weights;
  std::vector<glm::mat4> palette;
  std::vector<deform::DualQuat> dual_quats;
  std::vector<glm::mat3> scales;
};

// `influences` per vertex (distinct bones, random weights); with `mixed`, only every 10th vertex has them and the
// others four.
InfluenceData make_data(int influences, bool mixed) {
  InfluenceData d;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), positive(0.1f, 1.0f);
  std::vector<std::uint16_t> bones;
  std::vector<float> values;
  for (std::size_t i = 0; i < vertex_count; ++i) {
    d.positions.push_back({u(rng), u(rng), u(rng)});
    d.normals.push_back(glm::normalize(glm::vec3{u(rng), u(rng), 2.0f}));
    const int n = mixed && i % 10 != 3 ? 4 : influences;
    const auto first = static_cast<int>(rng() % bone_count);
    bones.clear(), values.clear();
    for (int k = 0; k < n; ++k)
      bones.push_back(std::uint16_t((first + 3 * k) % bone_count)), values.push_back(positive(rng));
    deform::append_influences(d.weights, bones, values);
  }
  d.out_positions.resize(vertex_count);
  d.out_normals.resize(vertex_count);
  for (int b = 0; b < bone_count; ++b) {
    const float turn = u(rng) * 3.0f;
    glm::mat4 m = glm::rotate(glm::mat4(1.0f), turn, glm::normalize(glm::vec3{u(rng), u(rng), 1.0f}));
    m[3] = glm::vec4{u(rng), u(rng), u(rng), 1.0f};
    d.palette.push_back(m);
  }
  d.dual_quats.resize(bone_count);
  d.scales.resize(bone_count);
  bool has_scale = false;
  deform::compute_dual_quat_palette(d.palette, d.dual_quats, d.scales, has_scale);
  return d;
}

void skin_influences(benchmark::State& state, deform::SkinningMethod method, bool mixed) {
  InfluenceData d = make_data(static_cast<int>(state.range(0)), mixed);
  deform::SkinningJob job;
  job.method = method;
  job.matrices = d.palette;
  job.dual_quats = d.dual_quats;
  job.bone_indices = d.weights.bones;
  job.bone_weights = d.weights.weights;
  job.extra_vertices = d.weights.extra_points;
  job.extra_offsets = d.weights.extra_offsets;
  job.extra_bones = d.weights.extra_bones;
  job.extra_weights = d.weights.extra_weights;
  job.in_positions = deform::as_floats(d.positions);
  job.in_normals = deform::as_floats(d.normals);
  job.out_positions = deform::as_floats(d.out_positions);
  job.out_normals = deform::as_floats(d.out_normals);
  if (!job.validate()) state.SkipWithError("invalid job");
  for (auto _ : state) {
    job.run();
    benchmark::DoNotOptimize(d.out_positions.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * vertex_count));
}

using deform::SkinningMethod;
BENCHMARK_CAPTURE(skin_influences, lbs, SkinningMethod::lbs, false)
    ->Name("skin_influences/lbs")
    ->Arg(4)
    ->Arg(8)
    ->Arg(16);
BENCHMARK_CAPTURE(skin_influences, dqs, SkinningMethod::dqs, false)
    ->Name("skin_influences/dqs")
    ->Arg(4)
    ->Arg(8)
    ->Arg(16);
BENCHMARK_CAPTURE(skin_influences, lbs_mixed, SkinningMethod::lbs, true)->Name("skin_influences/lbs_mixed")->Arg(8);
BENCHMARK_CAPTURE(skin_influences, dqs_mixed, SkinningMethod::dqs, true)->Name("skin_influences/dqs_mixed")->Arg(8);

// state.range(0) = targets, state.range(1) = percent of the points each moves.
void morph(benchmark::State& state) {
  const auto target_count = static_cast<std::size_t>(state.range(0));
  const auto percent = static_cast<std::uint32_t>(state.range(1));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<glm::vec3> rest(vertex_count), rest_n(vertex_count), out(vertex_count), out_n(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i) rest[i] = {u(rng), u(rng), u(rng)}, rest_n[i] = {0, 0, 1};
  std::vector<deform::MorphTarget> targets(target_count);
  for (deform::MorphTarget& t : targets)
    for (std::uint32_t p = 0; p < vertex_count; ++p)
      if (rng() % 100 < percent) {
        t.points.push_back(p);
        t.position_deltas.push_back({u(rng), u(rng), u(rng)});
        t.normal_deltas.push_back({u(rng), u(rng), u(rng)});
      }
  std::vector<float> weights(target_count, 0.3f);
  deform::MorphJob job;
  job.targets = targets;
  job.weights = weights;
  job.rest_positions = rest;
  job.rest_normals = rest_n;
  job.out_positions = out;
  job.out_normals = out_n;
  if (!job.validate()) state.SkipWithError("invalid job");
  for (auto _ : state) {
    job.run();
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * vertex_count));
}
BENCHMARK(morph)->Name("morph/apply")->Args({8, 20})->Args({64, 2})->Unit(benchmark::kMicrosecond);

}  // namespace
