// ddm/*: Direct Delta Mush against linear blend skinning on the same points, weights and palettes, positions and
// normals, one thread; items = points. The target (issue 33): DDM at most 6× LBS per vertex, at 2,850 and 100k points;
// the bind at most 2 s for a 40k-point mesh.
//   ddm/run/builtin, lbs/builtin        the built-in character (2,850 points, its own weights, 33 bones)
//   ddm/run/100k, lbs/100k              the 400 × 250 torus, 16 bones around its ring, two to three influences a point
//   ddm/run_threads/100k                DirectDeltaMushJob::run(pool) on every thread
//   ddm/reduced/builtin, ddm/reduced/100k  DirectDeltaMushReducedJob (reduce_direct_delta_mush of the same binding; its
//                                       lane kernel over the same blocks of 16 points and rounds as ddm/run's),
//                                       compute_dual_quat_palette of each frame's palette included
//   ddm/reduced_job/builtin, .../100k   the same with the rotations converted ahead: the job alone
//   ddm/bind/builtin, ddm/bind/40k      bind_direct_delta_mush with the default settings (the 200 × 200 torus)
// The LBS figures are SkinningJob's fastest kernel (the library's: what a caller would use), not a plain loop. The
// per-frame target is met by the reduced form (4 floats an influence, the bones' rotations blended) since its lane
// kernel; the full form (ddm/run/*) stays above it (docs/performance.md, 2026-11-28 11:45 UTC).
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/offline/direct_delta_mush.hpp"
#include "deform/runtime/direct_delta_mush.hpp"
#include "deform/runtime/parallel.hpp"
#include "deform/runtime/skinning.hpp"
#include "fixtures.hpp"

namespace {

constexpr int ring_bones = 16;

struct Rig {
  deform::Mesh mesh;
  deform::SkinWeights weights;
  std::vector<std::vector<glm::mat4>> palettes;  // 16 frames
  std::vector<glm::vec3> normals;
  int bones = 0;
};

// The torus of n × around points with `ring_bones` bones spaced around its ring, each point weighted to the bones
// beside its angle by a hat function (two influences, three near a bone); each frame turns every bone a little about
// its own centre, differently.
std::unique_ptr<Rig> torus_rig(int n, int around) {
  auto rig = std::make_unique<Rig>();
  rig->mesh = bench_fixtures::seamed_torus(n, around);
  rig->bones = ring_bones;
  const float tau = 2 * std::numbers::pi_v<float>;
  for (const glm::vec3& p : rig->mesh.positions) {
    const float s = std::atan2(p.y, p.x) / tau * float(ring_bones);  // in bones, (-8, 8]
    const float wrapped = s < 0.0f ? s + float(ring_bones) : s;
    std::vector<std::uint16_t> bones;
    std::vector<float> values;
    for (int b = 0; b < ring_bones; ++b) {
      float d = std::abs(wrapped - float(b));
      d = std::min(d, float(ring_bones) - d);
      if (d < 1.3f) bones.push_back(std::uint16_t(b)), values.push_back(1.3f - d);
    }
    deform::append_influences(rig->weights, bones, values);
    rig->normals.push_back(glm::normalize(p - glm::normalize(glm::vec3(p.x, p.y, 0.0f))));
  }
  std::mt19937 random(33);
  std::uniform_real_distribution<float> angle(-0.6f, 0.6f);
  for (int f = 0; f < 16; ++f) {
    std::vector<glm::mat4> palette;
    for (int b = 0; b < ring_bones; ++b) {
      const float a = tau * float(b) / float(ring_bones);
      const glm::vec3 centre(std::cos(a), std::sin(a), 0.0f);
      glm::mat4 m = glm::translate(glm::mat4(1.0f), centre);
      const float turn = angle(random);
      m = glm::rotate(m, turn, glm::normalize(glm::vec3{angle(random), angle(random), 1.0f}));
      palette.push_back(glm::translate(m, -centre));
    }
    rig->palettes.push_back(std::move(palette));
  }
  return rig;
}

// The built-in character, each frame its left arm and spine bent differently (a palette from FK).
std::unique_ptr<Rig> builtin_rig() {
  auto rig = std::make_unique<Rig>();
  const deform::Model model = deform::builtin_character();
  rig->mesh = model.mesh;
  rig->weights = model.weights;
  rig->bones = int(model.skeleton.bone_count());
  for (std::size_t i = 0; i < rig->mesh.point_count(); ++i)
    rig->normals.push_back(glm::normalize(rig->mesh.positions[i] - glm::vec3(0.0f, 1.0f, 0.0f)));
  const deform::Skeleton& sk = model.skeleton;
  for (int f = 0; f < 16; ++f) {
    deform::Pose pose = sk.bind_pose();
    sk.set_euler(pose, sk.find("forearm_l"), {10.0f * float(f), 0.0f, 0.0f});
    sk.set_euler(pose, sk.find("upperarm_l"), {0.0f, 3.0f * float(f), 20.0f});
    std::vector<glm::mat4> world(sk.bone_count()), palette(sk.bone_count());
    deform::LocalToWorldJob fk;
    fk.skeleton = &sk;
    fk.rotations = pose.rotations;
    fk.translations = pose.translations;
    fk.world = world;
    fk.palette = palette;
    (void)fk.run();
    rig->palettes.push_back(std::move(palette));
  }
  return rig;
}

const Rig& rig(int which) {  // 0: built-in, 1: 100k torus, 2: 40k torus
  static std::unique_ptr<Rig> rigs[3];
  if (!rigs[which]) rigs[which] = which == 0 ? builtin_rig() : which == 1 ? torus_rig(400, 250) : torus_rig(200, 200);
  return *rigs[which];
}

void ddm(benchmark::State& state, int which, bool threads) {
  const Rig& r = rig(which);
  const deform::DirectDeltaMushBinding binding = deform::bind_direct_delta_mush(r.mesh, r.weights);
  std::vector<glm::vec3> out(r.mesh.point_count()), out_normals(r.mesh.point_count());
  deform::DirectDeltaMushJob job;
  job.binding = &binding;
  job.out_positions = out;
  job.in_normals = r.normals;
  job.out_normals = out_normals;
  deform::ThreadPool pool;
  int frame = 0;
  for (auto _ : state) {
    job.matrices = r.palettes[std::size_t(frame++ % 16)];
    if (threads) {
      (void)job.run(pool);
    } else {
      (void)job.run();
    }
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(r.mesh.point_count()));
  state.counters["influences"] = double(binding.influence_count()) / double(binding.point_count());
  // The kernel's layout (DirectDeltaMushLanes): rounds per block of 16 points, and how many of them share one bone.
  const deform::DirectDeltaMushLanes& lanes = binding.lanes;
  double shared = 0.0;
  for (const std::uint32_t s : lanes.shared) shared += double(s);
  state.counters["rounds"] = double(lanes.rounds.back()) / double(lanes.shared.size());
  state.counters["shared"] = shared / double(lanes.shared.size());
}

void ddm_reduced(benchmark::State& state, int which, bool convert) {
  const Rig& r = rig(which);
  deform::DirectDeltaMushReducedBinding binding;
  if (!deform::reduce_direct_delta_mush(deform::bind_direct_delta_mush(r.mesh, r.weights), binding)) {
    state.SkipWithError("reduce_direct_delta_mush refused the binding");
    return;
  }
  std::vector<glm::vec3> out(r.mesh.point_count()), out_normals(r.mesh.point_count());
  std::vector<deform::DualQuat> dual_quats(std::size_t(r.bones));
  std::vector<glm::mat3> scales(std::size_t(r.bones));
  // Each frame's rotations converted ahead, for the job's cost alone (convert = false).
  std::vector<std::vector<deform::DualQuat>> converted(16, dual_quats);
  for (std::size_t f = 0; f < 16; ++f) {
    bool has_scale = false;
    (void)deform::compute_dual_quat_palette(r.palettes[f], converted[f], scales, has_scale);
  }
  deform::DirectDeltaMushReducedJob job;
  job.binding = &binding;
  job.dual_quats = dual_quats;
  job.out_positions = out;
  job.in_normals = r.normals;
  job.out_normals = out_normals;
  int frame = 0;
  for (auto _ : state) {
    const std::size_t f = std::size_t(frame++ % 16);
    job.matrices = r.palettes[f];
    bool has_scale = false;
    if (convert) {
      (void)deform::compute_dual_quat_palette(job.matrices, dual_quats, scales, has_scale);
      job.dual_quats = dual_quats;
    } else {
      job.dual_quats = converted[f];
    }
    (void)job.run();
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(r.mesh.point_count()));
  state.counters["influences"] = double(binding.influence_count()) / double(binding.point_count());
  state.counters["rounds"] = double(binding.lanes.rounds.back()) / double(binding.lanes.shared.size());
}

void lbs(benchmark::State& state, int which) {
  const Rig& r = rig(which);
  std::vector<glm::vec3> out(r.mesh.point_count()), out_normals(r.mesh.point_count());
  deform::SkinningJob job;
  job.bone_indices = r.weights.bones;
  job.bone_weights = r.weights.weights;
  job.extra_vertices = r.weights.extra_points;
  job.extra_offsets = r.weights.extra_offsets;
  job.extra_bones = r.weights.extra_bones;
  job.extra_weights = r.weights.extra_weights;
  job.in_positions = deform::as_floats(r.mesh.positions);
  job.out_positions = deform::as_floats(out);
  job.in_normals = deform::as_floats(r.normals);
  job.out_normals = deform::as_floats(out_normals);
  int frame = 0;
  for (auto _ : state) {
    job.matrices = r.palettes[std::size_t(frame++ % 16)];
    (void)job.run();
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(r.mesh.point_count()));
}

void bind(benchmark::State& state, int which) {
  const Rig& r = rig(which);
  for (auto _ : state) benchmark::DoNotOptimize(deform::bind_direct_delta_mush(r.mesh, r.weights));
  state.counters["points"] = double(r.mesh.point_count());
}

}  // namespace

BENCHMARK_CAPTURE(ddm, builtin, 0, false)->Name("ddm/run/builtin");
BENCHMARK_CAPTURE(lbs, builtin, 0)->Name("ddm/lbs/builtin");
BENCHMARK_CAPTURE(ddm, 100k, 1, false)->Name("ddm/run/100k")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(lbs, 100k, 1)->Name("ddm/lbs/100k")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(ddm_reduced, builtin, 0, true)->Name("ddm/reduced/builtin");
BENCHMARK_CAPTURE(ddm_reduced, builtin_job, 0, false)->Name("ddm/reduced_job/builtin");
BENCHMARK_CAPTURE(ddm_reduced, 100k, 1, true)->Name("ddm/reduced/100k")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(ddm_reduced, 100k_job, 1, false)->Name("ddm/reduced_job/100k")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(ddm, 100k_threads, 1, true)
    ->Name("ddm/run_threads/100k")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(bind, builtin, 0)->Name("ddm/bind/builtin")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(bind, 40k, 2)->Name("ddm/bind/40k")->Unit(benchmark::kMillisecond)->Iterations(2);
