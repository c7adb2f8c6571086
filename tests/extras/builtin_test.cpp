// The built-in character: counts, skeleton conventions and limits, a closed outward-facing body, UVs, normals,
// plausible weights, determinism, the texture, and samples/data/builtin.* equal to what the library builds.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/sk.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#ifdef DEFORM_HAVE_STB
#include <stb_image.h>
#endif

using deform::Model;

namespace {

const Model& character() {
  static const Model model = deform::builtin_character();
  return model;
}

std::int32_t id(const char* name) {
  const std::int32_t b = character().skeleton.find(name);
  REQUIRE_MESSAGE(b >= 0, name);
  return b;
}

glm::vec3 head(const glm::mat4& world) { return glm::vec3(world[3]); }

std::vector<glm::mat4> world_of(const deform::Pose& pose) {
  std::vector<glm::mat4> world(character().skeleton.bone_count());
  deform::LocalToWorldJob fk;
  fk.skeleton = &character().skeleton;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  REQUIRE(fk.run());
  return world;
}

// The angle between two rotations (radians), accurate near 0 (acos of their dot product is not, in float).
float angle_between(glm::quat a, glm::quat b) {
  const glm::quat d = glm::conjugate(a) * b;
  return 2.0f * std::atan2(glm::length(glm::vec3(d.x, d.y, d.z)), std::abs(d.w));
}

std::string data_path(const char* file) { return std::string(DEFORM_SOURCE_DIR) + "/samples/data/" + file; }

}  // namespace

TEST_CASE("counts are those of the thesis' test character, give or take") {
  const Model& m = character();
  CHECK(m.name == "builtin");
  CHECK(m.mesh.point_count() >= 2300);
  CHECK(m.mesh.point_count() <= 2900);  // 2,850 with the ponytail
  CHECK(m.mesh.triangle_count() >= 4500);
  CHECK(m.mesh.triangle_count() <= 5800);  // 5,696
  CHECK(m.skeleton.bone_count() >= 24);
  CHECK(m.skeleton.bone_count() <= 36);  // 33: 29 for the body, 4 for the ponytail
  CHECK(m.weights.size() == m.mesh.point_count());
  REQUIRE(m.mesh.materials.size() == 1);
  CHECK(m.mesh.materials[0].name == "skin");
  CHECK(m.mesh.materials[0].diffuse_map == "builtin.png");
  CHECK(m.mesh.face_sizes.size() == m.mesh.triangle_count());
  CHECK(m.mesh.face_corners == m.mesh.triangles);
  std::uint32_t covered = 0;
  for (const deform::Submesh& s : m.mesh.submeshes) {
    CHECK(s.first_triangle == covered);
    CHECK(s.material == 0);
    covered += s.triangle_count;
  }
  CHECK(covered == m.mesh.triangle_count());
}

TEST_CASE("skeleton: names, a valid tree, bones along their local +Y") {
  const deform::Skeleton& s = character().skeleton;
  CHECK(s.bone(0).name == "hips");
  for (const char* name :
       {"spine",      "chest",      "neck",      "head",     "clavicle_l", "upperarm_l", "forearm_l", "hand_l",
        "fingers1_l", "fingers2_l", "thumb1_l",  "thumb2_l", "thigh_l",    "shin_l",     "foot_l",    "toe_l",
        "clavicle_r", "upperarm_r", "forearm_r", "hand_r",   "thigh_r",    "shin_r",     "foot_r",    "toe_r"})
    CHECK(s.find(name) >= 0);
  // The ponytail's bones come after the body's 29, so the body's ids stay those of the 29-bone character.
  REQUIRE(s.bone_count() == 33);
  CHECK(s.find("toe_r") == 28);
  for (int i = 0; i < 4; ++i) {
    CHECK(s.find(("ponytail" + std::to_string(i + 1)).c_str()) == 29 + i);
    CHECK(s.bone(29 + i).parent == (i == 0 ? s.find("head") : 28 + i));
  }
  // Re-validating the bones succeeds (one root, consistent child lists, limits ordered).
  CHECK_NOTHROW(deform::Skeleton(std::vector<deform::Bone>(s.bones().begin(), s.bones().end())));
  for (std::size_t b = 0; b < s.bone_count(); ++b) {
    const deform::Bone& bone = s.bones()[b];
    if (bone.children.empty()) continue;
    const glm::vec3 t = s.bone(bone.children.front()).bind_translation;
    INFO(bone.name);
    if (b == 0) continue;       // the root's +Y is forward (documented)
    if (bone.name == "head") {  // the ponytail branches off the back of the skull (documented): 16 cm up, 8.5 cm back
      CHECK(s.bone(bone.children.front()).name == "ponytail1");
      CHECK(std::abs(t.x) < 1e-6f);
      CHECK(t.y == doctest::Approx(0.16f));
      CHECK(t.z == doctest::Approx(-0.085f));
      continue;
    }
    CHECK(std::abs(t.x) < 1e-6f);
    CHECK(std::abs(t.z) < 1e-6f);
    CHECK(t.y > 0.02f);
  }
  // T-pose, Y up, metres: FK heads where the docs put them.
  const auto& world = s.bind_world();
  CHECK(head(world[static_cast<std::size_t>(id("hips"))]).y == doctest::Approx(0.95f));
  CHECK(head(world[static_cast<std::size_t>(id("spine"))]).y == doctest::Approx(1.05f));
  CHECK(head(world[static_cast<std::size_t>(id("forearm_l"))]).x == doctest::Approx(0.45f));
  CHECK(head(world[static_cast<std::size_t>(id("forearm_r"))]).x == doctest::Approx(-0.45f));
  CHECK(head(world[static_cast<std::size_t>(id("forearm_l"))]).y == doctest::Approx(1.45f));
  CHECK(head(world[static_cast<std::size_t>(id("foot_r"))]).y == doctest::Approx(0.08f));
  // Left and right mirror each other through x = 0.
  for (const char* side : {"clavicle", "upperarm", "forearm", "hand", "fingers1", "fingers2", "thumb1", "thumb2",
                           "thigh", "shin", "foot", "toe"}) {
    const glm::vec3 l = head(world[static_cast<std::size_t>(id((std::string(side) + "_l").c_str()))]);
    const glm::vec3 r = head(world[static_cast<std::size_t>(id((std::string(side) + "_r").c_str()))]);
    INFO(side);
    CHECK(l.x > 0.0f);
    CHECK(r.x == doctest::Approx(-l.x));
    CHECK(r.y == doctest::Approx(l.y));
    CHECK(r.z == doctest::Approx(l.z));
  }
}

TEST_CASE("DOF limits are anatomical") {
  const deform::Skeleton& s = character().skeleton;
  for (const deform::Bone& b : s.bones()) {
    INFO(b.name);
    CHECK(deform::within_limits(b.bind_rotation, b.limits));  // the bind pose is a legal pose
  }
  // Elbows and knees bend one way, about X only.
  for (const char* name : {"forearm_l", "forearm_r", "shin_l", "shin_r"}) {
    const deform::DofLimits& l = s.bone(id(name)).limits;
    INFO(name);
    CHECK(l.min.x == 0.0f);
    CHECK(l.max.x >= 120.0f);
    CHECK(l.min.z == 0.0f);
    CHECK(l.max.z == 0.0f);
  }
  // The head cannot spin half a turn: neck and head twist together stay under 180°.
  CHECK(s.bone(id("neck")).limits.max.y + s.bone(id("head")).limits.max.y < 180.0f);
  CHECK(s.bone(id("neck")).limits.min.y + s.bone(id("head")).limits.min.y > -180.0f);

  // Bending an elbow or knee as far as allowed moves the hand forward and the foot backward, and the pose setter
  // refuses the other way.
  deform::Pose pose = s.bind_pose();
  const auto bind = world_of(pose);
  for (const char* side : {"_l", "_r"}) {
    const std::string forearm = std::string("forearm") + side, hand = std::string("hand") + side;
    const std::string shin = std::string("shin") + side, foot = std::string("foot") + side;
    CHECK(s.set_euler(pose, id(forearm.c_str()), {90, 0, 0}) == glm::vec3(90, 0, 0));
    CHECK(s.set_euler(pose, id(shin.c_str()), {90, 0, 0}) == glm::vec3(90, 0, 0));
    const auto bent = world_of(pose);
    CHECK(head(bent[static_cast<std::size_t>(id(hand.c_str()))]).z == doctest::Approx(0.26f).epsilon(1e-4));
    CHECK(head(bent[static_cast<std::size_t>(id(foot.c_str()))]).z == doctest::Approx(-0.42f).epsilon(1e-4));
    CHECK(head(bind[static_cast<std::size_t>(id(hand.c_str()))]).z == doctest::Approx(0.0f));
    CHECK(s.set_euler(pose, id(forearm.c_str()), {-45, 0, 0}) == glm::vec3(0, 0, 0));
    CHECK(s.set_euler(pose, id(shin.c_str()), {-45, 0, 0}) == glm::vec3(0, 0, 0));
  }
  // Flexing a thigh (X below its bind 90°) swings the knee forward.
  pose = s.bind_pose();
  s.set_euler(pose, id("thigh_l"), {30, 0, 0});
  CHECK(head(world_of(pose)[static_cast<std::size_t>(id("shin_l"))]).z > 0.3f);
}

TEST_CASE("the body: one closed surface wound outward, 1.8 m tall, UVs in [0, 1], unit normals") {
  const deform::Mesh& mesh = character().mesh;
  const deform::Bounds bounds = deform::compute_bounds(mesh.positions);
  CHECK(bounds.max.y == doctest::Approx(1.8f).epsilon(0.02));
  CHECK(bounds.min.y > -0.01f);
  CHECK(bounds.min.y < 0.02f);
  CHECK(bounds.max.x == doctest::Approx(-bounds.min.x).epsilon(1e-5));
  CHECK(bounds.max.x == doctest::Approx(0.9f).epsilon(0.03));  // arm span ≈ height

  // Fourteen parts (groups, atlas cells) of one surface.
  REQUIRE(mesh.submeshes.size() == 14);
  const char* names[] = {"torso",   "neck",    "head",  "arm_l", "arm_r",  "hand_l", "hand_r",
                         "thumb_l", "thumb_r", "leg_l", "leg_r", "foot_l", "foot_r", "hair"};
  REQUIRE(deform::builtin_part_names().size() == 14);
  for (std::size_t i = 0; i < 14; ++i) CHECK(deform::builtin_part_names()[i] == names[i]);
  // Every edge of the body is used exactly twice, once in each direction: closed and consistently oriented; the
  // enclosed volume is positive (outward) and the surface is one connected piece.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  double volume = 0.0;
  std::vector<std::uint32_t> component(mesh.point_count());
  for (std::uint32_t i = 0; i < component.size(); ++i) component[i] = i;
  auto find = [&](std::uint32_t i) {
    while (component[i] != i) i = component[i] = component[component[i]];
    return i;
  };
  for (std::uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    std::uint32_t p[3];
    for (int k = 0; k < 3; ++k) p[k] = mesh.vertex_point[mesh.triangles[3 * t + static_cast<std::uint32_t>(k)]];
    for (int k = 0; k < 3; ++k) {
      ++edges[{p[k], p[(k + 1) % 3]}];
      component[find(p[k])] = find(p[(k + 1) % 3]);
    }
    volume += glm::dot(glm::dvec3(mesh.positions[p[0]]),
                       glm::cross(glm::dvec3(mesh.positions[p[1]]), glm::dvec3(mesh.positions[p[2]]))) /
              6.0;
  }
  bool closed = true;
  for (const auto& [edge, count] : edges)
    if (count != 1 || edges.count({edge.second, edge.first}) != 1) closed = false;
  CHECK(closed);
  CHECK(volume > 0.05);  // outward; a person of 1.8 m holds about 0.07 m³
  CHECK(volume < 0.1);
  std::size_t pieces = 0;
  for (std::uint32_t i = 0; i < component.size(); ++i) pieces += find(i) == i ? 1 : 0;
  CHECK(pieces == 1);
  // Euler characteristic 2: a sphere's topology (no handles, no pinches).
  CHECK(static_cast<long>(mesh.point_count()) - static_cast<long>(edges.size() / 2) +
            static_cast<long>(mesh.triangle_count()) ==
        2);

  REQUIRE(mesh.vertex_uvs.size() == mesh.vertex_count());
  REQUIRE(mesh.vertex_normals.size() == mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    REQUIRE(mesh.vertex_uvs[v].x >= 0.0f);
    REQUIRE(mesh.vertex_uvs[v].x <= 1.0f);
    REQUIRE(mesh.vertex_uvs[v].y >= 0.0f);
    REQUIRE(mesh.vertex_uvs[v].y <= 1.0f);
    REQUIRE(std::abs(glm::length(mesh.vertex_normals[v]) - 1.0f) < 1e-4f);
    // Outward: the normal points away from the point's part axis, roughly (not into the body).
  }
}

TEST_CASE("weights: normalised, at most 4, and bound to plausible bones") {
  const Model& m = character();
  const deform::Skeleton& s = m.skeleton;
  const auto& world = s.bind_world();
  std::size_t checked_hand = 0, checked_foot = 0, checked_head = 0, checked_hair = 0;
  // The ponytail's points (the "hair" part's, borders included) belong to the ponytail, and the skull's to the head.
  std::vector<bool> hair(m.mesh.point_count(), false);
  for (std::size_t part = 0; part < m.mesh.submeshes.size(); ++part)
    if (const deform::Submesh& sub = m.mesh.submeshes[part]; deform::builtin_part_names()[part] == "hair")
      for (std::uint32_t c = 3 * sub.first_triangle; c < 3 * (sub.first_triangle + sub.triangle_count); ++c)
        hair[m.mesh.vertex_point[m.mesh.triangles[c]]] = true;
  for (std::size_t i = 0; i < m.mesh.point_count(); ++i) {
    float sum = 0.0f;
    for (int k = 0; k < 4; ++k) {
      REQUIRE(m.weights.weights[i][k] >= 0.0f);
      REQUIRE(m.weights.bones[i][k] < s.bone_count());
      sum += m.weights.weights[i][k];
    }
    REQUIRE(std::abs(sum - 1.0f) <= 1e-6f);
    REQUIRE(m.weights.weights[i][0] > 0.0f);
    const std::int32_t strongest = m.weights.bones[i][0];
    const glm::vec3 p = m.mesh.positions[i];
    // Every influence lies within 0.35 m of the point (no bone pulls from across the body).
    const auto segments = deform::bone_segments(s);
    for (int k = 0; k < 4; ++k) {
      if (m.weights.weights[i][k] == 0.0f) continue;
      const deform::BoneSegment& seg = segments[m.weights.bones[i][k]];
      const glm::vec3 axis = seg.tail - seg.head;
      const float t =
          glm::dot(axis, axis) > 0 ? std::clamp(glm::dot(p - seg.head, axis) / glm::dot(axis, axis), 0.f, 1.f) : 0.f;
      INFO("point " << i << " (" << p.x << ", " << p.y << ", " << p.z << "), bone "
                    << s.bone(m.weights.bones[i][k]).name);
      REQUIRE(glm::length(p - (seg.head + t * axis)) < 0.35f);
    }
    for (const char* side : {"_l", "_r"}) {
      const std::string hand = std::string("hand") + side, forearm = std::string("forearm") + side;
      const std::string foot = std::string("foot") + side, shin = std::string("shin") + side;
      // Within 8 cm of the hand's head: the hand, one of its fingers, or the forearm.
      if (glm::length(p - head(world[static_cast<std::size_t>(id(hand.c_str()))])) < 0.08f) {
        CHECK(s.is_ancestor(id(forearm.c_str()), strongest));
        ++checked_hand;
      }
      // Within 10 cm of the ankle: the foot, the toe or the shin.
      if (glm::length(p - head(world[static_cast<std::size_t>(id(foot.c_str()))])) < 0.10f) {
        CHECK(s.is_ancestor(id(shin.c_str()), strongest));
        ++checked_foot;
      }
    }
    if (p.y > 1.7f && !hair[i]) {
      INFO("point " << i << " (" << p.x << ", " << p.y << ", " << p.z << ")");
      CHECK(strongest == id("head"));
      ++checked_head;
    }
    if (hair[i] && p.y < 1.7f) {  // below the root: the ponytail's own bones
      CHECK(strongest >= id("ponytail1"));
      ++checked_hair;
    }
    // The arms beyond the elbow belong to the forearm chain; the hips' side of the body never to an arm.
    if (std::abs(p.x) > 0.5f) CHECK(s.is_ancestor(id(p.x > 0 ? "forearm_l" : "forearm_r"), strongest));
    if (p.y < 1.0f) CHECK(!s.is_ancestor(id("clavicle_l"), strongest));
    if (p.y < 1.0f) CHECK(!s.is_ancestor(id("clavicle_r"), strongest));
    if (p.y > 1.1f) CHECK(!s.is_ancestor(id("thigh_l"), strongest));
    if (p.y > 1.1f) CHECK(!s.is_ancestor(id("thigh_r"), strongest));
  }
  CHECK(checked_hand > 50);
  CHECK(checked_foot > 50);
  CHECK(checked_head > 50);
  CHECK(checked_hair > 100);
}

TEST_CASE("two calls build the same character") {
  const Model a = deform::builtin_character();
  const Model& b = character();
  CHECK(a.mesh.positions == b.mesh.positions);
  CHECK(a.mesh.vertex_point == b.mesh.vertex_point);
  CHECK(a.mesh.vertex_normals == b.mesh.vertex_normals);
  CHECK(a.mesh.vertex_uvs == b.mesh.vertex_uvs);
  CHECK(a.mesh.triangles == b.mesh.triangles);
  CHECK(std::equal(a.skeleton.bones().begin(), a.skeleton.bones().end(), b.skeleton.bones().begin(),
                   b.skeleton.bones().end()));
  CHECK(a.weights == b.weights);
  CHECK(deform::builtin_texture(64) == deform::builtin_texture(64));
}

TEST_CASE("the texture: painted skin, clothes and a face, without grid lines") {
  const std::vector<std::uint8_t> t = deform::builtin_texture(512);
  REQUIRE(t.size() == 512u * 512u * 3u);
  // The texel of body part `part` (atlas cell, row by row from the bottom left) at its own (u, v); row 0 is the top.
  auto texel = [&](int part, float u, float v) {
    const float cell = 128.0f, margin = 0.04f, inner = 1.0f - 2.0f * margin;
    const auto column = static_cast<std::size_t>(static_cast<float>(part % 4) * cell + cell * (margin + inner * u));
    const auto from_bottom =
        static_cast<std::size_t>(static_cast<float>(part / 4) * cell + cell * (margin + inner * v));
    const std::size_t i = ((511u - from_bottom) * 512u + column) * 3u;
    return glm::ivec3(t[i], t[i + 1], t[i + 2]);
  };
  // u = 0 is a part's front (or top), 1 its back (or underside); v runs along the part (docs/builtin-character.md).
  const glm::ivec3 face = texel(2, 0.0f, 0.42f), hair = texel(2, 0.9f, 0.8f), shirt = texel(0, 0.0f, 0.6f);
  const glm::ivec3 trousers = texel(9, 0.0f, 0.5f), hand = texel(5, 0.0f, 0.5f), eye = texel(2, 0.095f, 0.50f);
  INFO(face.x << " " << face.y << " " << face.z << " / shirt " << shirt.x << " " << shirt.y << " " << shirt.z);
  CHECK(face.x > 180);  // skin: warm and light
  CHECK(face.x > face.y);
  CHECK(face.y > face.z);
  CHECK(hand.x > hand.z + 40);
  CHECK(shirt.z > shirt.x);  // the shirt is blue
  CHECK(trousers.x + trousers.y + trousers.z < face.x + face.y + face.z - 200);
  CHECK(hair.x + hair.y + hair.z < 300);
  CHECK(eye.x + eye.y + eye.z < face.x + face.y + face.z - 200);
  // Painted, not a checker: neighbouring texels inside a cell never differ by a grid line's step.
  int steepest = 0;
  for (std::size_t row = 0; row < 512; ++row)
    for (std::size_t column = 0; column + 1 < 512; ++column) {
      if ((column + 1) % 128 == 0) continue;  // the border between two cells
      for (std::size_t k = 0; k < 3; ++k)
        steepest = std::max(steepest,
                            std::abs(int(t[(row * 512 + column) * 3 + k]) - int(t[(row * 512 + column + 1) * 3 + k])));
    }
  CHECK(steepest < 120);  // 89 here (the eyes); a checker's grid line steps by 150 or more
  CHECK_THROWS_AS(deform::builtin_texture(100), deform::Error);
  CHECK_THROWS_AS(deform::builtin_texture(8), deform::Error);
  CHECK_THROWS_AS(deform::builtin_texture(8192), deform::Error);
}

TEST_CASE("samples/data/builtin.* hold exactly the character the library builds") {
  const Model& m = character();
  deform::Warnings warnings;
  deform::ObjNames names;
  const deform::Mesh obj = deform::read_obj(data_path("builtin.obj"), &warnings, {}, &names);
  CHECK(warnings.messages.empty());
  // Tolerances of a few float ulps: the files are exact here, but another math library may round sin/exp/pow
  // differently than the one that wrote them.
  auto near = [](auto a, auto b, float eps) { return glm::all(glm::lessThanEqual(glm::abs(a - b), decltype(a)(eps))); };
  REQUIRE(obj.point_count() == m.mesh.point_count());
  for (std::size_t i = 0; i < obj.point_count(); ++i) REQUIRE(near(obj.positions[i], m.mesh.positions[i], 1e-6f));
  REQUIRE(obj.triangle_count() == m.mesh.triangle_count());
  // Corner by corner: the same point, UV and normal (the reader may number render vertices its own way).
  for (std::size_t c = 0; c < m.mesh.triangles.size(); ++c) {
    const std::uint32_t r = obj.triangles[c], e = m.mesh.triangles[c];
    REQUIRE(obj.vertex_point[r] == m.mesh.vertex_point[e]);
    REQUIRE(near(obj.vertex_uvs[r], m.mesh.vertex_uvs[e], 1e-6f));
    REQUIRE(near(obj.vertex_normals[r], m.mesh.vertex_normals[e], 1e-5f));
  }
  REQUIRE(obj.submeshes.size() == m.mesh.submeshes.size());
  REQUIRE(names.submeshes.size() == deform::builtin_part_names().size());
  for (std::size_t i = 0; i < obj.submeshes.size(); ++i) {
    CHECK(names.submeshes[i].object == "builtin");
    CHECK(names.submeshes[i].group == deform::builtin_part_names()[i]);
  }
  REQUIRE(obj.materials.size() == 1);
  CHECK(obj.materials[0].name == "skin");
  CHECK(obj.materials[0].diffuse == m.mesh.materials[0].diffuse);
  CHECK(std::filesystem::path(obj.materials[0].diffuse_map).filename() == "builtin.png");

  const deform::Skeleton sk = deform::read_sk(data_path("builtin.sk"));
  CHECK(std::equal(sk.bones().begin(), sk.bones().end(), m.skeleton.bones().begin(), m.skeleton.bones().end()));

  const deform::SkinWeights skw =
      deform::read_skw(data_path("builtin.skw"), m.mesh.point_count(), m.skeleton.bone_count());
  REQUIRE(skw.size() == m.weights.size());
  for (std::size_t i = 0; i < skw.size(); ++i) {
    REQUIRE(skw.bones[i] == m.weights.bones[i]);
    REQUIRE(near(skw.weights[i], m.weights.weights[i], 1e-5f));
  }

#ifdef DEFORM_HAVE_STB
  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load(data_path("builtin.png").c_str(), &width, &height, &channels, 3);
  REQUIRE(pixels != nullptr);
  CHECK(width == 512);
  CHECK(height == 512);
  const std::vector<std::uint8_t> expected = deform::builtin_texture(512);
  CHECK(std::equal(expected.begin(), expected.end(), pixels));
  stbi_image_free(pixels);
#else
  CHECK(std::filesystem::file_size(data_path("builtin.png")) > 1000);
#endif
}

TEST_CASE("clips: idle, walk, run and wave, smooth loops within the limits") {
  const Model& m = character();
  const deform::Skeleton& s = m.skeleton;
  const std::vector<deform::Animation> clips = deform::builtin_clips(m);
  REQUIRE(clips.size() == 4);
  const char* names[] = {"idle", "walk", "run", "wave"};
  for (std::size_t c = 0; c < clips.size(); ++c) CHECK(clips[c].name == names[c]);
  CHECK(deform::find_clip(clips, "run") == 2);

  // builtin_walk() is the list's walk, key for key (the benchmarks and tests that pin it keep their numbers).
  const deform::Animation walk = deform::builtin_walk(m);
  REQUIRE(walk.channels.size() == clips[1].channels.size());
  for (std::size_t c = 0; c < walk.channels.size(); ++c) {
    CHECK(walk.channels[c].bone == clips[1].channels[c].bone);
    CHECK(walk.channels[c].rotation.values == clips[1].channels[c].rotation.values);
    CHECK(walk.channels[c].rotation.out_tangents == clips[1].channels[c].rotation.out_tangents);
    CHECK(walk.channels[c].translation.values == clips[1].channels[c].translation.values);
  }

  for (const deform::Animation& clip : clips) {
    INFO(clip.name);
    CHECK(clip.loop);
    CHECK(clip.duration > 0.0f);
    CHECK_NOTHROW(clip.require_valid(s.bone_count(), m.name));
    CHECK(clip.channels.size() >= 7);
    for (const deform::Channel& channel : clip.channels) {
      INFO(s.bone(channel.bone).name);
      for (const auto* track : {&channel.rotation}) {
        if (track->times.empty()) continue;
        CHECK(track->interpolation == deform::Interpolation::cubic_spline);
        CHECK(track->times.front() == 0.0f);
        CHECK(track->times.back() == clip.duration);
        // A loop: the last key is the first, tangents included, so the motion is C¹ across the wrap.
        CHECK(track->values.front() == track->values.back());
        CHECK(track->out_tangents.front() == track->in_tangents.back());
        CHECK(track->times.size() >= 17);
      }
    }
    // Sampled anywhere, the pose is within the limits: set_pose's clamp leaves it (to the clamp's own rounding;
    // the walk's thigh touches its 110° limit at one key, the other clips keep a margin of a degree or more).
    deform::Pose pose = s.bind_pose();
    deform::SamplingJob sampling;
    sampling.animation = &clip;
    sampling.rotations = pose.rotations;
    sampling.translations = pose.translations;
    float largest_change = 0.0f, largest_motion = 0.0f;
    const deform::Pose first = [&] {
      sampling.time = 0.0f;
      REQUIRE(sampling.run());
      return pose;
    }();
    for (int n = 0; n <= 400; ++n) {
      sampling.time = clip.duration * float(n) / 400.0f;
      REQUIRE(sampling.run());
      deform::Pose clamped = pose;
      for (const deform::Channel& channel : clip.channels) {
        const auto b = std::size_t(channel.bone);
        s.clamp_to_limits(clamped, channel.bone);
        const float change = angle_between(clamped.rotations[b], pose.rotations[b]);
        largest_change = std::max(largest_change, change);
        const float motion = angle_between(first.rotations[b], pose.rotations[b]);
        largest_motion = std::max(largest_motion, motion);
        CHECK(deform::within_limits(deform::euler_within_limits(pose.rotations[b], s.bone(channel.bone).limits),
                                    s.bone(channel.bone).limits));
      }
    }
    CHECK(glm::degrees(largest_change) < 0.01f);
    CHECK(glm::degrees(largest_motion) > 5.0f);  // it moves
    // Smooth: no kick at the keys or the wrap — the angular velocity just before and after any time agrees.
    const float h = 1e-3f;
    auto rotation_at = [&](float t, std::size_t b) {
      sampling.time = t;
      REQUIRE(sampling.run());
      return pose.rotations[b];
    };
    float largest_jump = 0.0f, largest_speed = 0.0f;
    for (const deform::Channel& channel : clip.channels) {
      const auto b = std::size_t(channel.bone);
      if (channel.rotation.times.empty()) continue;
      for (const float t : channel.rotation.times) {
        const glm::quat q = rotation_at(t, b);
        glm::quat before = rotation_at(t - h, b), after = rotation_at(t + h, b);
        if (glm::dot(before, q) < 0.0f) before = -before;
        if (glm::dot(after, q) < 0.0f) after = -after;
        const glm::quat in = (q - before) / h, out = (after - q) / h;
        largest_jump =
            std::max(largest_jump, glm::length(glm::vec4(out.x - in.x, out.y - in.y, out.z - in.z, out.w - in.w)));
        largest_speed = std::max(largest_speed, glm::length(glm::vec4(out.x, out.y, out.z, out.w)));
      }
    }
    CHECK(largest_jump < 0.05f * largest_speed);
  }
}

TEST_CASE("builtin_full_rig: builtin_rig's arm lattices, then the right arm and both legs, every one binding points") {
  const Model& m = character();
  const deform::Rig arm = deform::builtin_rig(m), full = deform::builtin_full_rig(m);
  REQUIRE(arm.lattices.size() == 3);
  REQUIRE(full.lattices.size() == 12);
  for (std::size_t l = 0; l < 3; ++l) CHECK(full.lattices[l] == arm.lattices[l]);
  const char* bones[] = {"upperarm_l", "forearm_l", "hand_l", "upperarm_r", "forearm_r", "hand_r",
                         "thigh_l",    "shin_l",    "foot_l", "thigh_r",    "shin_r",    "foot_r"};
  for (std::size_t l = 0; l < 12; ++l) {
    INFO(bones[l]);
    CHECK(full.lattices[l].name == bones[l]);
    CHECK(full.lattices[l].bone == id(bones[l]));
    CHECK(full.lattices[l].elastic == arm.lattices[0].elastic);
  }
  CHECK(full.reach_effector == arm.reach_effector);
  CHECK(full.reach_root == arm.reach_root);
  CHECK(full.model.builtin);

  const deform::Character c(deform::builtin_character(), full);
  REQUIRE(c.deformers().lattice_count() == 12);
  for (std::size_t l = 0; l < 12; ++l) {
    INFO(bones[l]);
    CHECK(c.deformers().bound_count(l) > 20);
  }
  // Each limb's lattices nest like the left arm's: upper, then lower, then the end.
  for (std::size_t limb = 0; limb < 4; ++limb) {
    CHECK(c.deformers().parent(3 * limb) == -1);
    CHECK(c.deformers().parent(3 * limb + 1) == std::int32_t(3 * limb));
    CHECK(c.deformers().parent(3 * limb + 2) == std::int32_t(3 * limb + 1));
  }
  // The mirror: the right limbs bind about as many points as the left ones (the weights' ties go to the lower bone
  // id, so not exactly as many).
  for (const std::size_t l : {0, 1, 2, 6, 7, 8}) {
    INFO(bones[l]);
    CHECK(double(c.deformers().bound_count(l + 3)) ==
          doctest::Approx(double(c.deformers().bound_count(l))).epsilon(0.05));
  }
}
