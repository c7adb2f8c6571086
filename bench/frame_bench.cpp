// frame/builtin_3_lattices: one whole frame of the thesis' scene on one thread — the built-in character (2,850
// points) reaching far, its three arm lattices stretched and springing: elastic step, FK, the ponytail's spring
// chain, skinning, lattices.
// The same rig on the character's points repeated (jittered) to 100k and 1M points; and the frame plus normals.
// frame/builtin_lattices_step_update and frame/builtin_3_lattices_shape: the cost of the stretch shape.
// frame/builtin_3_lattices_normals: the frame and normals() (transported, the default); frame/builtin_whole and
// frame/builtin_whole_morph below.
#include <benchmark/benchmark.h>

#include <random>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/model.hpp"
namespace {

// The built-in character with every point repeated (within a millimetre) to reach `points` points.
deform::Model scaled_model(std::size_t points) {
  deform::Model base = deform::builtin_character();
  if (points <= base.mesh.point_count()) return base;
  deform::Model big;
  big.name = "builtin-" + std::to_string(points);
  big.skeleton = base.skeleton;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> jitter(-1e-3f, 1e-3f);
  for (std::size_t p = 0; p < points; ++p) {
    const std::size_t source = p % base.mesh.point_count();
    big.mesh.positions.push_back(base.mesh.positions[source] + glm::vec3{jitter(rng), jitter(rng), jitter(rng)});
    big.weights.bones.push_back(base.weights.bones[source]);
    big.weights.weights.push_back(base.weights.weights[source]);
  }
  return big;
}

// A character mid-reach: its arm stretched toward a point 1 m beyond the shoulder and springing.
deform::Character reaching_character(std::size_t points) {
  deform::Model model = scaled_model(points);
  const deform::Rig rig = deform::builtin_rig(model);
  deform::Character c(std::move(model), rig);
  const std::int32_t hand = c.skeleton().find("hand_l");
  c.reach(hand, c.bone_position(c.skeleton().find("clavicle_l")) + glm::vec3(1.0f, 0.2f, 0.1f));
  return c;
}

void frame(benchmark::State& state) {
  deform::Character c = reaching_character(std::size_t(state.range(0)));
  std::size_t bound = 0;
  for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l) bound += c.deformers().bound_count(l);
  for (auto _ : state) {
    c.update(1.0f / 60.0f);
    benchmark::DoNotOptimize(c.positions().data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(c.positions().size()));
  state.counters["bound"] = double(bound);
}

// The lattices' share of a frame: springs' step and DeformerHierarchy::update (carrying the control points into world
// space, with the stretch shape: length floor and volume compensation) on the built-in character mid-reach.
// Arg 0: the plain stretch (StretchShape{0, 0}, which skips the shape); Arg 1: the default shape {0.7, 1}.
void hierarchy_update(benchmark::State& state) {
  deform::Character c = reaching_character(0);
  const deform::StretchShape shape = state.range(0) ? deform::StretchShape{} : deform::StretchShape{0.0f, 0.0f};
  for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l) c.deformers().set_shape(l, shape);
  const std::span<const glm::mat4> world = c.skeleton().bind_world();
  for (auto _ : state) {
    c.deformers().step(1.0f / 60.0f);
    c.deformers().update(world);
    benchmark::DoNotOptimize(c.deformers().displacements(0).data());
  }
}

// frame/builtin_3_lattices with the plain stretch (Arg 0) and the default shape (Arg 1).
void frame_shape(benchmark::State& state) {
  deform::Character c = reaching_character(0);
  const deform::StretchShape shape = state.range(0) ? deform::StretchShape{} : deform::StretchShape{0.0f, 0.0f};
  for (std::size_t l = 0; l < c.deformers().lattice_count(); ++l) c.deformers().set_shape(l, shape);
  for (auto _ : state) {
    c.update(1.0f / 60.0f);
    benchmark::DoNotOptimize(c.positions().data());
  }
}

void frame_with_normals(benchmark::State& state) {
  deform::Character c = reaching_character(0);
  for (auto _ : state) {
    c.update(1.0f / 60.0f);
    benchmark::DoNotOptimize(c.normals().data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(c.positions().size()));
}

// frame/builtin_whole: the whole frame of the built-in character as an engine runs it, on one thread — the walk
// sampled (SamplingJob) into the pose, set_pose, update (FK, the springs' step, skinning, the three arm lattices,
// stretched mid-reach and springing) and normals() — with the transported normals (the default, Arg 0) or the
// recomputed ones (Arg 1).
void whole_frame(benchmark::State& state) {
  deform::Character c = reaching_character(0);
  c.set_normals_mode(state.range(0) ? deform::Character::NormalsMode::recomputed
                                    : deform::Character::NormalsMode::transported);
  const deform::Animation walk = deform::builtin_walk(c.model());
  deform::Pose pose = c.skeleton().bind_pose();
  deform::SamplingJob sampling;
  sampling.animation = &walk;
  sampling.rotations = pose.rotations;
  sampling.translations = pose.translations;
  if (!sampling.validate()) state.SkipWithError("walk does not fit");
  float time = 0.0f;
  for (auto _ : state) {
    time += 1.0f / 60.0f;
    sampling.time = time;
    sampling.run();
    c.set_pose(pose);
    c.update(1.0f / 60.0f);
    benchmark::DoNotOptimize(c.normals().data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(c.positions().size()));
}

// frame/builtin_whole_morph: frame/builtin_whole (transported normals) on the built-in character given two morph
// targets — one moving every point with normal deltas, one every third point — with every weight 0 (Arg 0: the
// morph job skipped, what a model with idle targets costs) or animated by a clip's morph channel and set by name
// each frame (Arg 1: MorphJob on the bind positions and normals before skinning).
void whole_frame_morph(benchmark::State& state) {
  deform::Model model = deform::builtin_character();
  for (int k = 0; k < 2; ++k) {
    deform::MorphTarget t;
    t.name = k ? "swell" : "lift";
    for (std::size_t p = 0; p < model.mesh.point_count(); p += k ? 3 : 1) {
      t.points.push_back(std::uint32_t(p));
      t.position_deltas.push_back(glm::vec3(0.0f, 0.01f * float(k + 1), 0.02f));
      if (!k) t.normal_deltas.push_back(glm::vec3(0.0f, 0.1f, 0.0f));
    }
    model.morph_targets.push_back(std::move(t));
  }
  const deform::Rig rig = deform::builtin_rig(model);
  deform::Character c(std::move(model), rig);
  c.reach(c.skeleton().find("hand_l"), c.bone_position(c.skeleton().find("clavicle_l")) + glm::vec3(1.0f, 0.2f, 0.1f));
  const deform::Animation walk = deform::builtin_walk(c.model());
  deform::Animation face;
  face.duration = 1.0f;
  deform::MorphChannel channel;
  channel.target = 0;
  channel.weight.times = {0.0f, 0.5f, 1.0f};
  channel.weight.values = {0.2f, 1.0f, 0.2f};
  face.morph_channels.push_back(channel);
  deform::Pose pose = c.skeleton().bind_pose();
  deform::SamplingJob sampling;
  sampling.animation = &walk;
  sampling.rotations = pose.rotations;
  sampling.translations = pose.translations;
  if (!sampling.validate()) state.SkipWithError("walk does not fit");
  const bool morphing = state.range(0) != 0;
  float time = 0.0f;
  for (auto _ : state) {
    time += 1.0f / 60.0f;
    sampling.time = time;
    sampling.run();
    c.set_pose(pose);
    if (morphing) {
      c.set_morph_weights(face, time);
      c.set_morph_weight("swell", 0.5f);
    }
    c.update(1.0f / 60.0f);
    benchmark::DoNotOptimize(c.normals().data());
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(c.positions().size()));
}

BENCHMARK(frame)->Name("frame/builtin_3_lattices")->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(frame)->Name("frame/3_lattices")->Arg(100000)->Arg(1000000)->Unit(benchmark::kMicrosecond);
BENCHMARK(hierarchy_update)->Name("frame/builtin_lattices_step_update")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(frame_shape)->Name("frame/builtin_3_lattices_shape")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(frame_with_normals)->Name("frame/builtin_3_lattices_normals")->Unit(benchmark::kMicrosecond);
BENCHMARK(whole_frame)->Name("frame/builtin_whole")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(whole_frame_morph)->Name("frame/builtin_whole_morph")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
