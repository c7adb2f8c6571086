// The model and its character: loading, the clips, the rig, and the Character's settings as the viewer changes them.
#include "model.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "deform/deform.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/runtime/blending.hpp"
#include "deform/runtime/error.hpp"
#if defined(DEFORM_VIEWER_HAVE_SIMPLIFY)
#include "deform/simplify/simplify.hpp"
#endif
#include "model_loading.hpp"
#include "view.hpp"

namespace viewer {
namespace {

// The model the options name (model_loading: the CLI loads the same way); an OBJ without --weights gets automatic
// weights. Exits with a message when the options name no loadable model.
model_loading::LoadedModel load(const Options& o) {
  const bool is_obj = o.model.size() > 4 &&
                      (o.model.substr(o.model.size() - 4) == ".obj" || o.model.substr(o.model.size() - 4) == ".OBJ");
  if (is_obj && o.skeleton.empty()) fail(o.model + ": an OBJ needs --skeleton S.sk");
  model_loading::LoadedModel loaded = model_loading::load_model(
      {.path = o.model, .skeleton = o.skeleton, .weights = o.weights, .automatic_weights = true, .references = {}});
  for (const std::string& w : loaded.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (o.up == 'y') loaded.up = glm::vec3(0.0f, 1.0f, 0.0f);
  if (o.up == 'z') loaded.up = glm::vec3(0.0f, 0.0f, 1.0f);
  return loaded;
}

void sample_one(const ViewerState& state, const deform::Animation& clip, float t, deform::Pose& into) {
  std::copy(state.bind_pose.rotations.begin(), state.bind_pose.rotations.end(), into.rotations.begin());
  std::copy(state.bind_pose.translations.begin(), state.bind_pose.translations.end(), into.translations.begin());
  deform::SamplingJob sampling;
  sampling.animation = &clip;
  sampling.time = t;
  sampling.rotations = into.rotations;
  sampling.translations = into.translations;
  (void)sampling.run();  // cannot fail: the clips were validated against this skeleton when loaded
}

// The clip at time t over the bind pose (bones without a channel keep it), blended with the second clip at the
// same phase when one is chosen. No allocation: `into` and the scratch poses are sized.
void sample_clip(ViewerState& state, float t, deform::Pose& into) {
  if (state.blend_clip < 0) {
    sample_one(state, state.clips[std::size_t(state.clip)], t, into);
    return;
  }
  const deform::Animation& first = state.clips[std::size_t(state.clip)];
  const deform::Animation& second = state.clips[std::size_t(state.blend_clip)];
  // The second clip's time at the first's phase (its own time when either has no length).
  const float t2 =
      first.duration > 0.0f && second.duration > 0.0f ? first.local_time(t) / first.duration * second.duration : t;
  sample_one(state, first, t, state.first);
  sample_one(state, second, t2, state.second);
  const deform::BlendLayer layers[] = {{state.first.rotations, state.first.translations, 1.0f - state.blend_weight, {}},
                                       {state.second.rotations, state.second.translations, state.blend_weight, {}}};
  deform::BlendingJob blend;
  blend.layers = layers;
  blend.rest_rotations = state.bind_pose.rotations;
  blend.rest_translations = state.bind_pose.translations;
  blend.rotations = into.rotations;
  blend.translations = into.translations;
  (void)blend.run();  // cannot fail: every pose has the skeleton's size, the weights are within [0, 1]
}

}  // namespace

void load_character(ViewerState& state) {
  const Options& options = state.options;
  model_loading::LoadedModel loaded = load(options);
  state.clips = std::move(loaded.clips);
  // A model with no clips of its own but the built-in character's bones (it, or its files in samples/data) gets the
  // built-in clips (idle, walk, run, wave); builtin_clips refuses any other skeleton, which then simply has none.
  if (state.clips.empty() && !loaded.imported) {
    try {
      state.clips = deform::builtin_clips(loaded.model);
    } catch (const deform::Error&) {
    }
  }
  state.clip_names.push_back("(none)");  // the panel's list, made once
  for (const deform::Animation& c : state.clips)
    state.clip_names.push_back(c.name.empty() ? "(unnamed)" : c.name.c_str());
  state.inertia = options.inertia;
  state.base_model = loaded.model;
  state.own_weights = state.base_model.weights;  // what the weight tools' "revert" gives back
  // The built-in character stretches whichever limb is nearest the click: its rig with lattices on every limb.
  state.rig = !options.rig.empty()
                  ? deform::read_rig_json(options.rig, state.base_model.skeleton, state.base_model.mesh.point_count())
              : loaded.builtin ? deform::builtin_full_rig(loaded.model)
                               : model_loading::starting_rig(loaded);
  if (options.pole) state.pole = *options.pole, state.use_pole = true;
  state.lattice_display = options.lattices == 'n'   ? LatticeDisplay::none
                          : options.lattices == 'e' ? LatticeDisplay::all
                                                    : LatticeDisplay::active;
  if (options.swing_twist) state.reach_limits = deform::Character::JointLimits::swing_twist;
  rebuild_character(state);
  if (!options.weight_map.empty()) {
    state.weight_bone = state.base_model.skeleton.find(options.weight_map);
    if (state.weight_bone < 0) fail("--weight-map: no bone '" + options.weight_map + "'");
  }
  // A clip by name, or "#N" for the N-th.
  auto find = [&](const std::string& name) {
    const int clip = name[0] == '#' ? std::atoi(name.c_str() + 1) : deform::find_clip(state.clips, name);
    if (clip < 0 || clip >= int(state.clips.size())) fail(loaded.source + ": no clip '" + name + "'");
    return clip;
  };
  if (!options.clip.empty()) select_clip(state, find(options.clip));  // play a clip from the start
  if (!options.blend_clip.empty()) {
    if (options.clip.empty()) fail("--blend needs --clip");
    state.blend_clip = find(options.blend_clip);
  }
  state.blend_weight = options.blend_weight;
  for (const auto& [name, weight] : options.morphs) {  // the model's targets and the rig's correctives
    bool found = false;
    const std::vector<deform::MorphTarget>& targets = state.character->model().morph_targets;
    for (std::size_t k = 0; k < targets.size(); ++k)
      if (targets[k].name == name) state.morph_held[k] = 1, state.morph_hold[k] = weight, found = true;
    if (!found) fail(loaded.source + ": --morph: no morph target '" + name + "'");
  }
  state.up = loaded.up;
}

void start_deformation(ViewerState& state) {
  const Options& options = state.options;
  if (options.dqs) state.character->settings.skinning = deform::SkinningMethod::dqs;
  state.ddm = options.ddm;
  state.mush_iterations = options.mush;
  apply_mush(state);
  if (options.gpu) {
    if (state.gpu_available) set_gpu(state, true);
    else std::fprintf(stderr, "deform_viewer: --gpu: %s; deforming on the CPU\n", gpu_missing(state).c_str());
  }
}

// The whole deformation on the GPU (on) or the CPU (off): the character only poses, GpuSkinning skins from its
// palette and GpuLatticeFields adds its lattices, all in the renderer's vertex buffer (whose UVs stay as created).
void set_gpu(ViewerState& state, bool on) {
  // GpuSkinning is LBS or DQS, and the GPU path has no Delta Mush.
  if (on && (state.ddm || state.mush_iterations > 0)) {
    std::fprintf(stderr, "deform_viewer: Direct Delta Mush and Delta Mush are CPU stages; deforming on the CPU\n");
    on = false;
  }
  if (on && state.character->level_count() > 1) {  // GpuSkinning skins with the model's own weights, not a level's
    std::fprintf(stderr,
                 "deform_viewer: the levels of detail (--lod-bones, --lod) are CPU levels; deforming on the CPU\n");
    on = false;
  }
  if (on && state.character->morph_target_count() > 0) {  // GpuSkinning skins the bind positions, not the morphed ones
    std::fprintf(stderr,
                 "deform_viewer: the model has morph targets, which the GPU path does not apply; "
                 "deforming on the CPU\n");
    on = false;
  }
  state.gpu = on && state.gpu_available;
  state.gpu_fields.clear();
  state.gpu_skinning.release();
  if (state.gpu) {
    const deform::Mesh& mesh = state.character->model().mesh;
    const auto normals = state.character->bind_normals();
    state.gpu_bind_normals.resize(mesh.vertex_count());
    for (std::size_t r = 0; r < mesh.vertex_count(); ++r) state.gpu_bind_normals[r] = normals[mesh.vertex_point[r]];
    deform::GpuSkinningBind bind;
    bind.positions = mesh.positions;
    bind.bone_indices = state.character->model().weights.bones;
    bind.bone_weights = state.character->model().weights.weights;
    bind.vertex_point = mesh.vertex_point;
    bind.normals = state.gpu_bind_normals;
    bind.bone_count = state.character->skeleton().bone_count();
    deform::Status status = state.gpu_skinning.create(bind);
    if (status) status = state.gpu_fields.create(state.character->deformers(), mesh.vertex_point, true);
    if (!status) {
      std::fprintf(stderr, "deform_viewer: GPU deformation refused: %s; deforming on the CPU\n", status.reason());
      state.gpu_fields.clear();
      state.gpu_skinning.release();
      state.gpu = false;
    }
  }
  state.character->settings.deform_on_cpu = !state.gpu;
}

namespace {

// The rig as the panel tunes it: each lattice with the panel's degree and elastic settings (the rig's own, taken at
// the first build).
deform::Rig tuned_rig(ViewerState& state) {
  deform::Rig rig = state.rig;
  for (auto& spec : rig.lattices) {
    if (state.degree == 0) state.degree = spec.degree.x;
    spec.degree = glm::ivec3(state.degree);
    if (state.elastic.oscillator.stiffness <= 0.0f) state.elastic = spec.elastic;
    spec.elastic = state.elastic.oscillator.stiffness > 0.0f ? state.elastic : spec.elastic;
  }
  if (state.degree == 0) state.degree = 3;
  if (state.elastic.oscillator.stiffness <= 0.0f) state.elastic = deform::ElasticSettings{};
  return rig;
}

// The motion of all the model's clips, 16 poses from each, for build_bone_lod to judge merges by.
std::vector<deform::Pose> clip_poses(const ViewerState& state) {
  std::vector<deform::Pose> poses;
  for (const deform::Animation& clip : state.clips) {
    for (int k = 0; k < 16; ++k) {
      deform::Pose pose = state.character->skeleton().bind_pose();
      sample_one(state, clip, clip.duration * float(k) / 16.0f, pose);
      poses.push_back(std::move(pose));
    }
  }
  return poses;
}

// --lod-bones N: the character shown at a level of detail that skins with N bones (fewer when the skeleton has
// fewer), merged on the motion of all the model's clips, by weight alone when it has none.
// --lod L|auto: four levels, as a game would give a character (docs/skinning.md, "Levels of detail"): level 0 the
// whole character; 1, 2 and 3 with 3/4, 1/2 and 1/3 of the bones (merged as above) and, where the simplify layer is
// built, the points and triangles of the mesh simplified to 0.5, 0.25 and 0.1 of its triangles; 1 with its deformers
// (on a simplified mesh, the spring chains), 2 and 3 without, deformed every 2nd and 4th update. A switch blends over
// 8 deformed updates. The model is not renumbered (order_points_first), so that the rig's per-point data stays valid:
// the levels deform scattered points, slower than a game's would but the same picture.
void apply_lod(ViewerState& state) {
  state.lod_levels = false;
  state.lod_triangles.clear();
  state.lod_submeshes.clear();
  state.lod_drawn = 0;
  const int bones = state.options.lod_bones;
  if (bones > 0) {
    deform::BoneLodSettings settings;
    settings.bones_per_level = {std::size_t(bones)};
    settings.poses = clip_poses(state);
    const deform::BoneLod lod = deform::build_bone_lod(state.character->model(), settings);
    const std::vector<deform::Character::LevelOptions> options(2);  // deformers on, every update
    state.character->set_levels(lod, options, 0);
    (void)state.character->set_level(1);  // cannot fail: the level exists
    std::fprintf(stderr, "deform_viewer: --lod-bones %d: skinning with %zu of %zu bones\n", bones,
                 lod.levels[1].kept_bones, lod.levels[0].kept_bones);
    return;
  }
  if (state.options.lod < 0 && !state.options.lod_auto) return;
  const std::size_t count = state.character->skeleton().bone_count();
  deform::BoneLodSettings settings;
  settings.bones_per_level = {std::max<std::size_t>(1, (3 * count + 3) / 4), std::max<std::size_t>(1, (count + 1) / 2),
                              std::max<std::size_t>(1, (count + 2) / 3)};
  settings.poses = clip_poses(state);
  std::vector<deform::Character::LevelOptions> options = {{true, 1}, {true, 1}, {false, 2}, {false, 4}};
  state.lod_triangles.resize(4);
  state.lod_submeshes.resize(4);
#if defined(DEFORM_VIEWER_HAVE_SIMPLIFY)
  const std::vector<deform::SimplifySettings> shares = {{0.5f, 0.05f}, {0.25f, 0.05f}, {0.1f, 0.05f}};
  const std::vector<deform::MeshLevel> meshes = deform::simplify_levels(state.character->model(), shares);
  for (std::size_t l = 1; l < 4; ++l) {
    options[l].points = meshes[l - 1].points;  // copied by set_levels
    state.lod_triangles[l] = meshes[l - 1].triangles;
    state.lod_submeshes[l] = meshes[l - 1].submeshes;
  }
#endif
  const deform::BoneLod lod = deform::build_bone_lod(state.character->model(), settings);
  state.character->set_levels(lod, options, 8);
  state.lod_levels = true;
  const deform::Bounds box = deform::compute_bounds(state.character->model().mesh.positions);
  state.lod_centre = 0.5f * (box.min + box.max);
  state.lod_choice = state.options.lod_auto ? -1 : state.options.lod;
  for (std::size_t l = 0; l < 4; ++l) {
    const deform::Character::LevelCost cost = state.character->level_cost(l);
    std::fprintf(stderr,
                 "deform_viewer: --lod: level %zu: %zu bones, %zu points, %zu triangles, every %u update(s)%s\n", l,
                 lod.levels[l].kept_bones, cost.points,
                 state.lod_triangles[l].empty() ? state.character->model().mesh.triangle_count()
                                                : state.lod_triangles[l].size() / 3,
                 unsigned(cost.update_interval), cost.deformers ? ", deformers on" : "");
  }
}

// Everything a new state.character needs around it: the picking triangles and BVH, the renderer, the per-lattice
// and per-target state, the poses, and the panel's settings passed to it.
void adopt_character(ViewerState& state) {
  const deform::Mesh& mesh = state.character->model().mesh;
  state.triangle_points.resize(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    state.triangle_points[i] = mesh.vertex_point[mesh.triangles[i]];
  state.character->update(0.0f);
  state.bvh.build(state.character->positions(), state.triangle_points);
  create_character_renderer(state);
  state.reaching = false;
  state.effector = state.hovered_effector = -1;
  state.lattice_shown.assign(state.character->deformers().lattice_count(), 0);
  state.morph_held.resize(state.character->morph_target_count(), 0);  // kept over rebuilds: the panel's holds stay
  state.morph_hold.resize(state.character->morph_target_count(), 0.0f);
  state.morph_second.resize(state.character->morph_target_count(), 0.0f);
  apply_morph_weights(state);
  state.bind_pose = state.character->skeleton().bind_pose();
  state.pose = state.later = state.first = state.second = state.bind_pose;  // sized once: sample_clip copies into them
  state.cut = true;
  apply_motion(state);
  if (state.max_stretch < 0.0f) state.max_stretch = state.character->rig().max_stretch;
  apply_shape(state);
  apply_reach_settings(state);
  apply_mush(state);
  apply_lod(state);
  set_gpu(state, state.gpu);
}

}  // namespace

void rebuild_character(ViewerState& state) {
  const deform::Rig rig = tuned_rig(state);
  try {
    state.character = std::make_unique<deform::Character>(state.base_model, rig);
  } catch (const deform::Error& e) {
    // A rig made by default_rig() for an unusual model may not bind: the character still reaches, without stretch.
    if (!state.options.rig.empty()) throw;
    std::fprintf(stderr, "warning: %s; reaching without elastic lattices\n", e.what());
    state.rig = deform::Rig{};
    state.character = std::make_unique<deform::Character>(state.base_model, state.rig);
  }
  adopt_character(state);
}

void rebind_weights(ViewerState& state, deform::SkinWeights weights) {
  deform::Model model = state.base_model;
  model.weights = std::move(weights);
  auto character = std::make_unique<deform::Character>(model, tuned_rig(state));  // throws: nothing changed yet
  character->settings = state.character->settings;  // LBS or DQS, the IK's settings, as the panel holds them
  state.base_model = std::move(model);
  state.character = std::move(character);
  adopt_character(state);
}

// The Character's mush stages as the panel holds them: Direct Delta Mush as the skinning (state.ddm) and Delta Mush
// after the lattices (state.mush_iterations). Binding allocates and takes a moment: only when a choice changes. Either
// one turns the GPU deformation off, which has neither.
void apply_mush(ViewerState& state) {
  if (state.ddm && state.character->direct_delta_mush() == nullptr) state.character->set_direct_delta_mush({});
  if (!state.ddm) state.character->clear_direct_delta_mush();
  const unsigned mushed = state.character->delta_mush() ? state.character->delta_mush()->iterations : 0u;
  if (unsigned(state.mush_iterations) != mushed) state.character->set_delta_mush({state.mush_iterations, 0.5f, {}});
  if (state.gpu && (state.ddm || state.mush_iterations > 0)) set_gpu(state, false);
}

// Plays clip `clip` (-1: none, the bind pose) from its start.
void select_clip(ViewerState& state, int clip) {
  const bool refit = state.floor_node >= 0 && camera_fitted(state);  // before the scene exists, the constructor fits
  state.clip = clip;
  state.clip_time = 0.0f;
  place_floor(state);
  if (refit) fit_camera(state);
  if (state.clip < 0) state.character->set_pose(state.bind_pose);
  state.cut = true;
  apply_motion(state);
}

void animate(ViewerState& state, float dt) {
  if (state.clip >= 0) {
    // The pose now and where it heads a millisecond later (paused: nowhere, so the still body gets no velocity);
    // then the reach again, on this frame's pose.
    constexpr float lead = 1e-3f;
    const deform::Animation& clip = state.clips[std::size_t(state.clip)];
    const float rate = state.playing ? state.speed : 0.0f;
    state.clip_time =
        clip.local_time(state.clip_time + dt * rate);  // kept within the clip: a small float stays precise
    sample_clip(state, state.clip_time, state.pose);
    sample_clip(state, state.clip_time + lead * rate, state.later);
    state.character->set_pose(state.pose, state.later, lead);
    // The reach again, on this frame's pose: a reach held so follows its target smoothly (Character::reach).
    if (state.reaching) state.last_reach = state.character->reach(state.effector, state.target);
  }
}

// The morph weights of this frame: the defaults, the playing clip's morph channels at its time (blended with the
// second clip's at the same phase, by the blend weight, as the poses are), then the panel's held weights.
void apply_morph_weights(ViewerState& state) {
  if (!state.character || state.character->morph_target_count() == 0) return;
  state.character->reset_morph_weights();
  if (state.clip >= 0) {
    const deform::Animation& first = state.clips[std::size_t(state.clip)];
    (void)state.character->set_morph_weights(first, state.clip_time);  // cannot fail: the clip was validated on loading
    if (state.blend_clip >= 0) {
      const deform::Animation& second = state.clips[std::size_t(state.blend_clip)];
      const float t2 = first.duration > 0.0f && second.duration > 0.0f
                           ? first.local_time(state.clip_time) / first.duration * second.duration
                           : state.clip_time;
      const std::vector<deform::MorphTarget>& targets = state.character->model().morph_targets;
      for (std::size_t k = 0; k < targets.size(); ++k) state.morph_second[k] = targets[k].default_weight;
      (void)deform::sample_morph_weights(second, t2, state.morph_second);
      for (std::size_t k = 0; k < targets.size(); ++k) {
        const float w = (1.0f - state.blend_weight) * state.character->morph_weights()[k] +
                        state.blend_weight * state.morph_second[k];
        (void)state.character->set_morph_weight(k, w);
      }
    }
  }
  for (std::size_t k = 0; k < state.morph_held.size(); ++k)
    if (state.morph_held[k]) (void)state.character->set_morph_weight(k, state.morph_hold[k]);
}

// The lattices' inertia: the panel's scale of each part's tuned inertia while a clip is chosen and jiggle is on,
// else none, so a reach on a still body is the plain rubber arm. The rig's gravity on the lattices is kept.
void apply_motion(ViewerState& state) {
  state.character->deformers().set_inertia_scale(state.clip >= 0 && state.jiggle ? state.inertia : 0.0f);
}

// The panel's shape for every lattice (DeformerHierarchy::set_shape).
void apply_shape(ViewerState& state) {
  try {
    for (std::size_t i = 0; i < state.character->deformers().lattice_count(); ++i)
      state.character->deformers().set_shape(i, state.shape);
  } catch (const deform::Error& e) {
    std::fprintf(stderr, "warning: %s\n", e.what());
  }
}

// The panel's pole and stretch bound; a reach in progress is solved again with them.
void apply_reach_settings(ViewerState& state) {
  state.character->settings.reach_pole = state.pole;
  state.character->settings.use_reach_pole = state.use_pole;
  state.character->settings.reach_limits = state.reach_limits;
  state.character->settings.reach_solver = state.reach_solver;
  state.character->settings.reach_soften = state.soften;
  state.character->set_max_stretch(state.max_stretch);
  if (state.reaching) state.last_reach = state.character->reach(state.effector, state.target);
}

void apply_elastic(ViewerState& state) {
  for (std::size_t i = 0; i < state.character->deformers().lattice_count(); ++i) {
    deform::ElasticSettings s = state.character->deformers().spec(i).elastic;
    s.oscillator = state.elastic.oscillator;
    s.integrator = state.elastic.integrator;
    if (s.integrator == deform::Integrator::verlet) s.springs = deform::NeighbourSprings{};  // exact only
    state.character->deformers().set_elastic(i, s);
  }
}

void choose_lod(ViewerState& state) {
  if (!state.lod_levels) return;
  std::size_t level = std::size_t(std::max(0, state.lod_choice));
  if (state.lod_choice < 0) {
    // The character's height on screen, from its bind pose's box carried into the world (the model node's turn and
    // scale) and the camera's distance to the box's centre: level 1 below half the window, 2 below a quarter, 3 below
    // an eighth.
    const glm::mat4 world = character_world(state);
    const glm::vec3 centre = transform_point(world, state.lod_centre);
    const float height = (state.rest_bounds.max.y - state.rest_bounds.min.y) * glm::length(glm::vec3(world[1]));
    constexpr float thresholds[] = {0.5f, 0.25f, 0.125f};
    level = deform::pick_level(
        thresholds, deform::screen_height(height, glm::length(state.camera.eye() - centre), state.camera.fov_y));
  }
  (void)state.character->set_level(level);  // cannot fail: the four levels exist
  if (int(level) == state.lod_drawn) return;
  // The level's own triangles for the renderer and the picking: the points outside its mesh keep stale places.
  state.lod_drawn = int(level);
  state.renderer->set_triangles(state.lod_triangles[level], state.lod_submeshes[level]);
  const deform::Mesh& mesh = state.character->model().mesh;
  const std::vector<std::uint32_t>& triangles = drawn_triangles(state);
  state.triangle_points.resize(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) state.triangle_points[i] = mesh.vertex_point[triangles[i]];
  state.bvh.build(state.character->positions(), state.triangle_points);
}

std::string gpu_missing(const ViewerState& state) {
  const int version = epoxy_gl_version();
  return "needs OpenGL 4.3 compute shaders; this context is OpenGL " + std::to_string(version / 10) + "." +
         std::to_string(version % 10) + " (" + state.window.renderer_name() + ")";
}

// The morph weights as applied now, comma-separated (the headless summary).
std::string morph_weights_text(const ViewerState& state) {
  std::string text;
  for (const float w : state.character->morph_weights()) {
    char number[32];
    std::snprintf(number, sizeof number, "%s%.6g", text.empty() ? "" : ", ", double(w));
    text += number;
  }
  return text;
}

}  // namespace viewer
