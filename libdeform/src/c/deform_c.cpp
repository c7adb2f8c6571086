// The C API (deform/c/deform.h): each function turns deform::Error and Status into a deform_status plus a per-thread
// message, and never lets a C++ exception cross into C.
#include <algorithm>
#include "deform/c/deform.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/model_files.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/offline/direct_delta_mush.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/skinning.hpp"
#include "deform/version.hpp"

#include "c_character.hpp"

struct deform_ddm {
  deform::DirectDeltaMushBinding binding;
};

struct deform_lattice {
  deform::BezierLattice lattice;
  std::optional<deform::LatticeBinding> binding;
  std::size_t bound_count = 0;
};

namespace {

thread_local std::string last_error;

}  // namespace

namespace deform_c {

deform_status fail(deform_status status, std::string message) {
  try {
    last_error = std::move(message);
  } catch (...) {
    last_error.clear();
  }
  return status;
}

deform_status fail_argument(const char* message) { return fail(DEFORM_ERROR_ARGUMENT, message); }

deform_status adopt(deform::Character character, std::shared_ptr<const CharacterSource> source,
                    deform_character** out) {
  std::unique_ptr<deform_character> handle(
      new deform_character{std::move(character), std::move(source), {}, {}, {}, {}, {}});
  handle->bind = handle->character.skeleton().bind_pose();
  handle->pose = handle->bind;
  handle->later = handle->bind;
  handle->sampled = handle->bind;
  for (const deform::Animation& clip : handle->source->clips) {
    deform::SamplingJob job;
    job.animation = &clip;
    handle->cursors.emplace_back(job.cursor_size(), 0u);
  }
  *out = handle.release();
  return DEFORM_OK;
}

}  // namespace deform_c

using deform_c::adopt;
using deform_c::CharacterSource;
using deform_c::fail;
using deform_c::fail_argument;
using deform_c::guarded;

namespace {

// Copies C arrays (quaternions x, y, z, w; translations) into a pose sized for them.
void stage(deform::Pose& pose, const float* rotations_xyzw, const float* translations) {
  for (std::size_t b = 0; b < pose.rotations.size(); ++b) {
    const float* q = rotations_xyzw + 4 * b;
    pose.rotations[b] = glm::quat(q[3], q[0], q[1], q[2]);
    const float* t = translations + 3 * b;
    pose.translations[b] = glm::vec3(t[0], t[1], t[2]);
  }
}

deform_status refused(const deform::Status& status) {
  return status ? DEFORM_OK : fail(DEFORM_ERROR_REFUSED, status.reason());
}

deform_status adopt(deform::Character character, deform_character** out) {
  return adopt(std::move(character), std::make_shared<const CharacterSource>(), out);
}

bool finite3(const float* v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

}  // namespace

extern "C" {

const char* deform_last_error(void) { return last_error.c_str(); }

const char* deform_version(void) { return DEFORM_VERSION_STRING; }

deform_status deform_character_create_builtin(deform_character** out) {
  if (out == nullptr) return fail_argument("deform_character_create_builtin: out is NULL");
  return guarded([&] {
    deform::Character character = deform::make_builtin_character();
    auto source = std::make_shared<CharacterSource>();
    source->clips = deform::builtin_clips(character.model());
    return adopt(std::move(character), std::move(source), out);
  });
}

deform_status deform_character_load(const char* obj_path, const char* sk_path, const char* skw_path,
                                    const char* rig_path, deform_character** out) {
  return deform_character_load_allowing(obj_path, sk_path, skw_path, rig_path, nullptr, 0, out);
}

deform_status deform_character_load_allowing(const char* obj_path, const char* sk_path, const char* skw_path,
                                             const char* rig_path, const char* const* allow_outside, size_t allow_count,
                                             deform_character** out) {
  if (out == nullptr || obj_path == nullptr || sk_path == nullptr || skw_path == nullptr)
    return fail_argument("deform_character_load: a path or out is NULL");
  if (allow_count > 0 && allow_outside == nullptr)
    return fail_argument("deform_character_load_allowing: allow_outside is NULL with a count above 0");
  for (size_t i = 0; i < allow_count; ++i)
    if (allow_outside[i] == nullptr) return fail_argument("deform_character_load_allowing: a folder is NULL");
  return guarded([&] {
    deform::ReferencePolicy policy;
    for (size_t i = 0; i < allow_count; ++i) policy.allow_outside.emplace_back(allow_outside[i]);
    deform::Model model = deform::load_model(obj_path, sk_path, skw_path, nullptr, deform::max_influences, policy);
    if (rig_path == nullptr) return adopt(deform::Character(std::move(model)), out);  // native files carry no clips
    deform::Rig rig = deform::read_rig_json(rig_path, model.skeleton, model.mesh.point_count());
    return adopt(deform::Character(std::move(model), rig), out);
  });
}

void deform_character_destroy(deform_character* character) { delete character; }

deform_status deform_character_instance(const deform_character* character, deform_character** out) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_instance: NULL argument");
  return guarded([&] { return adopt(character->character.instance(), character->source, out); });
}

void deform_import_options_init(deform_import_options* options) {
  if (options == nullptr) return;
  *options = deform_import_options{};
  options->struct_size = sizeof(deform_import_options);
  options->rig = DEFORM_IMPORT_RIG_NONE;
}

size_t deform_character_warning_count(const deform_character* character) {
  return character != nullptr ? character->source->warnings.size() : 0;
}

const char* deform_character_warning(const deform_character* character, size_t warning) {
  if (character == nullptr || warning >= character->source->warnings.size()) return nullptr;
  return character->source->warnings[warning].c_str();
}

size_t deform_character_clip_count(const deform_character* character) {
  return character != nullptr ? character->source->clips.size() : 0;
}

const char* deform_character_clip_name(const deform_character* character, size_t clip) {
  if (character == nullptr || clip >= character->source->clips.size()) return nullptr;
  return character->source->clips[clip].name.c_str();
}

float deform_character_clip_duration(const deform_character* character, size_t clip) {
  if (character == nullptr || clip >= character->source->clips.size()) return 0.0f;
  return character->source->clips[clip].duration;
}

int deform_character_clip_loops(const deform_character* character, size_t clip) {
  if (character == nullptr || clip >= character->source->clips.size()) return 0;
  return character->source->clips[clip].loop ? 1 : 0;
}

int32_t deform_character_find_clip(const deform_character* character, const char* name) {
  if (character == nullptr || name == nullptr) return -1;
  const std::vector<deform::Animation>& clips = character->source->clips;
  for (std::size_t c = 0; c < clips.size(); ++c)
    if (clips[c].name == name) return static_cast<int32_t>(c);
  return -1;
}

deform_status deform_character_sample_clip(deform_character* character, size_t clip, float seconds,
                                           float* rotations_xyzw, float* translations, size_t bone_count) {
  if (character == nullptr || rotations_xyzw == nullptr || translations == nullptr)
    return fail_argument("deform_character_sample_clip: a handle or array is NULL");
  if (clip >= character->source->clips.size()) return fail_argument("deform_character_sample_clip: clip out of range");
  if (bone_count != character->bind.rotations.size())
    return fail_argument("deform_character_sample_clip: bone_count differs from the skeleton's");
  // The bind pose, then the clip's bones over it (SamplingJob writes the bones it animates), staged in the handle:
  // a refusal writes nothing into the caller's arrays.
  deform::Pose& pose = character->sampled;
  std::copy(character->bind.rotations.begin(), character->bind.rotations.end(), pose.rotations.begin());
  std::copy(character->bind.translations.begin(), character->bind.translations.end(), pose.translations.begin());
  deform::SamplingJob job;
  job.animation = &character->source->clips[clip];
  job.time = seconds;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.cursor = character->cursors[clip];
  if (const deform::Status status = job.run(); !status) return refused(status);
  for (std::size_t b = 0; b < bone_count; ++b) {
    const glm::quat& q = pose.rotations[b];
    const glm::vec3& t = pose.translations[b];
    float* r = rotations_xyzw + 4 * b;
    r[0] = q.x, r[1] = q.y, r[2] = q.z, r[3] = q.w;
    float* o = translations + 3 * b;
    o[0] = t.x, o[1] = t.y, o[2] = t.z;
  }
  return DEFORM_OK;
}

size_t deform_character_point_count(const deform_character* character) {
  return character ? character->character.model().mesh.point_count() : 0;
}

size_t deform_character_bone_count(const deform_character* character) {
  return character ? character->character.skeleton().bone_count() : 0;
}

int32_t deform_character_find_bone(const deform_character* character, const char* name) {
  if (character == nullptr || name == nullptr) return -1;
  return character->character.skeleton().find(name);
}

deform_status deform_character_set_pose(deform_character* character, const float* rotations_xyzw,
                                        const float* translations, size_t bone_count) {
  if (character == nullptr || rotations_xyzw == nullptr || translations == nullptr)
    return fail_argument("deform_character_set_pose: a handle or array is NULL");
  if (bone_count != character->pose.rotations.size())
    return fail_argument("deform_character_set_pose: bone_count differs from the skeleton's");
  stage(character->pose, rotations_xyzw, translations);
  return refused(character->character.set_pose(character->pose));
}

deform_status deform_character_set_pose_moving(deform_character* character, const float* rotations_xyzw,
                                               const float* translations, const float* later_rotations_xyzw,
                                               const float* later_translations, float lead, size_t bone_count) {
  if (character == nullptr || rotations_xyzw == nullptr || translations == nullptr || later_rotations_xyzw == nullptr ||
      later_translations == nullptr)
    return fail_argument("deform_character_set_pose_moving: a handle or array is NULL");
  if (bone_count != character->pose.rotations.size())
    return fail_argument("deform_character_set_pose_moving: bone_count differs from the skeleton's");
  stage(character->pose, rotations_xyzw, translations);
  stage(character->later, later_rotations_xyzw, later_translations);
  return refused(character->character.set_pose(character->pose, character->later, lead));
}

deform_status deform_character_bind_pose(const deform_character* character, float* rotations_xyzw, float* translations,
                                         size_t bone_count) {
  if (character == nullptr || rotations_xyzw == nullptr || translations == nullptr)
    return fail_argument("deform_character_bind_pose: a handle or array is NULL");
  const deform::Skeleton& skeleton = character->character.skeleton();
  if (bone_count != skeleton.bone_count())
    return fail_argument("deform_character_bind_pose: bone_count differs from the skeleton's");
  for (std::size_t b = 0; b < bone_count; ++b) {
    const deform::Bone& bone = skeleton.bones()[b];
    const glm::quat q = deform::quat_from_euler(bone.bind_rotation);
    const float rotation[4] = {q.x, q.y, q.z, q.w};
    const float translation[3] = {bone.bind_translation.x, bone.bind_translation.y, bone.bind_translation.z};
    std::copy(rotation, rotation + 4, rotations_xyzw + 4 * b);
    std::copy(translation, translation + 3, translations + 3 * b);
  }
  return DEFORM_OK;
}

size_t deform_character_lattice_count(const deform_character* character) {
  return character != nullptr ? character->character.deformers().lattice_count() : 0;
}

size_t deform_character_spring_chain_count(const deform_character* character) {
  return character != nullptr ? character->character.springs().chain_count() : 0;
}

deform_status deform_character_set_lattice_motion(deform_character* character, size_t lattice, float inertia,
                                                  const float gravity[3], float units_per_metre) {
  if (character == nullptr) return fail_argument("deform_character_set_lattice_motion: the handle is NULL");
  deform::DeformerHierarchy& lattices = character->character.deformers();
  const bool all = lattice == DEFORM_ALL_LATTICES;
  if (!all && lattice >= lattices.lattice_count())
    return fail_argument("deform_character_set_lattice_motion: lattice out of range");
  // Inertia and gravity change; each lattice keeps its own along-bone bound and far-face share (its part's tuning).
  // For every lattice `inertia` scales each one's tuned inertia, its part's (scaled_inertia: 1 the tuned jiggle);
  // for one lattice it is that lattice's inertia.
  const auto with = [&](deform::LatticeMotion motion) {
    motion.inertia = all ? deform::scaled_inertia(motion.part, inertia) : inertia;
    motion.gravity = gravity != nullptr ? glm::vec3(gravity[0], gravity[1], gravity[2]) : glm::vec3(0.0f);
    motion.units_per_metre = units_per_metre;
    return motion;
  };
  return guarded([&] {
    for (std::size_t l = all ? 0 : lattice; l < (all ? lattices.lattice_count() : lattice + 1); ++l)
      deform::require_valid_motion(with(lattices.spec(l).motion));  // before any lattice changes
    for (std::size_t l = all ? 0 : lattice; l < (all ? lattices.lattice_count() : lattice + 1); ++l)
      lattices.set_motion(l, with(lattices.spec(l).motion));
    return DEFORM_OK;
  });
}

deform_status deform_character_set_delta_mush(deform_character* character, int iterations, float step,
                                              const float* mask, size_t mask_count) {
  if (character == nullptr) return fail_argument("deform_character_set_delta_mush: the handle is NULL");
  if (mask == nullptr && mask_count != 0)
    return fail_argument("deform_character_set_delta_mush: mask is NULL with a nonzero count");
  return guarded([&] {
    deform::DeltaMushSettings settings;
    settings.iterations = iterations;
    settings.step = step;
    if (mask != nullptr) settings.mask = std::span<const float>(mask, mask_count);
    character->character.set_delta_mush(settings);  // throws deform::Error (argument), changing nothing
    return DEFORM_OK;
  });
}

namespace {

deform_status set_direct_delta_mush(deform_character* character, int iterations, float step,
                                    deform::DirectDeltaMushVariant variant) {
  return guarded([&] {
    if (iterations == 0) {
      character->character.clear_direct_delta_mush();
      return DEFORM_OK;
    }
    deform::DirectDeltaMushSettings settings;
    settings.iterations = iterations;
    settings.step = step;
    settings.variant = variant;
    character->character.set_direct_delta_mush(settings);  // throws deform::Error (argument), changing nothing
    return DEFORM_OK;
  });
}

}  // namespace

deform_status deform_character_set_direct_delta_mush(deform_character* character, int iterations, float step) {
  if (character == nullptr) return fail_argument("deform_character_set_direct_delta_mush: the handle is NULL");
  return set_direct_delta_mush(character, iterations, step, deform::DirectDeltaMushVariant::full);
}

deform_status deform_character_set_direct_delta_mush_reduced(deform_character* character, int iterations, float step) {
  if (character == nullptr) return fail_argument("deform_character_set_direct_delta_mush_reduced: the handle is NULL");
  return set_direct_delta_mush(character, iterations, step, deform::DirectDeltaMushVariant::reduced);
}

deform_status deform_character_reach(deform_character* character, int32_t effector, const float target[3],
                                     deform_reach_result* result) {
  if (character == nullptr || target == nullptr)
    return fail_argument("deform_character_reach: a handle or target is NULL");
  const deform::ReachResult reached = character->character.reach(effector, glm::vec3(target[0], target[1], target[2]));
  if (!reached.status) return refused(reached.status);
  if (result != nullptr) *result = {reached.residual, reached.stretch, reached.distance, reached.iterations};
  return DEFORM_OK;
}

void deform_character_release(deform_character* character) {
  if (character != nullptr) character->character.release();
}

deform_status deform_character_update(deform_character* character, float dt) {
  if (character == nullptr) return fail_argument("deform_character_update: the handle is NULL");
  return refused(character->character.update(dt));
}

const float* deform_character_positions(const deform_character* character) {
  if (character == nullptr) return nullptr;
  return &character->character.positions().data()->x;
}

size_t deform_character_morph_target_count(const deform_character* character) {
  return character != nullptr ? character->character.morph_target_count() : 0;
}

const char* deform_character_morph_target_name(const deform_character* character, size_t target) {
  if (character == nullptr || target >= character->character.model().morph_targets.size()) return nullptr;
  return character->character.model().morph_targets[target].name.c_str();
}

deform_status deform_character_morph_weights(const deform_character* character, float* out, size_t capacity) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_morph_weights: NULL argument");
  const std::span<const float> weights = character->character.morph_weights();
  if (capacity < weights.size())
    return fail_argument("deform_character_morph_weights: capacity is less than morph_target_count");
  std::copy(weights.begin(), weights.end(), out);
  return DEFORM_OK;
}

deform_status deform_character_set_morph_weight(deform_character* character, size_t target, float weight) {
  if (character == nullptr) return fail_argument("deform_character_set_morph_weight: the handle is NULL");
  if (const deform::Status set = character->character.set_morph_weight(target, weight); !set) return refused(set);
  return DEFORM_OK;
}

deform_status deform_character_set_morph_weight_named(deform_character* character, const char* name, float weight) {
  if (character == nullptr || name == nullptr)
    return fail_argument("deform_character_set_morph_weight_named: NULL argument");
  if (const deform::Status set = character->character.set_morph_weight(std::string_view(name), weight); !set)
    return refused(set);
  return DEFORM_OK;
}

size_t deform_character_pose_driver_count(const deform_character* character) {
  return character != nullptr ? character->character.pose_driver_count() : 0;
}

deform_status deform_character_copy_positions(const deform_character* character, float* out, size_t capacity) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_copy_positions: NULL argument");
  const std::span<const glm::vec3> positions = character->character.positions();
  if (capacity < 3 * positions.size())
    return fail_argument("deform_character_copy_positions: capacity is less than point_count * 3");
  for (const glm::vec3& p : positions) *out++ = p.x, *out++ = p.y, *out++ = p.z;
  return DEFORM_OK;
}

size_t deform_character_vertex_count(const deform_character* character) {
  return character != nullptr ? character->character.model().mesh.vertex_count() : 0;
}

const uint32_t* deform_character_vertex_points(const deform_character* character) {
  return character != nullptr ? character->character.model().mesh.vertex_point.data() : nullptr;
}

size_t deform_character_triangle_count(const deform_character* character) {
  return character != nullptr ? character->character.model().mesh.triangle_count() : 0;
}

const uint32_t* deform_character_triangles(const deform_character* character) {
  return character != nullptr ? character->character.model().mesh.triangles.data() : nullptr;
}

const float* deform_character_uvs(const deform_character* character) {
  if (character == nullptr || character->character.model().mesh.vertex_uvs.empty()) return nullptr;
  return &character->character.model().mesh.vertex_uvs.data()->x;
}

const float* deform_character_normals(deform_character* character) {
  if (character == nullptr) return nullptr;
  return &character->character.normals().data()->x;
}

deform_status deform_character_set_levels(deform_character* character, const deform_level* levels, size_t level_count,
                                          const float* pose_rotations_xyzw, const float* pose_translations,
                                          size_t pose_count, uint32_t blend_frames) {
  if (character == nullptr || (levels == nullptr && level_count > 0) ||
      (pose_count > 0 && (pose_rotations_xyzw == nullptr || pose_translations == nullptr)))
    return fail_argument("deform_character_set_levels: NULL argument");
  if (level_count == 0) return fail_argument("deform_character_set_levels: no level (level 0 is the whole character)");
  return guarded([&] {
    deform::Character& c = character->character;
    const std::size_t bones = c.skeleton().bone_count();
    deform::BoneLodSettings settings;
    for (std::size_t l = 1; l < level_count; ++l) settings.bones_per_level.push_back(levels[l].bones);
    deform::Pose pose = c.skeleton().bind_pose();
    for (std::size_t k = 0; k < pose_count; ++k) {
      stage(pose, pose_rotations_xyzw + 4 * bones * k, pose_translations + 3 * bones * k);
      settings.poses.push_back(pose);
    }
    std::vector<deform::Character::LevelOptions> options(level_count);
    for (std::size_t l = 0; l < level_count; ++l) {
      if (levels[l].points == nullptr && levels[l].point_count > 0)
        return fail_argument(
            ("deform_character_set_levels: level " + std::to_string(l) + ": points is NULL and point_count is not 0")
                .c_str());
      options[l].deformers = levels[l].deformers != 0;
      options[l].update_interval = levels[l].update_interval;
      options[l].points = std::span<const std::uint32_t>(levels[l].points, levels[l].point_count);
    }
    // A single level: the whole character, which build_bone_lod makes from an empty list it would refuse.
    deform::BoneLod lod;
    if (level_count > 1) {
      lod = deform::build_bone_lod(c.model(), settings);
    } else {
      settings.weight_error = {0.0f};
      lod = deform::build_bone_lod(c.model(), settings);
      lod.levels.resize(1);
    }
    c.set_levels(lod, options, blend_frames);
    return DEFORM_OK;
  });
}

size_t deform_character_level_count(const deform_character* character) {
  return character != nullptr ? character->character.level_count() : 0;
}

size_t deform_character_level(const deform_character* character) {
  return character != nullptr ? character->character.level() : 0;
}

deform_status deform_character_set_level(deform_character* character, size_t level) {
  if (character == nullptr) return fail_argument("deform_character_set_level: character is NULL");
  return refused(character->character.set_level(level));
}

int deform_character_next_update_deforms(const deform_character* character) {
  return character != nullptr && character->character.next_update_deforms() ? 1 : 0;
}

deform_status deform_character_level_cost(const deform_character* character, size_t level, deform_level_cost* out) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_level_cost: NULL argument");
  if (level >= character->character.level_count())
    return fail_argument("deform_character_level_cost: level out of range");
  const deform::Character::LevelCost cost = character->character.level_cost(level);
  *out = deform_level_cost{cost.points, cost.influences, cost.bones, cost.deformers ? 1 : 0, cost.update_interval};
  return DEFORM_OK;
}

float deform_screen_height(float extent, float distance, float vertical_fov) {
  return deform::screen_height(extent, distance, vertical_fov);
}

size_t deform_pick_level(const float* thresholds, size_t count, float height) {
  if (thresholds == nullptr) return 0;
  return deform::pick_level(std::span<const float>(thresholds, count), height);
}

deform_status deform_character_bone_position(const deform_character* character, int32_t bone, float out[3]) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_bone_position: NULL argument");
  if (bone < 0 || std::size_t(bone) >= character->character.skeleton().bone_count())
    return fail_argument("deform_character_bone_position: bone out of range");
  const glm::vec3 p = character->character.bone_position(bone);
  out[0] = p.x, out[1] = p.y, out[2] = p.z;
  return DEFORM_OK;
}

float deform_character_stretch(const deform_character* character) {
  return character ? character->character.stretch() : 0.0f;
}

deform_status deform_character_set_deform_on_cpu(deform_character* character, int on) {
  if (character == nullptr) return fail_argument("deform_character_set_deform_on_cpu: the handle is NULL");
  character->character.settings.deform_on_cpu = on != 0;
  return DEFORM_OK;
}

const float* deform_character_palette(const deform_character* character) {
  if (character == nullptr) {
    fail_argument("deform_character_palette: the handle is NULL");
    return nullptr;
  }
  return reinterpret_cast<const float*>(character->character.palette().data());
}

deform_status deform_character_skin_bind(const deform_character* character, deform_skin_bind* out) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_skin_bind: NULL argument");
  const deform::Model& model = character->character.model();
  const deform::SkinWeights& skin = model.weights;
  if (skin.has_extra())
    return guarded([&] {
      return fail(DEFORM_ERROR_REFUSED, "deform_character_skin_bind: " + std::to_string(skin.extra_points.size()) +
                                            " points have more than four influences, which four slots cannot hold");
    });
  // GLM's vector types are plain arrays of their components, as the header's layout promises.
  *out = deform_skin_bind{model.mesh.point_count(), reinterpret_cast<const float*>(model.mesh.positions.data()),
                          reinterpret_cast<const float*>(character->character.bind_normals().data()),
                          reinterpret_cast<const std::uint16_t*>(skin.bones.data()),
                          reinterpret_cast<const float*>(skin.weights.data())};
  return DEFORM_OK;
}

deform_status deform_character_lattice_binding(const deform_character* character, size_t lattice,
                                               deform_lattice_binding* out) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_lattice_binding: NULL argument");
  const deform::DeformerHierarchy& lattices = character->character.deformers();
  if (lattice >= lattices.lattice_count())
    return fail_argument("deform_character_lattice_binding: lattice out of range");
  // The hierarchy's own binding (one lane per bound point, 16-lane blocks): handed out as it is, so that instances
  // share it and nothing is copied.
  const deform::LatticeBinding& binding = lattices.binding(lattice);
  const glm::ivec3 degree = binding.point_counts - 1;
  const std::span<const std::uint32_t> carried = lattices.carried_points(lattice);
  *out = deform_lattice_binding{{degree.x, degree.y, degree.z},
                                binding.control_point_count(),
                                binding.vertex_count,
                                binding.vertices.size(),
                                binding.vertices.data(),
                                binding.u.data(),
                                binding.v.data(),
                                binding.w.data(),
                                lattices.bound_weights(lattice).data(),
                                carried.size(),
                                carried.data(),
                                lattices.carried_weights(lattice).data()};
  return DEFORM_OK;
}

deform_status deform_character_lattice_frame(const deform_character* character, size_t lattice,
                                             deform_lattice_frame* out) {
  if (character == nullptr || out == nullptr) return fail_argument("deform_character_lattice_frame: NULL argument");
  const deform::DeformerHierarchy& lattices = character->character.deformers();
  if (lattice >= lattices.lattice_count()) return fail_argument("deform_character_lattice_frame: lattice out of range");
  // A level that did not run the lattices left the hierarchy's state as an earlier update had it: nothing to add.
  const glm::vec3 far = lattices.far_displacement(lattice);
  *out = deform_lattice_frame{character->character.lattices_ran() && lattices.active(lattice) ? 1 : 0,
                              reinterpret_cast<const float*>(lattices.displacements(lattice).data()),
                              {far.x, far.y, far.z}};
  return DEFORM_OK;
}

deform_status deform_skin_lbs(const float* palette, size_t bone_count, const uint16_t* bones, const float* weights,
                              const float* positions, size_t vertex_count, float* out) {
  if (palette == nullptr || bones == nullptr || weights == nullptr || positions == nullptr || out == nullptr)
    return fail_argument("deform_skin_lbs: an array is NULL");
  // GLM's matrix and vector types are plain arrays of their components, as the header's layout promises.
  deform::SkinningJob job;
  job.method = deform::SkinningMethod::lbs;
  job.matrices = {reinterpret_cast<const glm::mat4*>(palette), bone_count};
  job.bone_indices = {reinterpret_cast<const glm::u16vec4*>(bones), vertex_count};
  job.bone_weights = {reinterpret_cast<const glm::vec4*>(weights), vertex_count};
  job.in_positions = {positions, 3 * vertex_count};
  job.out_positions = {out, 3 * vertex_count};
  if (const deform::Status valid = job.validate(); !valid) return refused(valid);
  return refused(job.run());
}

deform_status deform_ddm_create(const float* positions, size_t point_count, const uint32_t* triangles,
                                size_t triangle_count, const uint16_t* bones, const float* weights, int iterations,
                                float step, deform_ddm** out) {
  if (out == nullptr) return fail_argument("deform_ddm_create: out is NULL");
  *out = nullptr;
  if ((point_count > 0 && (positions == nullptr || bones == nullptr || weights == nullptr)) ||
      (triangle_count > 0 && triangles == nullptr))
    return fail_argument("deform_ddm_create: an array is NULL");
  return guarded([&] {
    deform::Mesh mesh;
    mesh.positions.assign(reinterpret_cast<const glm::vec3*>(positions),
                          reinterpret_cast<const glm::vec3*>(positions) + point_count);
    mesh.vertex_point.resize(point_count);
    for (std::size_t i = 0; i < point_count; ++i) mesh.vertex_point[i] = static_cast<std::uint32_t>(i);
    mesh.triangles.assign(triangles, triangles + 3 * triangle_count);
    deform::SkinWeights skin;
    skin.bones.assign(reinterpret_cast<const glm::u16vec4*>(bones),
                      reinterpret_cast<const glm::u16vec4*>(bones) + point_count);
    skin.weights.assign(reinterpret_cast<const glm::vec4*>(weights),
                        reinterpret_cast<const glm::vec4*>(weights) + point_count);
    deform::DirectDeltaMushSettings settings;
    if (iterations != 0) settings.iterations = iterations;
    if (step != 0.0f) settings.step = step;
    *out = new deform_ddm{deform::bind_direct_delta_mush(mesh, skin, settings)};
    return DEFORM_OK;
  });
}

void deform_ddm_destroy(deform_ddm* ddm) { delete ddm; }

size_t deform_ddm_point_count(const deform_ddm* ddm) { return ddm == nullptr ? 0 : ddm->binding.point_count(); }

deform_status deform_ddm_skin(const deform_ddm* ddm, const float* palette, size_t bone_count, float* out,
                              const float* normals, float* out_normals) {
  if (ddm == nullptr || palette == nullptr || out == nullptr) return fail_argument("deform_ddm_skin: NULL argument");
  if ((normals == nullptr) != (out_normals == nullptr))
    return fail_argument("deform_ddm_skin: normals and out_normals must both be given or both be NULL");
  const std::size_t n = ddm->binding.point_count();
  deform::DirectDeltaMushJob job;
  job.binding = &ddm->binding;
  job.matrices = {reinterpret_cast<const glm::mat4*>(palette), bone_count};
  job.out_positions = {reinterpret_cast<glm::vec3*>(out), n};
  if (normals != nullptr) {
    job.in_normals = {reinterpret_cast<const glm::vec3*>(normals), n};
    job.out_normals = {reinterpret_cast<glm::vec3*>(out_normals), n};
  }
  if (const deform::Status valid = job.validate(); !valid) return refused(valid);
  return refused(job.run());
}

deform_status deform_lattice_create(const float origin[3], const float size[3], int degree_u, int degree_v,
                                    int degree_w, deform_lattice** out) {
  if (origin == nullptr || size == nullptr || out == nullptr)
    return fail_argument("deform_lattice_create: NULL argument");
  if (!finite3(origin) || !finite3(size)) return fail_argument("deform_lattice_create: origin or size is not finite");
  if (!(size[0] > 0.0f && size[1] > 0.0f && size[2] > 0.0f))
    return fail_argument("deform_lattice_create: size is not positive on every axis");
  for (const int degree : {degree_u, degree_v, degree_w})
    if (degree < 1 || degree > deform::max_bezier_degree)
      return fail_argument("deform_lattice_create: a degree is outside [1, 16]");
  return guarded([&] {
    const deform::LatticeFrame frame =
        deform::LatticeFrame::axis_aligned({origin[0], origin[1], origin[2]}, {size[0], size[1], size[2]});
    *out = new deform_lattice{deform::BezierLattice(frame, glm::ivec3(degree_u, degree_v, degree_w)), {}, 0};
    return DEFORM_OK;
  });
}

void deform_lattice_destroy(deform_lattice* lattice) { delete lattice; }

float* deform_lattice_control_points(deform_lattice* lattice, size_t* count) {
  if (lattice == nullptr) return nullptr;
  const std::span<glm::vec3> points = lattice->lattice.control_points();
  if (count != nullptr) *count = points.size();
  return &points.data()->x;
}

deform_status deform_lattice_bind(deform_lattice* lattice, const float* points, size_t count) {
  if (lattice == nullptr || (points == nullptr && count > 0))
    return fail_argument("deform_lattice_bind: NULL argument");
  return guarded([&] {
    lattice->binding = deform::bind_lattice(lattice->lattice, {reinterpret_cast<const glm::vec3*>(points), count});
    lattice->bound_count = count;
    return DEFORM_OK;
  });
}

deform_status deform_lattice_evaluate(const deform_lattice* lattice, float* out, size_t count) {
  if (lattice == nullptr || out == nullptr) return fail_argument("deform_lattice_evaluate: NULL argument");
  if (!lattice->binding) return fail_argument("deform_lattice_evaluate: no points are bound (deform_lattice_bind)");
  if (count != lattice->bound_count)
    return fail_argument("deform_lattice_evaluate: count differs from the bound count");
  deform::LatticeEvaluateJob job;
  job.binding = &*lattice->binding;
  job.control_points = lattice->lattice.control_points();
  job.positions = {reinterpret_cast<glm::vec3*>(out), count};
  if (lattice->binding->vertex_count == 0) return DEFORM_OK;
  return refused(job.run());
}

}  // extern "C"
