// Poses as JSON (docs/cli.md): {"bones": {"NAME": {"rotation": [rx, ry, rz], "translation": [x, y, z]}}}.
#include <nlohmann/json.hpp>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "deform/io/text.hpp"
#include "json_reader.hpp"
namespace deform {

Pose parse_pose_json(std::string_view json, const Skeleton& skeleton, bool clamp, const std::string& name) {
  const nlohmann::json document = detail::parse_json(json, name);
  const detail::JsonReader root(name, document);
  if (!root.has("bones") || !root.at("bones").is_object())
    detail::JsonReader(name, document, "bones").fail("expected {\"bones\": {NAME: {...}, ...}}");
  const detail::JsonReader bones = root.at("bones");

  Pose pose = skeleton.bind_pose();
  std::vector<bool> seen(skeleton.bone_count(), false);
  for (const auto& item : bones.value().items()) {
    const std::string& key = item.key();
    const detail::JsonReader entry = bones.at(key);
    const std::int32_t id = skeleton.find(key);
    if (id < 0) entry.fail("no such bone");
    if (key.empty() || (key.front() != '#' && skeleton.key(id) != key))
      entry.fail("name shared by several bones: address it as \"" + skeleton.key(id) + "\" (\"#ID\")");
    if (seen[static_cast<std::size_t>(id)]) entry.fail("bone given twice");
    seen[static_cast<std::size_t>(id)] = true;
    if (!entry.is_object()) entry.fail("expected {\"rotation\": [..], \"translation\": [..]}");
    entry.expect_object({"rotation", "translation"});
    if (entry.has("rotation")) skeleton.set_euler(pose, id, entry.at("rotation").vec3(), clamp);
    if (entry.has("translation")) pose.translations[static_cast<std::size_t>(id)] = entry.at("translation").vec3();
  }
  return pose;
}

Pose read_pose_json(const std::string& path, const Skeleton& skeleton, bool clamp) {
  return parse_pose_json(read_file_text(path), skeleton, clamp, path);
}

std::string format_pose_bones_json(const Skeleton& skeleton, const Pose& pose, std::span<const std::int32_t> bones,
                                   bool within_limits) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  auto add = [&](std::int32_t id) {
    const auto i = static_cast<std::size_t>(id);
    const glm::vec3 e = within_limits ? euler_within_limits(pose.rotations.at(i), skeleton.bone(id).limits)
                                      : euler_from_quat(pose.rotations.at(i));
    const glm::vec3 t = pose.translations.at(i);
    out[skeleton.key(id)] = {{"rotation", {shortest_double(e.x), shortest_double(e.y), shortest_double(e.z)}},
                             {"translation", {shortest_double(t.x), shortest_double(t.y), shortest_double(t.z)}}};
  };
  if (bones.empty())
    for (std::size_t i = 0; i < skeleton.bone_count(); ++i) add(static_cast<std::int32_t>(i));
  else
    for (const std::int32_t id : bones) add(id);
  return out.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

}  // namespace deform
