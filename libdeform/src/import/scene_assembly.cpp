// The stages the importers share once their format is read (scene_assembly.hpp).
#include "scene_assembly.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"
namespace deform::import_detail {

namespace fs = std::filesystem;

std::vector<bool> skeleton_nodes(const std::vector<std::int32_t>& parents, const std::vector<bool>& needed,
                                 std::int32_t stop) {
  std::vector<bool> in_skeleton(parents.size(), false);
  for (std::size_t i = 0; i < parents.size(); ++i)
    if (needed[i])
      for (auto n = static_cast<std::int32_t>(i); n >= 0 && !in_skeleton[static_cast<std::size_t>(n)];
           n = n == stop ? -1 : parents[static_cast<std::size_t>(n)])
        in_skeleton[static_cast<std::size_t>(n)] = true;
  return in_skeleton;
}

ForestBones bones_of_forest(const std::vector<std::string>& names, const std::vector<std::int32_t>& parents,
                            std::size_t& shortened) {
  ForestBones out;
  const auto tops = static_cast<std::size_t>(std::count(parents.begin(), parents.end(), -1));
  if (names.empty() || tops > 1) {
    Bone root;
    root.name = "root";
    out.bones.push_back(root);
    out.first = names.empty() ? 0 : 1;
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    Bone bone;
    bone.name = fit_name(names[i], shortened);
    bone.parent = parents[i] < 0 ? (out.first == 1 ? 0 : -1) : out.first + parents[i];
    out.bones.push_back(std::move(bone));
  }
  return out;
}

void warn_shortened_names(std::size_t shortened, std::vector<std::string>& warnings) {
  if (shortened > 0)
    warnings.push_back(std::to_string(shortened) + " bone names longer than 79 bytes shortened to fit .sk");
}

void require_bone_count(std::size_t bones, const std::string& path) {
  if (bones > 65535) throw Error::in_file(path, "", std::to_string(bones) + " bones (at most 65535)");
}

std::string unique_material_name(std::string raw, std::size_t index, std::vector<std::string>& used) {
  for (char& c : raw)
    if (std::isspace(static_cast<unsigned char>(c)) || static_cast<unsigned char>(c) < 0x20) c = '_';
  if (raw.empty() || std::find(used.begin(), used.end(), raw) != used.end()) raw = "material" + std::to_string(index);
  used.push_back(raw);
  return raw;
}

std::string unique_clip_name(std::string raw, std::size_t index, std::vector<std::string>& used) {
  if (raw.empty() || std::find(used.begin(), used.end(), raw) != used.end()) raw = "clip" + std::to_string(index);
  used.push_back(raw);
  return raw;
}

std::string referenced_texture(const std::string& path, std::string texture, const std::string& element,
                               const ReferencePolicy& policy, const std::string& material,
                               std::vector<std::string>& warnings) {
  std::replace(texture.begin(), texture.end(), '\\', '/');
  const std::string real = resolve_referenced_file(path, texture, element, policy);
  fs::path resolved = utf8_path::from_utf8(texture);
  if (resolved.is_relative()) resolved = utf8_path::from_utf8(path).parent_path() / resolved;
  std::string map = utf8_path::to_utf8(resolved.lexically_normal());
  std::error_code error;
  if (!fs::is_regular_file(utf8_path::from_utf8(real), error))
    warnings.push_back("material '" + material + "': texture '" + map + "' not found");
  return map;
}

std::pair<std::uint32_t, bool> PointMerger::add(glm::vec3 position, std::span<const Influence> influences,
                                                std::span<const glm::vec3> morph_deltas, std::uint32_t first_target) {
  Influences slots;
  for (std::size_t k = 0; k < influences.size() && k < 4; ++k) {
    slots.bones[k] = influences[k].bone;
    slots.weights[k] = influences[k].weight;
  }
  std::uint32_t word = 0;
  if (influences.size() > 4 || !morph_deltas.empty()) {
    for (std::size_t k = 4; k < influences.size(); ++k) extra_ids_.add(influences[k].bone, influences[k].weight);
    extra_ids_.separate();  // the extras' pairs end here: a list of extras and one of deltas never read alike
    if (!morph_deltas.empty()) extra_ids_.add_word(first_target);
    for (const glm::vec3& d : morph_deltas) extra_ids_.add(d);
    word = extra_ids_.take();
  }
  const auto [found, inserted] =
      point_of_key_.emplace(point_key(position, slots, word), static_cast<std::uint32_t>(positions_.size()));
  if (!inserted) return {found->second, false};
  const auto point = static_cast<std::uint32_t>(positions_.size());
  positions_.push_back(position);
  weights_.bones.emplace_back(slots.bones[0], slots.bones[1], slots.bones[2], slots.bones[3]);
  weights_.weights.emplace_back(slots.weights[0], slots.weights[1], slots.weights[2], slots.weights[3]);
  if (influences.size() > 4) {
    if (weights_.extra_offsets.empty()) weights_.extra_offsets.push_back(0);
    weights_.extra_points.push_back(point);
    for (std::size_t k = 4; k < influences.size(); ++k) {
      weights_.extra_bones.push_back(influences[k].bone);
      weights_.extra_weights.push_back(influences[k].weight);
    }
    weights_.extra_offsets.push_back(static_cast<std::uint32_t>(weights_.extra_bones.size()));
  }
  return {point, true};
}

void close_triangle_faces(Mesh& mesh, const std::string& path) {
  if (mesh.triangles.empty()) throw Error::in_file(path, "", "the scene has no triangles");
  mesh.face_sizes.assign(mesh.triangle_count(), 3);
  mesh.face_corners = mesh.triangles;
}

RestLocals rest_locals(const Skeleton& skeleton, const std::vector<glm::vec3>& points,
                       std::vector<std::pair<glm::vec3, glm::quat>> local, const std::vector<bool>& has_rest) {
  const Bounds bounds = compute_bounds(points);
  const float model_size = std::max(glm::length(bounds.max - bounds.min), 1e-6f);
  const Pose bind = skeleton.bind_pose();
  RestLocals rest{std::move(local), std::vector<bool>(has_rest.size(), false)};
  for (std::size_t b = 0; b < has_rest.size(); ++b) {
    if (!has_rest[b]) continue;
    const auto& [t, q] = rest.local[b];
    const glm::quat r = bind.rotations[b];
    rest.differs[b] = glm::length(t - bind.translations[b]) > 1e-6f * model_size ||
                      std::min(glm::length(q - r), glm::length(q + r)) > 1e-6f;
  }
  return rest;
}

void hold_rest(Animation& clip, const RestLocals& rest, const std::vector<bool>& has_channel) {
  for (Channel& channel : clip.channels) {
    const auto b = static_cast<std::size_t>(channel.bone);
    if (channel.translation.empty())
      channel.translation = {Interpolation::linear, {0.0f}, {rest.local[b].first}, {}, {}};
    if (channel.rotation.empty()) channel.rotation = {Interpolation::linear, {0.0f}, {rest.local[b].second}, {}, {}};
  }
  for (std::size_t b = 0; b < rest.local.size(); ++b) {
    if (has_channel[b] || !rest.differs[b]) continue;
    Channel hold;
    hold.bone = static_cast<std::int32_t>(b);
    hold.translation = {Interpolation::linear, {0.0f}, {rest.local[b].first}, {}, {}};
    hold.rotation = {Interpolation::linear, {0.0f}, {rest.local[b].second}, {}, {}};
    clip.channels.push_back(std::move(hold));
  }
}

void add_clip(Animation clip, std::size_t dropped, std::size_t scaled_bones, std::size_t bones, const std::string& path,
              std::vector<Animation>& clips, std::vector<std::string>& warnings) {
  const std::string element = "clip '" + clip.name + "'";
  if (dropped > 0)
    warnings.push_back(element + ": " + std::to_string(dropped) +
                       " keys at or before their predecessor's time dropped");
  if (scaled_bones > 0)
    warnings.push_back(element + ": " + std::to_string(scaled_bones) +
                       " bones animate scale, which a Pose cannot hold (ignored)");
  clip.require_valid(bones, path);
  clips.push_back(std::move(clip));
}

}  // namespace deform::import_detail
