// Pose JSON: applying rotations (clamped or not) and translations by name or #ID, every error naming its key,
// and format_pose_bones_json read back.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "runtime/skeleton_test_util.hpp"

namespace {

bool same_rotation(glm::quat a, glm::quat b) { return glm::abs(glm::dot(a, b)) > 1.0f - 1e-6f; }

std::string error_key(const std::string& json, const deform::Skeleton& s) {
  try {
    deform::parse_pose_json(json, s, true, "pose.json");
  } catch (const deform::Error& e) {
    CHECK(e.file() == "pose.json");
    return e.element();
  }
  FAIL("accepted " << json);
  return {};
}

deform::Skeleton shared_names() {
  std::vector<deform::Bone> bones = skeleton_test::arm_bones();
  bones[3].name = "";
  bones[4].name = "shoulder";
  return deform::Skeleton(bones);
}

}  // namespace

TEST_CASE("parse_pose_json applies rotations and translations; unlisted bones keep the bind pose") {
  const deform::Skeleton s(skeleton_test::arm_bones());
  const std::string json = R"({"bones": {"elbow": {"rotation": [30, 0, 90]},
                                          "wrist": {"translation": [0, 2, 0.5]},
                                          "#4": {"rotation": [0, 45, 0], "translation": [1, 1, 1]}},
                               "solver": "ignored: other top-level keys are allowed"})";
  const deform::Pose pose = deform::parse_pose_json(json, s);
  const deform::Pose bind = s.bind_pose();
  CHECK(same_rotation(pose.rotations[2], deform::quat_from_euler({10, 0, 90})));  // x clamped to 10
  CHECK(pose.translations[2] == bind.translations[2]);
  CHECK(pose.translations[3] == glm::vec3(0, 2, 0.5f));
  CHECK(pose.rotations[3] == bind.rotations[3]);
  CHECK(same_rotation(pose.rotations[4], deform::quat_from_euler({0, 45, 0})));
  CHECK(pose.translations[4] == glm::vec3(1));
  CHECK(pose.rotations[1] == bind.rotations[1]);
  const deform::Pose free = deform::parse_pose_json(json, s, false);
  CHECK(same_rotation(free.rotations[2], deform::quat_from_euler({30, 0, 90})));
  CHECK(deform::parse_pose_json(R"({"bones": {}})", s).rotations == bind.rotations);
}

TEST_CASE("pose JSON errors name the key") {
  const deform::Skeleton s(skeleton_test::arm_bones());
  CHECK(error_key(R"({"bones": {"knee": {"rotation": [0, 0, 0]}}})", s) == "key 'bones.knee'");
  CHECK(error_key(R"({"bones": {"#9": {}}})", s) == "key 'bones.#9'");
  CHECK(error_key(R"({"bones": {"": {}}})", s) == "key 'bones.'");
  CHECK(error_key(R"({"bones": {"elbow": {"rotation": [0, 0]}}})", s) == "key 'bones.elbow.rotation'");
  CHECK(error_key(R"({"bones": {"elbow": {"rotation": [0, 0, 0, 0]}}})", s) == "key 'bones.elbow.rotation'");
  CHECK(error_key(R"({"bones": {"elbow": {"rotation": [0, "1", 0]}}})", s) == "key 'bones.elbow.rotation[1]'");
  CHECK(error_key(R"({"bones": {"elbow": {"translation": [0, 1e39, 0]}}})", s) == "key 'bones.elbow.translation[1]'");
  CHECK(error_key(R"({"bones": {"elbow": {"translation": 3}}})", s) == "key 'bones.elbow.translation'");
  CHECK(error_key(R"({"bones": {"elbow": {"rotaton": [0, 0, 0]}}})", s) == "key 'bones.elbow.rotaton'");
  CHECK(error_key(R"({"bones": {"elbow": [0, 0, 0]}})", s) == "key 'bones.elbow'");
  CHECK(error_key(R"({"bones": {"elbow": {}, "#2": {}}})", s) == "key 'bones.elbow'");  // the same bone twice
  CHECK(error_key(R"({"pose": {}})", s) == "key 'bones'");
  CHECK(error_key(R"([1, 2])", s) == "key 'bones'");
  try {
    deform::parse_pose_json(R"({"bones": {"elbow": )", s, true, "pose.json");
    FAIL("accepted truncated JSON");
  } catch (const deform::Error& e) {
    CHECK(e.where() == deform::Error::Where::byte);
  }
  CHECK_THROWS_AS(deform::parse_pose_json(R"({"bones": {"elbow": {"rotation": [NaN, 0, 0]}}})", s), deform::Error);
  CHECK_THROWS_AS(deform::read_pose_json("/nonexistent/pose.json", s), deform::Error);
  // A shared name must be addressed as #ID.
  const deform::Skeleton shared = shared_names();
  CHECK(error_key(R"({"bones": {"shoulder": {}}})", shared) == "key 'bones.shoulder'");
  CHECK_NOTHROW(deform::parse_pose_json(R"({"bones": {"#1": {}, "#4": {}, "#3": {}}})", shared));
}

TEST_CASE("format_pose_bones_json reads back as the same pose") {
  const deform::Skeleton s = shared_names();
  deform::Pose pose = s.bind_pose();
  s.set_euler(pose, 1, {12.5f, -40, 170});
  s.set_euler(pose, 3, {0, 90, 30});
  pose.translations[4] = {0.1f, 0.2f, 0.3f};
  const nlohmann::json bones = nlohmann::json::parse(deform::format_pose_bones_json(s, pose));
  CHECK(bones.size() == 5);
  CHECK(bones.contains("#1"));
  CHECK(bones.contains("#3"));
  CHECK(bones.contains("#4"));
  CHECK(bones["#4"]["translation"] == nlohmann::json::array({0.1, 0.2, 0.3}));
  CHECK(bones["#1"]["rotation"][0].get<double>() == doctest::Approx(12.5).epsilon(1e-5));
  const deform::Pose back = deform::parse_pose_json(nlohmann::json{{"bones", bones}}.dump(), s, false);
  for (std::size_t i = 0; i < s.bone_count(); ++i) {
    CHECK(same_rotation(back.rotations[i], pose.rotations[i]));
    CHECK(glm::all(glm::lessThan(glm::abs(back.translations[i] - pose.translations[i]), glm::vec3(1e-6f))));
  }
  const std::int32_t some[] = {2};
  const nlohmann::json one = nlohmann::json::parse(deform::format_pose_bones_json(s, pose, some));
  CHECK(one.size() == 1);
  CHECK(one.contains("elbow"));
}

TEST_CASE("pose JSON nested a million levels deep is refused in one pass, naming where") {
  const std::string deep = "{\"bones\": " + std::string(1000000, '[') + std::string(1000000, ']') + "}";
  CHECK_THROWS_WITH_AS(deform::parse_pose_json(deep, deform::Skeleton(skeleton_test::arm_bones()), true, "deep.json"),
                       doctest::Contains("deep.json: byte 73: JSON nested deeper than 64 levels"), deform::Error);
  // Brackets inside strings do not count.
  const std::string quoted = "{\"bones\": {\"" + std::string(100, '[') + "\": {}}}";
  CHECK_THROWS_WITH_AS(deform::parse_pose_json(quoted, deform::Skeleton(skeleton_test::arm_bones()), true, "q.json"),
                       doctest::Contains("no such bone"), deform::Error);
}

TEST_CASE("a pose of 65,535 bones reads in O(bones log bones)") {
  std::vector<deform::Bone> bones(65535);
  std::string json = "{\"bones\": {";
  for (std::size_t i = 0; i < bones.size(); ++i) {
    bones[i].name = "b" + std::to_string(i);
    if (i > 0) bones[i].parent = 0, bones[0].children.push_back(std::int32_t(i));
    json += (i ? ", \"" : "\"") + bones[i].name + "\": {\"translation\": [0, " + std::to_string(i % 7) + ", 0]}";
  }
  json += "}}";
  const deform::Skeleton skeleton(bones);
  const deform::Pose pose = deform::parse_pose_json(json, skeleton, true, "wide.json");
  CHECK(pose.translations[65534].y == 65534 % 7);
}
