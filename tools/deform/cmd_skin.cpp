// deform skin: deform a rigged mesh by a pose, LBS, DQS or Direct Delta Mush (docs/cli.md, docs/skinning.md).
#include <algorithm>
#include <cmath>
#include <iostream>

#include "cli.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/model_files.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/pose_json.hpp"
#include "deform/io/text.hpp"
#include "deform/offline/delta_mush.hpp"
#include "deform/offline/direct_delta_mush.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/blending.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/morph.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
#include "model_loader.hpp"

namespace cli {
namespace {

// Skins one stream of the model: `positions` (and `normals` when not empty) with the given per-entry weights (their
// extra influences included).
void skin(deform::SkinningJob job, const deform::SkinWeights& weights, std::span<const glm::vec3> positions,
          std::span<glm::vec3> out_positions, std::span<const glm::vec3> normals, std::span<glm::vec3> out_normals,
          const std::string& source) {
  job.bone_indices = weights.bones;
  job.bone_weights = weights.weights;
  job.extra_vertices = weights.extra_points;
  job.extra_offsets = weights.extra_offsets;
  job.extra_bones = weights.extra_bones;
  job.extra_weights = weights.extra_weights;
  job.in_positions = deform::as_floats(positions);
  job.out_positions = deform::as_floats(out_positions);
  job.in_normals = deform::as_floats(normals);
  job.out_normals = deform::as_floats(out_normals);
  if (!job.validate()) throw deform::Error::in_file(source, "", "the weights do not fit the skeleton or the mesh");
  job.run();
}

// The clips a model offers by name: an import's own, or the built-in character's (builtin_clips). `flag` names the
// option asking, for the message when the model has none (native files carry no clips).
std::vector<deform::Animation> model_clips(const LoadedModel& loaded, const std::string& flag) {
  if (loaded.builtin) return deform::builtin_clips(loaded.model);
  if (!loaded.imported)
    throw UsageError(flag + " needs the built-in character or an imported model (glTF, FBX, .x, ...), not " +
                     loaded.source);
  return loaded.clips;
}

// The clip named `name` among `clips`, or a deform::Error (exit 2) naming the model, the clip and the names there are.
const deform::Animation& named_clip(const std::vector<deform::Animation>& clips, const std::string& name,
                                    const LoadedModel& loaded) {
  const std::int32_t found = deform::find_clip(clips, name);
  if (found >= 0) return clips[static_cast<std::size_t>(found)];
  std::string names;
  for (const deform::Animation& c : clips) names += (names.empty() ? "" : ", ") + ("'" + c.name + "'");
  throw deform::Error::in_file(loaded.source, "clip '" + name + "'",
                               "no clip of that name (" + (names.empty() ? "it has none" : "it has " + names) + ")");
}

// `clip` sampled at `seconds` (clips loop as they say) over the bind pose.
deform::Pose sample_clip(const deform::Animation& clip, float seconds, const LoadedModel& loaded) {
  deform::Pose pose = loaded.model.skeleton.bind_pose();
  deform::SamplingJob sampling;
  sampling.animation = &clip;
  sampling.time = seconds;
  sampling.rotations = pose.rotations;
  sampling.translations = pose.translations;
  if (const deform::Status status = sampling.run(); !status)
    throw deform::Error::in_file(loaded.source, "clip '" + clip.name + "'", status.reason());
  return pose;
}

// The pose of the model's clip NAME at T seconds, over the bind pose.
deform::Pose clip_pose(const Args& args, const LoadedModel& loaded) {
  if (args.has("--pose")) throw UsageError("--clip and --pose exclude each other");
  const std::vector<deform::Animation> clips = model_clips(loaded, "--clip");
  const auto seconds = static_cast<float>(parse_number(args.required("--time"), "--time"));
  return sample_clip(named_clip(clips, args.required("--clip"), loaded), seconds, loaded);
}

// One CLIP:WEIGHT item of --blend.
struct BlendItem {
  std::string clip;
  float weight = 0.0f;
};

// "walk:0.7,run:0.3" -> items. The weight follows the last ':' (a clip name may hold ':'); each must be a finite number
// >= 0 and at most 1e6 (so the sum stays a normal float). UsageError naming the item otherwise.
std::vector<BlendItem> parse_blend(const std::string& text) {
  std::vector<BlendItem> items;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t colon = item.rfind(':');
    if (colon == std::string::npos || colon == 0) throw UsageError("--blend: item '" + item + "' is not CLIP:WEIGHT");
    const double weight = parse_number(item.substr(colon + 1), "--blend: item '" + item + "': weight");
    if (weight < 0.0 || weight > 1e6) throw UsageError("--blend: item '" + item + "': weight must be within [0, 1e6]");
    items.push_back({item.substr(0, colon), static_cast<float>(weight)});
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return items;
}

// The blend of the --blend clips at T seconds (BlendingJob: normalised weights, the bind pose where they sum to less
// than 0.1; docs/animation.md), each clip sampled at the same time.
deform::Pose blend_pose(const Args& args, const LoadedModel& loaded, const std::vector<BlendItem>& items) {
  if (args.has("--pose") || args.has("--clip")) throw UsageError("--blend excludes --pose and --clip");
  const std::vector<deform::Animation> clips = model_clips(loaded, "--blend");
  const auto seconds = static_cast<float>(parse_number(args.required("--time"), "--time"));
  std::vector<deform::Pose> poses;
  poses.reserve(items.size());
  for (const BlendItem& item : items)
    poses.push_back(sample_clip(named_clip(clips, item.clip, loaded), seconds, loaded));
  std::vector<deform::BlendLayer> layers;
  for (std::size_t i = 0; i < items.size(); ++i)
    layers.push_back({poses[i].rotations, poses[i].translations, items[i].weight, {}});
  const deform::Pose bind = loaded.model.skeleton.bind_pose();
  deform::Pose pose = bind;
  deform::BlendingJob job;
  job.layers = layers;
  job.rest_rotations = bind.rotations;
  job.rest_translations = bind.translations;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  if (const deform::Status status = job.validate(); !status)
    throw deform::Error::in_file(loaded.source, "--blend", status.reason());
  job.run();
  return pose;
}

// The point weights carried to render vertices (vertex r gets point vertex_point[r]'s influences, extras too).
deform::SkinWeights vertex_weights_of(const deform::SkinWeights& w, std::span<const std::uint32_t> vertex_point) {
  deform::SkinWeights out;
  out.bones.reserve(vertex_point.size());
  out.weights.reserve(vertex_point.size());
  for (std::size_t r = 0; r < vertex_point.size(); ++r) {
    const std::uint32_t p = vertex_point[r];
    out.bones.push_back(w.bones[p]);
    out.weights.push_back(w.weights[p]);
    const auto it = std::lower_bound(w.extra_points.begin(), w.extra_points.end(), p);
    if (it == w.extra_points.end() || *it != p) continue;
    const auto j = static_cast<std::size_t>(it - w.extra_points.begin());
    if (out.extra_offsets.empty()) out.extra_offsets.push_back(0);
    out.extra_points.push_back(static_cast<std::uint32_t>(r));
    for (std::uint32_t e = w.extra_offsets[j]; e < w.extra_offsets[j + 1]; ++e) {
      out.extra_bones.push_back(w.extra_bones[e]);
      out.extra_weights.push_back(w.extra_weights[e]);
    }
    out.extra_offsets.push_back(static_cast<std::uint32_t>(out.extra_bones.size()));
  }
  return out;
}

// The morph-target weights of the --blend clips at T seconds: each clip's weights (the defaults, then its morph
// channels) averaged with the blend's weights, as BlendingJob averages the poses: normalised by their sum W, and
// below W = 0.1 the defaults join in with weight 0.1 - W (where the bind pose joins the poses).
void blend_morph_weights(const Args& args, const LoadedModel& loaded, const std::vector<BlendItem>& items,
                         std::vector<float>& weights) {
  const auto seconds = static_cast<float>(parse_number(args.required("--time"), "--time"));
  const std::vector<float> defaults = weights;
  std::vector<double> sum(weights.size(), 0.0);
  double total = 0.0;
  for (const BlendItem& item : items) {
    const std::int32_t clip = deform::find_clip(loaded.clips, item.clip);
    std::vector<float> clip_weights = defaults;
    if (clip >= 0)
      if (const deform::Status status =
              deform::sample_morph_weights(loaded.clips[static_cast<std::size_t>(clip)], seconds, clip_weights);
          !status)
        throw deform::Error::in_file(loaded.source, "clip '" + item.clip + "'", status.reason());
    for (std::size_t k = 0; k < weights.size(); ++k) sum[k] += double(item.weight) * double(clip_weights[k]);
    total += double(item.weight);
  }
  constexpr double threshold = 0.1;  // BlendingJob's default, which blend_pose uses
  if (total < threshold) {
    for (std::size_t k = 0; k < weights.size(); ++k) sum[k] += (threshold - total) * double(defaults[k]);
    total = threshold;
  }
  for (std::size_t k = 0; k < weights.size(); ++k) weights[k] = static_cast<float>(sum[k] / total);
}

// The morph-target weights: each target's default, then the clip's morph channels at --time (with --clip; with
// --blend, the clips' weights blended as above), then --morph NAME:W[,NAME:W...] (every target of that name; an
// unknown name is a usage error naming it).
std::vector<float> morph_weights(const Args& args, const LoadedModel& loaded, const std::vector<BlendItem>& blend) {
  const std::vector<deform::MorphTarget>& targets = loaded.model.morph_targets;
  std::vector<float> weights;
  for (const deform::MorphTarget& t : targets) weights.push_back(t.default_weight);
  if (!blend.empty() && !targets.empty()) blend_morph_weights(args, loaded, blend, weights);
  if (args.has("--clip")) {
    const std::int32_t clip = deform::find_clip(loaded.clips, args.required("--clip"));
    const auto seconds = static_cast<float>(parse_number(args.required("--time"), "--time"));
    if (clip >= 0)
      if (const deform::Status status =
              deform::sample_morph_weights(loaded.clips[static_cast<std::size_t>(clip)], seconds, weights);
          !status)
        throw deform::Error::in_file(loaded.source, "clip '" + args.required("--clip") + "'", status.reason());
  }
  if (const auto list = args.value("--morph")) {
    std::size_t at = 0;
    while (at <= list->size()) {
      const std::size_t comma = std::min(list->find(',', at), list->size());
      const std::string item = list->substr(at, comma - at);
      const std::size_t colon = item.rfind(':');
      if (colon == std::string::npos || colon == 0) throw UsageError("--morph: '" + item + "' is not NAME:WEIGHT");
      const std::string name = item.substr(0, colon);
      const auto weight = static_cast<float>(parse_number(item.substr(colon + 1), "--morph " + name));
      if (!std::isfinite(weight))
        throw UsageError("--morph " + name + ": '" + item.substr(colon + 1) + "' is out of float range");
      bool found = false;
      for (std::size_t k = 0; k < targets.size(); ++k)
        if (targets[k].name == name) weights[k] = weight, found = true;
      if (!found)
        throw UsageError("--morph: the model has no morph target '" + name + "'" +
                         (targets.empty() ? std::string(" (it has none)") : std::string()));
      at = comma + 1;
    }
  }
  return weights;
}

// deform skin's options, checked before the model loads so that a bad one fails fast.
struct SkinOptions {
  std::string method_name;  // lbs, dqs or ddm
  bool direct_mush = false;
  bool reduced_mush = false;  // --ddm-variant reduced
  bool animated = false;      // --clip or --blend
  std::string pose_path;      // --pose, when not animated
  std::vector<BlendItem> blend;
  std::string out_path;
  bool limits = true;
  int mush_iterations = 0;  // Delta Mush after skinning: 0 for none
  double mush_step = 0.5;
};

SkinOptions skin_options(const Args& args) {
  SkinOptions o;
  o.method_name = args.value("--method").value_or("lbs");
  if (o.method_name != "lbs" && o.method_name != "dqs" && o.method_name != "ddm")
    throw UsageError("--method: '" + o.method_name + "' is not lbs, dqs or ddm");
  o.direct_mush = o.method_name == "ddm";
  if (const auto variant = args.value("--ddm-variant")) {
    if (!o.direct_mush) throw UsageError("--ddm-variant needs --method ddm");
    if (*variant != "full" && *variant != "reduced")
      throw UsageError("--ddm-variant: '" + *variant + "' is not full or reduced");
    o.reduced_mush = *variant == "reduced";
  }
  o.animated = args.has("--clip") || args.has("--blend");
  o.pose_path = o.animated ? std::string() : args.required("--pose");
  if (args.has("--blend")) o.blend = parse_blend(*args.value("--blend"));
  if (!o.animated && args.has("--time")) throw UsageError("--time needs --clip or --blend");
  o.out_path = args.required("--out");
  o.limits = !args.has("--no-limits");
  o.mush_iterations = static_cast<int>(
      args.has("--mush") ? parse_integer(*args.value("--mush"), "--mush", 0, deform::max_delta_mush_iterations) : 0);
  o.mush_step = args.has("--mush-step") ? parse_number(*args.value("--mush-step"), "--mush-step") : 0.5;
  if (!(o.mush_step > 0.0 && o.mush_step <= 1.0)) throw UsageError("--mush-step: must be within (0, 1]");
  if (args.has("--mush-step") && !args.has("--mush")) throw UsageError("--mush-step needs --mush");
  return o;
}

// The pose's skinning matrices, and for DQS its dual quaternions (and scales, when the pose scales).
struct BonePalette {
  std::vector<glm::mat4> world, palette;
  std::vector<deform::DualQuat> dual_quats;
  std::vector<glm::mat3> scales;
  bool has_scale = false;
};

BonePalette bone_palette(const deform::Skeleton& skeleton, const deform::Pose& pose, bool dqs,
                         const std::string& pose_path) {
  const std::size_t bone_count = skeleton.bone_count();
  BonePalette bones;
  bones.world.resize(bone_count);
  bones.palette.resize(bone_count);
  deform::LocalToWorldJob fk;
  fk.skeleton = &skeleton;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = bones.world;
  fk.palette = bones.palette;
  if (!fk.run()) throw deform::Error::in_file(pose_path, "", "the pose does not fit the skeleton");
  bones.dual_quats.resize(bone_count);
  bones.scales.resize(bone_count);
  if (dqs && !deform::compute_dual_quat_palette(bones.palette, bones.dual_quats, bones.scales, bones.has_scale))
    throw deform::Error::in_file(pose_path, "", "the pose gives a singular bone transform");
  return bones;
}

// The bind points with the morph targets applied at `weights` (in bind space, as glTF and three.js do), and each
// point's normal delta (0 without targets). Refuses weights that move a point beyond float range.
struct MorphedRest {
  std::vector<glm::vec3> positions, normal_deltas;
};

MorphedRest morphed_rest(const LoadedModel& loaded, const std::vector<float>& weights) {
  const deform::Mesh& mesh = loaded.model.mesh;
  MorphedRest rest{mesh.positions, std::vector<glm::vec3>(mesh.point_count(), glm::vec3(0.0f))};
  if (loaded.model.morph_targets.empty()) return rest;
  const std::vector<glm::vec3> zeros(mesh.point_count(), glm::vec3(0.0f));
  deform::MorphJob morph;
  morph.targets = loaded.model.morph_targets;
  morph.weights = weights;
  morph.rest_positions = mesh.positions;
  morph.out_positions = rest.positions;
  morph.rest_normals = zeros;  // the normal deltas alone, added to each render vertex's normal by the caller
  morph.out_normals = rest.normal_deltas;
  if (const deform::Status status = morph.validate(); !status)
    throw deform::Error::in_file(loaded.source, "morph targets", status.reason());
  morph.run();
  for (std::size_t p = 0; p < rest.positions.size(); ++p) {
    const glm::vec3 q = rest.positions[p], n = rest.normal_deltas[p];
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(n.x) ||
        !std::isfinite(n.y) || !std::isfinite(n.z))
      throw deform::Error::in_file(loaded.source, "morph targets",
                                   "the weights move point " + std::to_string(p) + " beyond float range");
  }
  return rest;
}

// The deformed points, and the render vertices' normals (none when the mesh has no normal per render vertex).
struct SkinnedMesh {
  std::vector<glm::vec3> positions;  // one per point
  std::vector<glm::vec3> normals;    // one per render vertex
};

// Direct Delta Mush of the morphed points (each morph offset turned with its point), bound on the rest points; each
// render vertex's normal turns with its point's rotation.
// --ddm-variant reduced: the reduced form (DirectDeltaMushReducedJob), the bones' rotations from the DQS palette.
void direct_delta_mush(const LoadedModel& loaded, const BonePalette& bones, const std::vector<glm::vec3>& rest,
                       const std::vector<glm::vec3>& vertex_normals, bool reduced, SkinnedMesh& out) {
  const deform::Mesh& mesh = loaded.model.mesh;
  const deform::DirectDeltaMushBinding binding = deform::bind_direct_delta_mush(mesh, loaded.model.weights);
  std::vector<glm::quat> rotations(mesh.point_count());
  if (reduced) {
    deform::DirectDeltaMushReducedBinding small;
    std::vector<deform::DualQuat> dual_quats(bones.palette.size());
    std::vector<glm::mat3> scales(bones.palette.size());
    bool has_scale = false;
    deform::DirectDeltaMushReducedJob job;
    job.binding = &small;
    job.matrices = bones.palette;
    job.dual_quats = dual_quats;
    job.in_positions = rest;
    job.out_positions = out.positions;
    job.out_rotations = rotations;
    deform::Status status = deform::reduce_direct_delta_mush(binding, small);
    if (status) status = deform::compute_dual_quat_palette(bones.palette, dual_quats, scales, has_scale);
    if (status) status = job.validate();
    if (!status) throw deform::Error::in_file(loaded.source, "--method ddm", status.reason());
    job.run();
  } else {
    deform::DirectDeltaMushJob ddm;
    ddm.binding = &binding;
    ddm.matrices = bones.palette;
    ddm.in_positions = rest;
    ddm.out_positions = out.positions;
    ddm.out_rotations = rotations;
    if (const deform::Status status = ddm.validate(); !status)
      throw deform::Error::in_file(loaded.source, "--method ddm", status.reason());
    ddm.run();
  }
  for (std::size_t r = 0; r < out.normals.size(); ++r) {
    const glm::vec3 n = rotations[mesh.vertex_point[r]] * vertex_normals[r];
    const float length = glm::length(n);
    out.normals[r] = length > 0.0f ? n / length : glm::vec3(0.0f);
  }
}

// Points (the OBJ's `v`, in order) carry the weights; render vertices carry the normals, so they are skinned with
// their point's weights.
SkinnedMesh skin_mesh(const LoadedModel& loaded, const SkinOptions& o, const BonePalette& bones,
                      const MorphedRest& rest) {
  const deform::Mesh& mesh = loaded.model.mesh;
  const std::size_t render_vertices = mesh.vertex_normals.size() == mesh.vertex_count() ? mesh.vertex_count() : 0;
  SkinnedMesh out{std::vector<glm::vec3>(mesh.point_count()), std::vector<glm::vec3>(render_vertices)};
  std::vector<glm::vec3> vertex_positions(render_vertices), vertex_normals(render_vertices), scratch(render_vertices);
  for (std::size_t r = 0; r < render_vertices; ++r) {
    const std::uint32_t point = mesh.vertex_point[r];
    vertex_positions[r] = rest.positions[point];
    vertex_normals[r] = mesh.vertex_normals[r] + rest.normal_deltas[point];
  }
  if (o.direct_mush) {
    direct_delta_mush(loaded, bones, rest.positions, vertex_normals, o.reduced_mush, out);
    return out;
  }
  deform::SkinningJob job;
  job.method = o.method_name == "dqs" ? deform::SkinningMethod::dqs : deform::SkinningMethod::lbs;
  job.matrices = bones.palette;
  if (job.method == deform::SkinningMethod::dqs) {
    job.dual_quats = bones.dual_quats;
    if (bones.has_scale) job.scales = bones.scales;
  }
  skin(job, loaded.model.weights, rest.positions, out.positions, {}, {}, loaded.source);
  const deform::SkinWeights vertex_weights =
      vertex_weights_of(loaded.model.weights, std::span(mesh.vertex_point).first(render_vertices));
  if (render_vertices > 0)
    skin(job, vertex_weights, vertex_positions, scratch, vertex_normals, out.normals, loaded.source);
  return out;
}

// Delta Mush of the skinned points, bound on the rest points; the normals then come from the mushed surface.
void delta_mush(const LoadedModel& loaded, const SkinOptions& o, SkinnedMesh& skinned) {
  const deform::Mesh& mesh = loaded.model.mesh;
  const deform::DeltaMushBinding binding =
      deform::bind_delta_mush(mesh, {o.mush_iterations, static_cast<float>(o.mush_step), {}});
  std::vector<glm::vec4> mush_scratch(deform::DeltaMushJob::scratch_size(binding));
  deform::DeltaMushJob mush;
  mush.binding = &binding;
  mush.in_positions = skinned.positions;
  mush.out_positions = skinned.positions;
  mush.scratch = mush_scratch;
  if (const deform::Status status = mush.validate(); !status)
    throw deform::Error::in_file(loaded.source, "--mush", status.reason());
  mush.run();
  if (skinned.normals.empty()) return;
  const deform::VertexNormalsBinding normals_binding = deform::bind_vertex_normals(mesh);
  std::vector<glm::vec4> normals_scratch(normals_binding.scratch_size());
  deform::VertexNormalsJob recompute;
  recompute.binding = &normals_binding;
  recompute.positions = skinned.positions;
  recompute.normals = skinned.normals;
  recompute.scratch = normals_scratch;
  if (const deform::Status status = recompute.run(); !status)
    throw deform::Error::in_file(loaded.source, "--mush", status.reason());
}

// stdout: what was skinned, how far it moved, and where it went (docs/cli.md).
void print_skin_report(const LoadedModel& loaded, const SkinOptions& o, const deform::Pose& pose,
                       const SkinnedMesh& skinned) {
  const deform::Skeleton& skeleton = loaded.model.skeleton;
  const deform::Mesh& mesh = loaded.model.mesh;
  const std::size_t bone_count = skeleton.bone_count();
  const deform::Pose bind = skeleton.bind_pose();
  int posed = 0;
  for (std::size_t b = 0; b < bone_count; ++b)
    if (std::abs(glm::dot(pose.rotations[b], bind.rotations[b])) < 1.0f - 1e-7f ||
        pose.translations[b] != bind.translations[b])
      ++posed;
  float max_displacement = 0.0f;
  for (std::size_t i = 0; i < skinned.positions.size(); ++i)
    max_displacement = std::max(max_displacement, glm::length(skinned.positions[i] - mesh.positions[i]));
  const deform::Bounds bounds = deform::compute_bounds(skinned.positions);

  nlohmann::ordered_json out;
  out["method"] = o.method_name;
  out["model"] = loaded.source;
  out["vertices"] = mesh.point_count();
  out["normals"] = skinned.normals.size();
  out["bones"] = bone_count;
  out["bones_posed"] = posed;
  out["limits"] = o.limits;
  out["max_displacement"] = max_displacement;
  out["bounds"] = {{"min", to_json(bounds.min)}, {"max", to_json(bounds.max)}};
  out["kernel"] = deform::isa_name(deform::isa_best());
  if (o.mush_iterations > 0)
    out["mush"] = {{"iterations", o.mush_iterations},
                   {"step", deform::shortest_double(static_cast<float>(o.mush_step))}};
  out["out"] = o.out_path;
  if (!o.blend.empty()) {
    nlohmann::ordered_json items = nlohmann::ordered_json::array();
    for (const BlendItem& item : o.blend)
      items.push_back({{"clip", item.clip}, {"weight", deform::shortest_double(item.weight)}});
    out["blend"] = std::move(items);
  }
  print_json_in_order(out);
}

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = model_value_flags;
  value_flags.insert(value_flags.end(), {"--pose", "--method", "--out", "--clip", "--time", "--blend", "--morph",
                                         "--mush", "--mush-step", "--ddm-variant"});
  std::vector<std::string> switch_flags = model_switch_flags;
  switch_flags.push_back("--no-limits");
  const Args args(argv, value_flags, switch_flags);
  const SkinOptions o = skin_options(args);

  const LoadedModel loaded = load_model(args);
  const deform::Model& model = loaded.model;
  const deform::Pose pose = args.has("--blend")  ? blend_pose(args, loaded, o.blend)
                            : args.has("--clip") ? clip_pose(args, loaded)
                                                 : deform::read_pose_json(o.pose_path, model.skeleton, o.limits);
  const BonePalette bones = bone_palette(model.skeleton, pose, o.method_name == "dqs", o.pose_path);
  const MorphedRest rest = morphed_rest(loaded, morph_weights(args, loaded, o.blend));
  SkinnedMesh skinned = skin_mesh(loaded, o, bones, rest);
  if (o.mush_iterations > 0) delta_mush(loaded, o, skinned);

  // The output names the input's MTL files (relative to its own folder), so it opens with its materials.
  deform::write_obj(
      o.out_path, model.mesh, skinned.positions, skinned.normals,
      {.mtllib = deform::material_libraries_for(loaded.names, o.out_path), .submesh_names = loaded.names.submeshes});
  print_skin_report(loaded, o, pose, skinned);
  return exit_ok;
}

}  // namespace

const Command skin_command = {
    "skin", "deform a mesh by a pose (LBS, DQS or Direct Delta Mush)",
    "usage: deform skin (MESH.obj --skeleton S.sk --weights W.skw | --builtin) --pose P.json\n"
    "                   [--method lbs|dqs|ddm [--ddm-variant full|reduced]]\n"
    "                   [--mush N [--mush-step S]] [--no-limits] --out OUT.obj\n"
    "       deform skin MODEL (--pose P.json | --clip NAME --time T) [--morph NAME:W[,NAME:W...]] ...\n"
    "                   (MODEL: an import: glTF, FBX, .x, ...)\n"
    "       deform skin (--builtin | MODEL) --blend CLIP:WEIGHT[,CLIP:WEIGHT...] --time T ...\n\n"
    "Poses the skeleton (bones not in P.json keep their bind pose; angles clamped into the DOF limits unless\n"
    "--no-limits) and deforms the mesh: linear blend skinning (lbs, default), dual quaternion skinning (dqs) or\n"
    "Direct Delta Mush (ddm: the weights smoothed over the mesh at bind time, a rotation per point; slower to bind,\n"
    "smooth at bent joints, the rest pose exact; docs/skinning.md). --ddm-variant reduced keeps 4 floats an influence\n"
    "instead of 10 and blends the bones' rotations instead of fitting one per point (default full).\n"
    "OUT.obj keeps the input's `v` lines in order and count, its UVs and faces; normals are skinned too.\n"
    "Morph targets (blend shapes) apply before skinning, at their default weights, the clip's animated weights (with\n"
    "--blend, the clips' weights averaged by the blend's weights), or the weights --morph gives by target name\n"
    "(`deform info` lists them).\n"
    "--max-influences N (1 to 16, default 4): influences kept per point from W.skw (`deform weights --max-influences\n"
    "N` writes up to 16).\n"
    "--allow-outside DIR (repeatable): files the model names (MTL, textures, buffers) may also come from DIR; by\n"
    "default only its own folder is read, and a file named elsewhere is refused with exit 2 (docs/security.md).\n"
    "Written atomically. Pose JSON: {\"bones\": {\"NAME\": {\"rotation\": [rx, ry, rz], \"translation\": [x, y, "
    "z]}}}.\n"
    "--clip samples a clip of the model (the built-in character's: idle, walk, run, wave) at T seconds; --blend\n"
    "samples several at T and blends them by weight (>= 0, normalised; below a sum of 0.1 the bind pose joins in).\n"
    "Prints {\"method\", \"model\", \"vertices\", \"normals\", \"bones\", \"bones_posed\", \"limits\",\n"
    "\"max_displacement\", \"bounds\": {\"min\", \"max\"}, \"kernel\", \"out\"}; with --blend also\n"
    "\"blend\": [{\"clip\", \"weight\"}].\n"
    "--mush N (0 to 10000) smooths the skinned points by Delta Mush with N iterations (--mush-step S, (0, 1],\n"
    "default 0.5): bent joints smooth, detail kept; the normals are then recomputed from the mushed points and the\n"
    "summary gains \"mush\": {\"iterations\", \"step\"}.\n",
    run};

}  // namespace cli
