// Poses as JSON (shared/spec/cli.md): {"bones": {"NAME": {"rotation": [rx, ry, rz], "translation": [x, y, z]}}}.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
namespace deform {
namespace {

std::string key_element(const std::string& path) { return "key '" + path + "'"; }

glm::vec3 parse_vec3(const nlohmann::json& value, const std::string& name, const std::string& path) {
  if (!value.is_array() || value.size() != 3)
    throw Error::in_file(name, key_element(path), "expected an array of 3 numbers");
  glm::vec3 v(0.0f);
  for (int k = 0; k < 3; ++k) {
    const nlohmann::json& item = value[static_cast<std::size_t>(k)];
    if (!item.is_number()) throw Error::in_file(name, key_element(path), "expected an array of 3 numbers");
    v[k] = static_cast<float>(item.get<double>());
    if (!std::isfinite(v[k])) throw Error::in_file(name, key_element(path), "number is not finite");
  }
  return v;
}

// The float's shortest decimal form as a double, so that JSON shows 0.1 rather than 0.10000000149011612.
double shortest(float value) {
  if (value == 0.0f) return 0.0;
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text - 1, value);
  *result.ptr = '\0';
  return std::strtod(text, nullptr);
}

}  // namespace

Pose parse_pose_json(std::string_view json, const Skeleton& skeleton, bool clamp, const std::string& name) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(json);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error::at_byte(name, static_cast<std::int64_t>(e.byte), "", std::string("invalid JSON: ") + e.what());
  } catch (const nlohmann::json::exception& e) {
    throw Error::in_file(name, "", std::string("invalid JSON: ") + e.what());
  }
  if (!document.is_object() || !document.contains("bones") || !document["bones"].is_object())
    throw Error::in_file(name, key_element("bones"), "expected {\"bones\": {NAME: {...}, ...}}");

  Pose pose = skeleton.bind_pose();
  std::vector<bool> seen(skeleton.bone_count(), false);
  for (const auto& [key, entry] : document["bones"].items()) {
    const std::string path = "bones." + key;
    const std::int32_t id = skeleton.find(key);
    if (id < 0) throw Error::in_file(name, key_element(path), "no such bone");
    if (key.empty() || (key.front() != '#' && skeleton.key(id) != key))
      throw Error::in_file(name, key_element(path),
                           "name shared by several bones: address it as \"" + skeleton.key(id) + "\" (\"#ID\")");
    if (seen[static_cast<std::size_t>(id)]) throw Error::in_file(name, key_element(path), "bone given twice");
    seen[static_cast<std::size_t>(id)] = true;
    if (!entry.is_object())
      throw Error::in_file(name, key_element(path), "expected {\"rotation\": [..], \"translation\": [..]}");
    for (const auto& [field, value] : entry.items()) {
      const std::string field_path = path + "." + field;
      if (field == "rotation")
        skeleton.set_euler(pose, id, parse_vec3(value, name, field_path), clamp);
      else if (field == "translation")
        pose.translations[static_cast<std::size_t>(id)] = parse_vec3(value, name, field_path);
      else
        throw Error::in_file(name, key_element(field_path), "unknown key (expected rotation or translation)");
    }
  }
  return pose;
}

Pose read_pose_json(const std::string& path, const Skeleton& skeleton, bool clamp) {
  return parse_pose_json(read_file_text(path), skeleton, clamp, path);
}

std::string format_pose_bones_json(const Skeleton& skeleton, const Pose& pose, std::span<const std::int32_t> bones) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  auto add = [&](std::int32_t id) {
    const auto i = static_cast<std::size_t>(id);
    const glm::vec3 e = euler_from_quat(pose.rotations.at(i));
    const glm::vec3 t = pose.translations.at(i);
    out[skeleton.key(id)] = {{"rotation", {shortest(e.x), shortest(e.y), shortest(e.z)}},
                             {"translation", {shortest(t.x), shortest(t.y), shortest(t.z)}}};
  };
  if (bones.empty())
    for (std::size_t i = 0; i < skeleton.bone_count(); ++i) add(static_cast<std::int32_t>(i));
  else
    for (const std::int32_t id : bones) add(id);
  return out.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
}

}  // namespace deform
