// Skeleton: hierarchy validation, order, forward kinematics against hand-computed values, pose setters, palette.
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include <doctest/doctest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/runtime/error.hpp"
#include "runtime/skeleton_test_util.hpp"

using deform::Bone;
using deform::Skeleton;
using skeleton_test::head;
using skeleton_test::make_bone;

namespace {

bool near(glm::vec3 a, glm::vec3 b, float eps = 1e-5f) {
  return glm::all(glm::lessThanEqual(glm::abs(a - b), glm::vec3(eps)));
}

std::vector<glm::mat4> world_of(const Skeleton& s, const deform::Pose& pose) {
  std::vector<glm::mat4> world(s.bone_count());
  deform::LocalToWorldJob fk;
  fk.skeleton = &s;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  REQUIRE(fk.validate());
  REQUIRE(fk.run());
  return world;
}

// Head of a child at `offset` under a root rotated by `degrees` (X·Y·Z).
glm::vec3 child_head(glm::vec3 degrees, glm::vec3 offset) {
  const Skeleton s({make_bone("root", -1, {1}, {0, 0, 0}, degrees), make_bone("child", 0, {}, offset)});
  return head(s.bind_world()[1]);
}

std::string element_of(std::vector<Bone> bones) {
  try {
    Skeleton s(std::move(bones), "test");
  } catch (const deform::Error& e) {
    CHECK(e.file() == "test");
    return e.element();
  }
  FAIL("no error");
  return {};
}

}  // namespace

TEST_CASE("FK: 90 degrees about each axis") {
  CHECK(near(child_head({90, 0, 0}, {0, 1, 0}), {0, 0, 1}));
  CHECK(near(child_head({0, 90, 0}, {1, 0, 0}), {0, 0, -1}));
  CHECK(near(child_head({0, 0, 90}, {1, 0, 0}), {0, 1, 0}));
  CHECK(near(child_head({0, 0, -90}, {0, 1, 0}), {1, 0, 0}));
}

TEST_CASE("FK: X·Y·Z order, not Z·Y·X") {
  // Rx(90)·Rz(90)·(1,0,0) = Rx(90)·(0,1,0) = (0,0,1); Z·Y·X would give (0,1,0).
  CHECK(near(child_head({90, 0, 90}, {1, 0, 0}), {0, 0, 1}));
  // Rx(90)·Ry(90)·(0,0,1) = Rx(90)·(1,0,0) = (1,0,0); Z·Y·X would give (0,-1,0).
  CHECK(near(child_head({90, 90, 0}, {0, 0, 1}), {1, 0, 0}));
  // Matches the glTranslate-then-glRotate X, Y, Z product of the spec for an arbitrary triple.
  const glm::vec3 e(31.0f, -47.0f, 112.0f);
  glm::mat4 m = glm::translate(glm::mat4(1.0f), {1, 2, 3});
  m = glm::rotate(m, glm::radians(e.x), {1, 0, 0});
  m = glm::rotate(m, glm::radians(e.y), {0, 1, 0});
  m = glm::rotate(m, glm::radians(e.z), {0, 0, 1});
  const glm::mat4 l = deform::local_matrix(deform::quat_from_euler(e), {1, 2, 3});
  for (int c = 0; c < 4; ++c) CHECK(near(glm::vec3(l[c]), glm::vec3(m[c])));
}

TEST_CASE("FK: three-bone chain with translations") {
  const Skeleton s({make_bone("a", -1, {1}, {1, 2, 3}), make_bone("b", 0, {2}, {0, 2, 0}, {0, 0, 90}),
                    make_bone("c", 1, {}, {0, 3, 0})});
  const auto world = world_of(s, s.bind_pose());
  CHECK(near(head(world[0]), {1, 2, 3}));
  CHECK(near(head(world[1]), {1, 4, 3}));
  CHECK(near(head(world[2]), {-2, 4, 3}));         // (1,4,3) + Rz(90)·(0,3,0)
  CHECK(near(glm::vec3(world[2][0]), {0, 1, 0}));  // c's x axis, rotated by b
  // A pose: turn a by -90 about z; everything below follows.
  deform::Pose pose = s.bind_pose();
  CHECK(s.set_euler(pose, 0, {0, 0, -90}) == glm::vec3(0, 0, -90));
  const auto posed = world_of(s, pose);
  CHECK(near(head(posed[1]), glm::vec3(1, 2, 3) + glm::vec3(2, 0, 0)));
  CHECK(near(head(posed[2]), glm::vec3(3, 2, 3) + glm::vec3(0, 3, 0)));
}

TEST_CASE("parents may come later in the file; order() is parent-before-child") {
  const Skeleton s({make_bone("root", -1, {2}), make_bone("leaf", 2, {}, {0, 1, 0}),
                    make_bone("mid", 0, {1}, {1, 0, 0}, {0, 0, 90})});
  REQUIRE(s.order().size() == 3);
  CHECK(s.order()[0] == 0);
  CHECK(s.order()[1] == 2);
  CHECK(s.order()[2] == 1);
  CHECK(near(head(s.bind_world()[1]), {0, 0, 0}));  // (1,0,0) + Rz(90)·(0,1,0)
  CHECK(s.is_ancestor(2, 1));
  CHECK(s.is_ancestor(0, 1));
  CHECK(s.is_ancestor(1, 1));
  CHECK_FALSE(s.is_ancestor(1, 2));
  CHECK_FALSE(s.is_ancestor(5, 1));
}

TEST_CASE("bind matrices, their inverses and the skinning palette") {
  const Skeleton s(skeleton_test::arm_bones());
  const auto bind = world_of(s, s.bind_pose());
  for (std::size_t i = 0; i < s.bone_count(); ++i) {
    CHECK(bind[i] == s.bind_world()[i]);
    const glm::mat4 product = s.bind_world()[i] * s.inverse_bind_world()[i];
    for (int c = 0; c < 4; ++c) CHECK(near(glm::vec3(product[c]), glm::vec3(glm::mat4(1.0f)[c])));
  }
  std::vector<glm::mat4> palette(s.bone_count()), world(s.bone_count());
  const deform::Pose bind_pose = s.bind_pose();
  deform::LocalToWorldJob fk;
  fk.skeleton = &s;
  fk.rotations = bind_pose.rotations;
  fk.translations = bind_pose.translations;
  fk.world = world;
  fk.palette = palette;
  REQUIRE(fk.run());
  for (const glm::mat4& m : palette)
    for (int c = 0; c < 4; ++c) CHECK(near(glm::vec3(m[c]), glm::vec3(glm::mat4(1.0f)[c])));
  // Posed: the palette carries a bind-space point attached to the wrist to where the posed wrist carries it.
  deform::Pose pose = s.bind_pose();
  s.set_euler(pose, 1, {20, 30, 40});
  s.set_euler(pose, 2, {0, 0, 100});
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  REQUIRE(fk.run());
  CHECK(world == world_of(s, pose));
  for (std::size_t b = 0; b < s.bone_count(); ++b) CHECK(palette[b] == world[b] * s.inverse_bind_world()[b]);
  const glm::vec3 local(0.1f, 0.2f, -0.3f);
  const glm::vec3 bind_point = glm::vec3(s.bind_world()[3] * glm::vec4(local, 1.0f));
  CHECK(near(glm::vec3(palette[3] * glm::vec4(bind_point, 1.0f)), glm::vec3(world[3] * glm::vec4(local, 1.0f))));
}

TEST_CASE("LocalToWorldJob: ranges in order() give the whole run; bad sizes and poses are refused, nothing written") {
  const Skeleton s(skeleton_test::arm_bones());
  deform::Pose pose = s.bind_pose();
  s.set_euler(pose, 1, {20, 30, 40});
  s.set_euler(pose, 2, {0, 0, 100});
  const std::vector<glm::mat4> whole = world_of(s, pose);
  std::vector<glm::mat4> world(s.bone_count()), palette(s.bone_count());
  deform::LocalToWorldJob fk;
  fk.skeleton = &s;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  fk.palette = palette;
  CHECK(fk.count() == s.bone_count());
  for (std::size_t split = 0; split <= fk.count(); ++split) {
    std::fill(world.begin(), world.end(), glm::mat4(0.0f));
    REQUIRE(fk.run(0, split));
    REQUIRE(fk.run(split, fk.count()));
    CHECK(world == whole);
  }
  CHECK_FALSE(fk.run(2, 1));
  CHECK_FALSE(fk.run(0, fk.count() + 1));

  const std::vector<glm::mat4> before = world;
  auto refused = [&](const deform::LocalToWorldJob& job, const char* why) {
    const deform::Status validated = job.validate(), ran = job.run();
    CHECK_FALSE(validated);
    CHECK_FALSE(ran);
    CHECK(std::string(ran.reason()) == why);
    CHECK(world == before);
  };
  deform::LocalToWorldJob bad = fk;
  bad.skeleton = nullptr;
  refused(bad, "no skeleton");
  CHECK(bad.count() == 0);
  std::vector<glm::mat4> short_out(2);
  bad = fk;
  bad.world = short_out;
  refused(bad, "world does not have one entry per bone");
  bad = fk;
  bad.palette = short_out;
  refused(bad, "palette is neither empty nor one entry per bone");
  bad = fk;
  bad.rotations = std::span<const glm::quat>(pose.rotations).first(2);
  refused(bad, "rotations or translations do not have one entry per bone");
  for (const float nan_or_inf : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    deform::Pose broken = pose;
    broken.translations.back().y = nan_or_inf;
    bad = fk;
    bad.translations = broken.translations;
    refused(bad, "pose is not finite");
    broken = pose;
    broken.rotations[1].w = nan_or_inf;
    bad = fk;
    bad.rotations = broken.rotations;
    refused(bad, "pose is not finite");
  }
  // Without a palette only the world matrices are written.
  bad = fk;
  bad.palette = {};
  CHECK(bad.validate());
  CHECK(bad.run());
}

TEST_CASE("LocalToWorldJob: glm's products bit for bit over random trees; a range checks only its own bones") {
  // A random tree of 50 bones (parents listed after children too) in random poses: world = parent world times
  // local_matrix, palette = world times the inverse bind matrix, as plain glm mat4 products give them.
  std::mt19937 random(36);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 50;
    std::vector<Bone> bones(n);
    std::vector<int> ids(n - 1);
    for (int i = 0; i < n - 1; ++i) ids[std::size_t(i)] = i + 1;
    std::shuffle(ids.begin(), ids.end(), random);
    std::vector<int> placed{0};
    for (const int id : ids) {
      const int parent = placed[random() % placed.size()];
      bones[std::size_t(id)].parent = parent;
      bones[std::size_t(parent)].children.push_back(id);
      bones[std::size_t(id)].bind_translation = {unit(random), unit(random), unit(random)};
      bones[std::size_t(id)].bind_rotation = 180.0f * glm::vec3{unit(random), unit(random), unit(random)};
      placed.push_back(id);
    }
    const Skeleton s(bones);
    deform::Pose pose = s.bind_pose();
    for (std::size_t b = 0; b < s.bone_count(); ++b) {
      pose.rotations[b] = glm::normalize(glm::quat{unit(random), unit(random), unit(random), unit(random)});
      pose.translations[b] = 3.0f * glm::vec3{unit(random), unit(random), unit(random)};
    }
    std::vector<glm::mat4> world(s.bone_count()), palette(s.bone_count());
    deform::LocalToWorldJob fk{&s, pose.rotations, pose.translations, world, palette};
    REQUIRE(fk.run());
    std::vector<glm::mat4> expected(s.bone_count());
    for (const std::int32_t id : s.order()) {
      const auto i = std::size_t(id);
      const glm::mat4 local = deform::local_matrix(pose.rotations[i], pose.translations[i]);
      const std::int32_t parent = s.bones()[i].parent;
      expected[i] = parent < 0 ? local : expected[std::size_t(parent)] * local;
      CHECK(world[i] == expected[i]);
      CHECK(palette[i] == expected[i] * s.inverse_bind_world()[i]);
    }
    // A range reads only its own bones: a non-finite bone after it does not stop it, one inside it does.
    const std::size_t last = std::size_t(s.order().back());
    pose.rotations[last].x = std::numeric_limits<float>::infinity();
    CHECK(fk.run(0, s.bone_count() - 1));
    CHECK(std::string(fk.run(s.bone_count() - 1, s.bone_count()).reason()) == "pose is not finite");
    CHECK(std::string(fk.run().reason()) == "pose is not finite");
  }
}

TEST_CASE("set_euler clamps into the limits; clamp_to_limits converts, clamps and converts back") {
  const Skeleton s(skeleton_test::arm_bones());
  deform::Pose pose = s.bind_pose();
  CHECK(s.set_euler(pose, 2, {30, 5, 200}) == glm::vec3(10, 0, 150));
  CHECK(glm::abs(glm::dot(pose.rotations[2], deform::quat_from_euler({10, 0, 150}))) > 1 - 1e-6f);
  CHECK(s.set_euler(pose, 2, {30, 5, 200}, false) == glm::vec3(30, 5, 200));

  pose.rotations[2] = deform::quat_from_euler({25, 0, 60});
  s.clamp_to_limits(pose, 2);
  CHECK(glm::abs(glm::dot(pose.rotations[2], deform::quat_from_euler({10, 0, 60}))) > 1 - 1e-6f);

  const glm::quat inside = deform::quat_from_euler({-4, 0, 120});
  pose.rotations[2] = inside;
  s.clamp_to_limits(pose, 2);
  CHECK(pose.rotations[2] == inside);

  // y beyond 90: the canonical triple (180, 80, 180) breaks x's limits, the equivalent (0, 100, 0) does not.
  std::vector<Bone> bones = {make_bone("r", -1, {})};
  bones[0].limits.min = {-10, 95, -10};
  bones[0].limits.max = {10, 120, 10};
  const Skeleton t(bones);
  deform::Pose tp = t.bind_pose();
  const glm::quat beyond = deform::quat_from_euler({0, 100, 0});
  tp.rotations[0] = beyond;
  t.clamp_to_limits(tp, 0);
  CHECK(glm::abs(glm::dot(tp.rotations[0], beyond)) > 1 - 1e-6f);
  tp.rotations[0] = deform::quat_from_euler({0, 60, 0});
  t.clamp_to_limits(tp, 0);
  CHECK(glm::abs(glm::dot(tp.rotations[0], deform::quat_from_euler({0, 95, 0}))) > 1 - 1e-6f);
}

TEST_CASE("find and key: names, #ID, empty and shared names") {
  const Skeleton s({make_bone("root", -1, {1, 2, 3, 4}), make_bone("arm", 0, {}), make_bone("arm", 0, {}),
                    make_bone("", 0, {}), make_bone("#1", 0, {})});
  CHECK(s.find("root") == 0);
  CHECK(s.find("arm") == 1);
  CHECK(s.find("#2") == 2);
  CHECK(s.find("#0") == 0);
  CHECK(s.find("#5") == -1);
  CHECK(s.find("#") == -1);
  CHECK(s.find("#1x") == -1);
  CHECK(s.find("#-1") == -1);
  CHECK(s.find("leg") == -1);
  CHECK(s.key(0) == "root");
  CHECK(s.key(1) == "#1");
  CHECK(s.key(2) == "#2");
  CHECK(s.key(3) == "#3");
  CHECK(s.key(4) == "#4");
  for (std::int32_t id = 0; id < 5; ++id) CHECK(s.find(s.key(id)) == id);
}

TEST_CASE("validation: every rule of the spec, naming the bone") {
  using V = std::vector<Bone>;
  CHECK(element_of(V{}) == "");
  CHECK(element_of(V{make_bone("a", 1, {}), make_bone("b", -1, {0})}) == "bone 0");  // root not bone 0
  CHECK(element_of(V{make_bone("a", -1, {}), make_bone("b", -1, {})}) == "bone 1");  // two roots
  CHECK(element_of(V{make_bone("a", -1, {}), make_bone("b", 7, {})}) == "bone 1");   // parent out of range
  CHECK(element_of(V{make_bone("a", -1, {}), make_bone("b", -2, {})}) == "bone 1");
  CHECK(element_of(V{make_bone("a", -1, {}), make_bone("b", 1, {1})}) == "bone 1");  // own parent
  CHECK(element_of(V{make_bone("a", -1, {5})}) == "bone 0");                         // child out of range
  CHECK(element_of(V{make_bone("a", -1, {}), make_bone("b", 2, {2}), make_bone("c", 1, {1})}) == "bone 1");  // cycle
  CHECK(element_of(V{make_bone("a", -1, {}), make_bone("b", 0, {})}) == "bone 1");      // parent does not list it
  CHECK(element_of(V{make_bone("a", -1, {1, 1}), make_bone("b", 0, {})}) == "bone 0");  // listed twice
  CHECK(element_of(V{make_bone("a", -1, {1, 2}), make_bone("b", 0, {2}), make_bone("c", 1, {})}) == "bone 0");
  V limits{make_bone("a", -1, {})};
  limits[0].limits.min.y = 10;
  limits[0].limits.max.y = 5;
  CHECK(element_of(limits) == "bone 0");
  for (int field = 0; field < 4; ++field) {
    V bad{make_bone("a", -1, {1}), make_bone("b", 0, {})};
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    if (field == 0) bad[1].bind_translation.x = nan;
    if (field == 1) bad[1].bind_rotation.z = inf;
    if (field == 2) bad[1].limits.min.x = -inf;
    if (field == 3) bad[1].limits.max.z = nan;
    CHECK(element_of(bad) == "bone 1");
  }
  // min == max locks an axis and is valid; a bind pose outside the limits is valid too.
  V locked{make_bone("a", -1, {}, {0, 0, 0}, {45, 0, 0})};
  locked[0].limits.min = locked[0].limits.max = glm::vec3(0.0f);
  CHECK_NOTHROW(Skeleton{locked});
}

TEST_CASE("a skeleton whose bind transforms overflow is refused, naming the bone") {
  std::vector<deform::Bone> bones(3);
  bones[0].children = {1};
  bones[1].parent = 0, bones[1].children = {2}, bones[1].bind_translation = glm::vec3(3e38f, 0.0f, 0.0f);
  bones[2].parent = 1, bones[2].bind_translation = glm::vec3(3e38f, 0.0f, 0.0f);  // finite alone, infinite summed
  CHECK_THROWS_WITH_AS(deform::Skeleton(bones, "huge.sk"),
                       doctest::Contains("huge.sk: bone 2: bind transform overflows"), deform::Error);
}

TEST_CASE("find and key over 65,535 bones: lowest id of a name, #ID for shared, empty and '#' names") {
  std::vector<deform::Bone> bones(65535);
  for (std::size_t i = 0; i < bones.size(); ++i) {
    bones[i].name = "b" + std::to_string(i);
    if (i > 0)
      bones[i].parent = static_cast<std::int32_t>((i - 1) / 2), bones[(i - 1) / 2].children.push_back(std::int32_t(i));
  }
  bones[10].name = bones[20].name = "twin";
  bones[30].name = "";
  bones[40].name = "#hash";
  const deform::Skeleton s(bones);
  for (std::int32_t id : {0, 1, 999, 65534}) {
    CHECK(s.find("b" + std::to_string(id)) == id);
    CHECK(s.key(id) == "b" + std::to_string(id));
  }
  CHECK(s.find("twin") == 10);
  CHECK(s.key(10) == "#10");
  CHECK(s.key(20) == "#20");
  CHECK(s.key(30) == "#30");
  CHECK(s.key(40) == "#40");
  CHECK(s.find("#40") == 40);
  CHECK(s.find("nope") == -1);
  CHECK(s.find("") == 30);
}
