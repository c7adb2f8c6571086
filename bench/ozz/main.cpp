// libdeform beside ozz-animation 0.16 on the same data, in one binary (docs/performance.md, "libdeform beside
// ozz-animation"). Not part of the suite: bench/ozz/run.sh builds it against an ozz source tree.
//
// Data: the built-in character (2,850 points, its own 4-influence weights, normals averaged per point from the
// mesh's render-vertex normals), its "walk" and "run" clips with their keys made linear (ozz's keys are linear; the
// built-in clips are cubic splines): both libraries interpolate the same keys, libdeform by slerp, ozz by nlerp, and
// ozz's AnimationBuilder quantises them (rotations to 16-bit components, translations to half floats).
//  ozz/skin/<isa>:   skinning alone, positions and normals, 4 influences, one thread, the palette of the walk at 0.3 s;
//                    libdeform's SkinningJob (instruction set <isa>: auto = the best this CPU has) and ozz's.
//  ozz/frame/<n>:    the whole common frame of n characters, one thread: sample walk and run, blend them at 0.5,
//                    local to model, the skinning palette, skin positions and normals. Character c plays from
//                    0.37 · c s on, every iteration one frame (1/60 s) later: forward playback, which ozz's sampling
//                    contexts are made for (one per clip and character), and libdeform's SamplingJob cursors too.
//  ozz/skin/parts:  ozz/skin/auto against ozz given the benefit its own pipeline gives itself: the mesh split into
//                    parts by influence count (fbx2mesh's way), one ozz SkinningJob per part with influences_count 1
//                    to 4; libdeform's job as in ozz/skin/auto (the whole mesh, 4 slots).
//  ozz/skin_positions/auto, ozz/pose/<n>: where the time goes: skinning positions only, and the frame without the
//                    skinning (sampling, blending, local to model and the palette).
// Each benchmark times both libraries in every iteration, alternating which goes first, and reports the mean time of
// each per iteration (libdeform_us, ozz_us) and their ratio (speedup = ozz / libdeform: > 1 when libdeform is faster).
// Before timing, main() prints how far the two outputs are apart.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/extras/builtin.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/blending.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
#include "ozz_side.hpp"

namespace {

constexpr int crowd = 100;
constexpr float blend = 0.5f;
constexpr float frame_seconds = 1.0f / 60.0f;
constexpr float phase_seconds = 0.37f;

std::array<float, 16> to_array(const glm::mat4& m) {
  std::array<float, 16> r;
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 4; ++k) r[std::size_t(4 * c + k)] = m[c][k];
  return r;
}

// The same keys, interpolated linearly.
deform::Animation linear_keys(deform::Animation clip) {
  for (deform::Channel& c : clip.channels) {
    c.translation.interpolation = c.rotation.interpolation = deform::Interpolation::linear;
    c.translation.in_tangents.clear();
    c.translation.out_tangents.clear();
    c.rotation.in_tangents.clear();
    c.rotation.out_tangents.clear();
  }
  return clip;
}

ozz_side::ClipData clip_data(const deform::Animation& clip, const deform::Skeleton& skeleton) {
  const std::size_t bones = skeleton.bone_count();
  const deform::Pose rest = skeleton.bind_pose();
  ozz_side::ClipData d;
  d.name = clip.name;
  d.duration = clip.duration;
  d.translation_times.resize(bones);
  d.rotation_times.resize(bones);
  d.translations.resize(bones);
  d.rotations.resize(bones);
  for (const deform::Channel& c : clip.channels) {
    const auto b = std::size_t(c.bone);
    d.translation_times[b] = c.translation.times;
    for (const glm::vec3& v : c.translation.values) d.translations[b].push_back({v.x, v.y, v.z});
    d.rotation_times[b] = c.rotation.times;
    for (const glm::quat& q : c.rotation.values) d.rotations[b].push_back({q.x, q.y, q.z, q.w});
  }
  for (std::size_t b = 0; b < bones; ++b) {
    if (d.translation_times[b].empty()) {
      const glm::vec3 t = rest.translations[b];
      d.translation_times[b] = {0.0f};
      d.translations[b] = {{t.x, t.y, t.z}};
    }
    if (d.rotation_times[b].empty()) {
      const glm::quat q = rest.rotations[b];
      d.rotation_times[b] = {0.0f};
      d.rotations[b] = {{q.x, q.y, q.z, q.w}};
    }
  }
  return d;
}

// One libdeform character's per-frame buffers.
struct DeformCharacter {
  deform::Pose layers[2];
  deform::Pose blended;
  std::vector<std::uint32_t> cursors[2];  // SamplingJob's key cursor per clip (forward playback: no search)
  std::vector<glm::mat4> world, palette;
  std::vector<glm::vec3> positions, normals;
};

struct Scene {
  deform::Model model = deform::builtin_character();
  std::vector<deform::Animation> clips;  // walk, run; linear keys
  std::vector<glm::vec3> normals;        // per point
  std::vector<glm::mat4> skin_palette;   // the walk at 0.3 s
  std::vector<glm::vec3> out_positions, out_normals;
  deform::Pose rest;
  std::vector<DeformCharacter> characters;
  std::unique_ptr<ozz_side::Runner> ozz;
  std::vector<float> ozz_positions, ozz_normals;

  Scene() {
    const deform::Skeleton& skeleton = model.skeleton;
    const std::size_t bones = skeleton.bone_count(), points = model.mesh.point_count();
    if (model.weights.has_extra()) throw std::runtime_error("the built-in character has more than 4 influences");
    const auto all = deform::builtin_clips(model);
    for (const char* name : {"walk", "run"}) {
      const auto i = deform::find_clip(all, name);
      if (i < 0) throw std::runtime_error(std::string("no clip ") + name);
      clips.push_back(linear_keys(all[std::size_t(i)]));
      clips.back().require_valid(bones);
    }
    normals.assign(points, glm::vec3(0.0f));
    for (std::size_t v = 0; v < model.mesh.vertex_count(); ++v)
      normals[model.mesh.vertex_point[v]] += model.mesh.vertex_normals[v];
    for (glm::vec3& n : normals) n = glm::normalize(n);
    rest = skeleton.bind_pose();

    characters.resize(crowd);
    for (DeformCharacter& c : characters) {
      c.layers[0] = c.layers[1] = c.blended = rest;
      for (int k = 0; k < 2; ++k) c.cursors[k].assign(2 * clips[std::size_t(k)].channels.size(), 0);
      c.world.resize(bones);
      c.palette.resize(bones);
      c.positions.resize(points);
      c.normals.resize(points);
    }
    // The skinning-alone palette: the walk at 0.3 s.
    sample_pose(characters[0], 0.3f, 0.0f);
    skin_palette = characters[0].palette;
    out_positions.resize(points);
    out_normals.resize(points);

    ozz_side::RigData rig;
    for (std::size_t b = 0; b < bones; ++b) {
      const deform::Bone& bone = skeleton.bones()[b];
      if (skeleton.key(std::int32_t(b)) != bone.name) throw std::runtime_error("bone names are not unique");
      rig.names.push_back(bone.name);
      rig.parents.push_back(bone.parent);
      rig.rest_translations.push_back({rest.translations[b].x, rest.translations[b].y, rest.translations[b].z});
      const glm::quat q = rest.rotations[b];
      rig.rest_rotations.push_back({q.x, q.y, q.z, q.w});
      rig.inverse_bind.push_back(to_array(skeleton.inverse_bind_world()[b]));
    }
    const std::vector<ozz_side::ClipData> data{clip_data(clips[0], skeleton), clip_data(clips[1], skeleton)};
    ozz_side::MeshData mesh{{&model.mesh.positions[0].x, points * 3},
                            {&normals[0].x, points * 3},
                            {&model.weights.bones[0].x, points * 4},
                            {&model.weights.weights[0].x, points * 4}};
    ozz = std::make_unique<ozz_side::Runner>(rig, data, mesh, blend, crowd);
    std::vector<std::array<float, 16>> palette;
    for (const glm::mat4& m : skin_palette) palette.push_back(to_array(m));
    ozz->set_palette(palette);
    ozz_positions.resize(points * 3);
    ozz_normals.resize(points * 3);
  }

  // Sampling (weight `run_weight` of the run; 0: the walk alone), blending, local to world with the palette.
  void sample_pose(DeformCharacter& c, float seconds, float run_weight) const {
    for (int k = 0; k < 2; ++k) {
      deform::SamplingJob sampling;
      sampling.animation = &clips[std::size_t(k)];
      sampling.time = seconds;
      sampling.rotations = c.layers[k].rotations;
      sampling.translations = c.layers[k].translations;
      sampling.cursor = c.cursors[k];
      if (!sampling.run()) throw std::runtime_error("SamplingJob refused");
    }
    const deform::BlendLayer layers[2] = {{c.layers[0].rotations, c.layers[0].translations, 1.0f - run_weight, {}},
                                          {c.layers[1].rotations, c.layers[1].translations, run_weight, {}}};
    deform::BlendingJob blending;
    blending.layers = layers;
    blending.rest_rotations = rest.rotations;
    blending.rest_translations = rest.translations;
    blending.rotations = c.blended.rotations;
    blending.translations = c.blended.translations;
    if (!blending.run()) throw std::runtime_error("BlendingJob refused");
    deform::LocalToWorldJob ltw;
    ltw.skeleton = &model.skeleton;
    ltw.rotations = c.blended.rotations;
    ltw.translations = c.blended.translations;
    ltw.world = c.world;
    ltw.palette = c.palette;
    if (!ltw.run()) throw std::runtime_error("LocalToWorldJob refused");
  }

  deform::SkinningJob skinning(std::span<const glm::mat4> palette, std::vector<glm::vec3>& positions,
                               std::vector<glm::vec3>& out_normals_, deform::Isa isa = deform::Isa::automatic) const {
    deform::SkinningJob job;
    job.isa = isa;
    job.matrices = palette;
    job.bone_indices = model.weights.bones;
    job.bone_weights = model.weights.weights;
    job.in_positions = deform::as_floats(model.mesh.positions);
    job.in_normals = deform::as_floats(normals);
    job.out_positions = deform::as_floats(positions);
    job.out_normals = deform::as_floats(out_normals_);
    return job;
  }

  // libdeform's whole frame of character c at `seconds`.
  void frame(int index, float seconds) {
    DeformCharacter& c = characters[std::size_t(index)];
    sample_pose(c, seconds, blend);
    if (!skinning(c.palette, c.positions, c.normals).run()) throw std::runtime_error("SkinningJob refused");
  }
};

Scene& scene() {
  static Scene s;
  return s;
}

float character_time(int c, int frame) { return phase_seconds * float(c) + frame_seconds * float(frame); }

struct Difference {
  float points = 0.0f, normals = 0.0f;  // largest distance between points, between unit normals
  double normals_sum = 0.0;             // of the normal distances, for the mean
  std::size_t count = 0;
  void add(const Difference& d) {
    points = std::max(points, d.points);
    normals = std::max(normals, d.normals);
    normals_sum += d.normals_sum;
    count += d.count;
  }
  double normals_mean() const { return count ? normals_sum / double(count) : 0.0; }
};

glm::vec3 at(std::span<const float> v, std::size_t i) { return {v[3 * i], v[3 * i + 1], v[3 * i + 2]}; }

// ozz does not renormalise a skinned normal; libdeform does: normals are compared as directions.
Difference compare(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                   std::span<const float> ozz_positions, std::span<const float> ozz_normals) {
  Difference d;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    d.points = std::max(d.points, glm::length(positions[i] - at(ozz_positions, i)));
    const float n = glm::length(normals[i] - glm::normalize(at(ozz_normals, i)));
    d.normals = std::max(d.normals, n);
    d.normals_sum += double(n);
  }
  d.count = positions.size();
  return d;
}

// The two rules for normals differ by design: libdeform maps a normal by the cofactor of the blended matrix
// Σ wᵢ Mᵢ (the inverse-transpose rule, exact for the blended map), ozz by the blended matrix itself (exact only
// where the blend is a rotation). So ozz's normals are checked against that rule computed here in plain glm: the
// largest distance between the directions.
float ozz_rule_difference(const Scene& s, std::span<const glm::mat4> palette, std::span<const float> ozz_normals);

// Prints how far apart the two libraries' outputs are; false when they disagree beyond what the key quantisation
// and nlerp explain (a mapping error shows as centimetres).
bool check() {
  Scene& s = scene();
  const float height = 1.8f;
  bool ok = true;
  if (!s.skinning(s.skin_palette, s.out_positions, s.out_normals).run() || !s.ozz->skin(s.ozz_positions, s.ozz_normals))
    throw std::runtime_error("a skinning job refused");
  const Difference skin = compare(s.out_positions, s.out_normals, s.ozz_positions, s.ozz_normals);
  const float rule = ozz_rule_difference(s, s.skin_palette, s.ozz_normals);
  std::printf(
      "skinning alone, same palette: max point difference %.3g m (%.3g of the height); normals (unit "
      "directions): libdeform's cofactor rule against ozz's blended-matrix rule max %.3g, mean %.3g; ozz "
      "against that rule in plain glm max %.3g\n",
      double(skin.points), double(skin.points / height), double(skin.normals), skin.normals_mean(), double(rule));
  ok = ok && skin.points < 1e-5f * height && rule < 1e-4f;

  // ozz's parts against its whole-mesh job, point by point through the parts' order.
  std::vector<float> part_positions(s.ozz_positions.size()), part_normals(s.ozz_normals.size());
  if (!s.ozz->skin_parts(part_positions, part_normals)) throw std::runtime_error("an ozz part job refused");
  const std::vector<std::uint32_t> order = s.ozz->part_points();
  float parts_apart = 0.0f;
  for (std::size_t j = 0; j < order.size(); ++j)
    for (std::size_t c = 0; c < 3; ++c)
      parts_apart = std::max({parts_apart, std::abs(part_positions[3 * j + c] - s.ozz_positions[3 * order[j] + c]),
                              std::abs(part_normals[3 * j + c] - s.ozz_normals[3 * order[j] + c])});
  const std::vector<std::size_t> sizes = s.ozz->part_sizes();
  std::printf("ozz's parts: points of 1/2/3/4 influences %zu/%zu/%zu/%zu; against its whole mesh: max %.3g\n", sizes[0],
              sizes[1], sizes[2], sizes[3], double(parts_apart));
  ok = ok && parts_apart < 1e-5f;

  float bone = 0.0f;
  Difference frame;
  for (int f = 0; f < 120; f += 7)
    for (int c = 0; c < crowd; c += 9) {
      const float t = character_time(c, f);
      s.frame(c, t);
      if (!s.ozz->frame(c, t)) throw std::runtime_error("an ozz job refused");
      for (std::size_t b = 0; b < s.model.skeleton.bone_count(); ++b) {
        const auto m = s.ozz->model(c, int(b));
        const glm::vec3 head(m[12], m[13], m[14]);
        bone = std::max(bone, glm::length(head - glm::vec3(s.characters[std::size_t(c)].world[b][3])));
      }
      frame.add(compare(s.characters[std::size_t(c)].positions, s.characters[std::size_t(c)].normals,
                        s.ozz->positions(c), s.ozz->normals(c)));
    }
  std::printf(
      "whole frame (linear keys: libdeform slerp, ozz nlerp of its quantised keys), 17 frames x 12 "
      "characters: max bone head difference %.3g m, max point difference %.3g m (%.3g of the height); "
      "normals (the two rules, as above) max %.3g, mean %.3g\n",
      double(bone), double(frame.points), double(frame.points / height), double(frame.normals), frame.normals_mean());
  ok = ok && frame.points < 1e-2f * height;
  return ok;
}

float ozz_rule_difference(const Scene& s, std::span<const glm::mat4> palette, std::span<const float> ozz_normals) {
  float largest = 0.0f;
  for (std::size_t i = 0; i < s.normals.size(); ++i) {
    glm::mat3 m(0.0f);
    for (int k = 0; k < 4; ++k) m += s.model.weights.weights[i][k] * glm::mat3(palette[s.model.weights.bones[i][k]]);
    largest = std::max(largest, glm::length(glm::normalize(m * s.normals[i]) - glm::normalize(at(ozz_normals, i))));
  }
  return largest;
}

using Clock = std::chrono::steady_clock;

// Runs both in every iteration, alternating which goes first; reports each one's mean time and the ratio.
template <class Deform, class Ozz>
void paired(benchmark::State& state, Deform&& deform_side, Ozz&& ozz_side) {
  double deform_seconds = 0.0, ozz_seconds = 0.0;
  bool deform_first = true;
  for (auto _ : state) {
    for (int half = 0; half < 2; ++half) {
      const bool deform_now = (half == 0) == deform_first;
      const auto start = Clock::now();
      if (deform_now) deform_side();
      else ozz_side();
      benchmark::ClobberMemory();
      const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
      (deform_now ? deform_seconds : ozz_seconds) += seconds;
    }
    deform_first = !deform_first;
  }
  const double n = double(state.iterations());
  state.counters["libdeform_us"] = deform_seconds / n * 1e6;
  state.counters["ozz_us"] = ozz_seconds / n * 1e6;
  state.counters["speedup"] = ozz_seconds / deform_seconds;
}

// `parts`: ozz by parts (normals on).
void skin(benchmark::State& state, deform::Isa isa, bool normals, bool parts) {
  Scene& s = scene();
  deform::SkinningJob job = s.skinning(s.skin_palette, s.out_positions, s.out_normals, isa);
  if (!normals) {
    job.in_normals = {};
    job.out_normals = {};
  }
  if (!job.validate()) {
    state.SkipWithError("libdeform's job is not valid here (instruction set not available?)");
    return;
  }
  paired(
      state,
      [&] {
        job.run();
        benchmark::DoNotOptimize(s.out_positions.data());
      },
      [&] {
        if (parts) s.ozz->skin_parts(s.ozz_positions, s.ozz_normals);
        else if (normals) s.ozz->skin(s.ozz_positions, s.ozz_normals);
        else s.ozz->skin_positions(s.ozz_positions);
        benchmark::DoNotOptimize(s.ozz_positions.data());
      });
  state.SetItemsProcessed(state.iterations() * std::int64_t(s.model.mesh.point_count()));
}

void frame(benchmark::State& state, bool skinning) {
  Scene& s = scene();
  const int characters = int(state.range(0));
  int deform_frame = 0, ozz_frame = 0;
  paired(
      state,
      [&] {
        for (int c = 0; c < characters; ++c) {
          const float t = character_time(c, deform_frame);
          if (skinning) s.frame(c, t);
          else s.sample_pose(s.characters[std::size_t(c)], t, blend);
        }
        ++deform_frame;
      },
      [&] {
        for (int c = 0; c < characters; ++c) {
          const float t = character_time(c, ozz_frame);
          if (skinning) s.ozz->frame(c, t);
          else s.ozz->pose(c, t);
        }
        ++ozz_frame;
      });
  state.SetItemsProcessed(state.iterations() * characters);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  try {
    std::printf("libdeform SkinningJob automatic instruction set: %s; ozz math compiled for %s\n",
                deform::isa_name(deform::isa_best()), ozz_side::Runner::simd_name());
    std::printf("built-in character: %zu points, %zu bones; clips walk %.2f s and run %.2f s, blended at %.1f\n",
                scene().model.mesh.point_count(), scene().model.skeleton.bone_count(),
                double(scene().clips[0].duration), double(scene().clips[1].duration), double(blend));
    if (!check()) {
      std::fprintf(stderr, "the two libraries disagree beyond the expected rounding: not timing\n");
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  benchmark::RegisterBenchmark("ozz/skin/auto", skin, deform::Isa::automatic, true, false);
  benchmark::RegisterBenchmark("ozz/skin/avx2", skin, deform::Isa::avx2, true, false);
  benchmark::RegisterBenchmark("ozz/skin/parts", skin, deform::Isa::automatic, true, true);
  benchmark::RegisterBenchmark("ozz/frame", frame, true)->ArgName("characters")->Arg(1)->Arg(crowd);
  // Where the time goes: skinning without normals, and the frame without the skinning.
  benchmark::RegisterBenchmark("ozz/skin_positions/auto", skin, deform::Isa::automatic, false, false);
  benchmark::RegisterBenchmark("ozz/pose", frame, false)->ArgName("characters")->Arg(1)->Arg(crowd);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
