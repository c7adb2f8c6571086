// elastic/step: one frame of a 4×4×4 lattice's oscillators (exact, Verlet, exact + neighbour springs).
// elastic/mass_spring_50x50 vs elastic/lattice_4x4x4: the thesis' rejected design (§8.2.3: every vertex of a 50×50
// grid a particle with structural, shear and bend springs) next to the one it chose (springs on the 64 lattice
// points), both one 1/60 s frame with the same spring kinds and sub-step.
#include <benchmark/benchmark.h>

#include <vector>

#include "deform/runtime/elastic.hpp"
namespace {

std::vector<glm::vec3> grid(glm::ivec3 dims) {
  std::vector<glm::vec3> points;
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) points.emplace_back(float(i), float(j), float(k));
  return points;
}

// Steps frames toward a rest that alternates between two shapes every half second, so the points keep moving.
void run_frames(benchmark::State& state, glm::ivec3 dims, const deform::ElasticSettings& settings) {
  const std::vector<glm::vec3> rest = grid(dims);
  std::vector<glm::vec3> stretched = rest;
  for (glm::vec3& p : stretched) p.x *= 1.3f;
  deform::ElasticLattice lattice(rest, settings, dims);
  int frame = 0;
  for (auto _ : state) {
    lattice.step(1.0f / 60.0f, (frame++ / 30) % 2 ? rest : stretched);
    benchmark::DoNotOptimize(lattice.positions().data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(rest.size()));
  state.counters["points"] = double(rest.size());
}

deform::ElasticSettings with_springs() {
  deform::ElasticSettings s;
  s.springs.structural = s.springs.shear = s.springs.bend = true;
  return s;
}

void step_exact(benchmark::State& state) { run_frames(state, glm::ivec3(4), {}); }
void step_verlet(benchmark::State& state) {
  deform::ElasticSettings s;
  s.integrator = deform::Integrator::verlet;
  run_frames(state, glm::ivec3(4), s);
}
void step_springs(benchmark::State& state) { run_frames(state, glm::ivec3(4), with_springs()); }
void mass_spring_50x50(benchmark::State& state) { run_frames(state, glm::ivec3(50, 50, 1), with_springs()); }
void lattice_4x4x4(benchmark::State& state) { run_frames(state, glm::ivec3(4), with_springs()); }

BENCHMARK(step_exact)->Name("elastic/step/exact");
BENCHMARK(step_verlet)->Name("elastic/step/verlet");
BENCHMARK(step_springs)->Name("elastic/step/exact_springs");
BENCHMARK(mass_spring_50x50)->Name("elastic/mass_spring_50x50");
BENCHMARK(lattice_4x4x4)->Name("elastic/lattice_4x4x4");

}  // namespace
