// The built-in character: skeleton, body (generalised cylinders swept along the bones), atlas UVs, texture, weights.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/runtime/error.hpp"
#include "deform/offline/weights.hpp"
namespace deform {
namespace {

// ----------------------------------------------------------------------------------------------------------------
// Skeleton. Translations are in the parent's frame, rotations are Euler X·Y·Z degrees (docs/formats.md).
// Every chain child sits on its parent's local +Y axis, so a bone's direction is its local +Y.

DofLimits limits(glm::vec3 min, glm::vec3 max) { return {min, max}; }

// The character's right side is its left side mirrored through the plane x = 0: S = diag(-1, 1, 1). For a bone frame
// R' = S·R·S, so Euler X stays and Y, Z change sign; a translation in the (mirrored) parent frame is S·t.
Bone mirrored(const Bone& left) {
  Bone right = left;
  right.bind_translation.x = -left.bind_translation.x;
  right.bind_rotation = {left.bind_rotation.x, -left.bind_rotation.y, -left.bind_rotation.z};
  right.limits.min = {left.limits.min.x, -left.limits.max.y, -left.limits.max.z};
  right.limits.max = {left.limits.max.x, -left.limits.min.y, -left.limits.min.z};
  return right;
}

std::vector<Bone> character_bones() {
  const DofLimits free;
  std::vector<Bone> bones = {
      // The root's +Y points forward (+Z), so spine (-90°) and legs (+90°) both leave it a quarter turn away.
      {"hips", -1, {}, {0.0f, 0.95f, 0.0f}, {90.0f, 0.0f, 0.0f}, free},
      {"spine", 0, {}, {0.0f, 0.0f, -0.10f}, {-90.0f, 0.0f, 0.0f}, limits({-115, -30, -25}, {-45, 30, 25})},
      {"chest", 1, {}, {0.0f, 0.20f, 0.0f}, {}, limits({-20, -30, -20}, {30, 30, 20})},
      {"neck", 2, {}, {0.0f, 0.25f, 0.0f}, {}, limits({-40, -60, -30}, {50, 60, 30})},
      {"head", 3, {}, {0.0f, 0.10f, 0.0f}, {}, limits({-30, -60, -20}, {30, 60, 20})},
  };
  // Left arm (+X), in the chest's frame. Arm frames: local X = world -Y, Y = world +X (along the arm), Z = world +Z.
  // Positive X rotation swings forward; positive Z raises; elbows and fingers bend one way only.
  const std::vector<Bone> left_arm = {
      {"clavicle_l", 2, {}, {0.02f, 0.20f, 0.0f}, {0.0f, 0.0f, -90.0f}, limits({-10, -20, -100}, {10, 20, -60})},
      {"upperarm_l", 0, {}, {0.0f, 0.15f, 0.0f}, {}, limits({-45, -80, -85}, {135, 80, 90})},
      {"forearm_l", 1, {}, {0.0f, 0.28f, 0.0f}, {}, limits({0, -80, 0}, {150, 80, 0})},
      {"hand_l", 2, {}, {0.0f, 0.26f, 0.0f}, {}, limits({-20, -10, -80}, {30, 10, 70})},
      {"fingers1_l", 3, {}, {0.0f, 0.09f, 0.0f}, {}, limits({-10, 0, -90}, {10, 0, 10})},
      {"fingers2_l", 4, {}, {0.0f, 0.05f, 0.0f}, {}, limits({0, 0, -100}, {0, 0, 0})},
      {"thumb1_l", 3, {}, {0.005f, 0.02f, 0.03f}, {45.0f, 0.0f, 0.0f}, limits({-20, -30, -60}, {60, 30, 20})},
      {"thumb2_l", 6, {}, {0.0f, 0.04f, 0.0f}, {}, limits({0, 0, -80}, {0, 0, 10})},
  };
  // Left leg, in the hips' frame. Leg frames: local X = world +X, Y = world -Y (down the leg), Z = world -Z; the
  // thigh flexes forward as X decreases from its bind 90°, the knee bends backward for X in [0, 150].
  const std::vector<Bone> left_leg = {
      {"thigh_l", 0, {}, {0.09f, 0.0f, 0.05f}, {90.0f, 0.0f, 0.0f}, limits({-30, -40, -45}, {110, 40, 20})},
      {"shin_l", 0, {}, {0.0f, 0.40f, 0.0f}, {}, limits({0, -10, 0}, {150, 10, 0})},
      {"foot_l", 1, {}, {0.0f, 0.42f, 0.0f}, {-65.0f, 0.0f, 0.0f}, limits({-85, -20, -15}, {-20, 20, 15})},
      {"toe_l", 2, {}, {0.0f, 0.13f, 0.0f}, {-25.0f, 0.0f, 0.0f}, limits({-65, 0, 0}, {5, 0, 0})},
  };
  // Appends a limb: parent indices inside the list are relative to the limb's first bone, except the first's.
  auto append = [&](const std::vector<Bone>& limb, bool mirror) {
    const auto first = static_cast<std::int32_t>(bones.size());
    for (std::size_t i = 0; i < limb.size(); ++i) {
      Bone bone = mirror ? mirrored(limb[i]) : limb[i];
      if (mirror) bone.name.back() = 'r';
      bone.parent = i == 0 ? limb[0].parent : first + limb[i].parent;
      bones.push_back(std::move(bone));
    }
  };
  append(left_arm, false);
  append(left_arm, true);
  append(left_leg, false);
  append(left_leg, true);
  for (std::size_t b = 1; b < bones.size(); ++b)
    bones[static_cast<std::size_t>(bones[b].parent)].children.push_back(static_cast<std::int32_t>(b));
  return bones;
}

// ----------------------------------------------------------------------------------------------------------------
// Body: 13 closed tubes. A tube runs straight from `start` to `end`; its cross-section is an ellipse with radius r1
// along e1 and r2 along e2 = t × e1, interpolated between profile keys; both ends are closed by two cap rings and a
// pole (a rounded end). Rings crowd around the joints so that elbows and knees bend smoothly.

struct ProfileKey {
  float t;              // 0 at start, 1 at end
  float r1, r2;         // metres
  glm::vec3 shift{0.0f};  // world offset of the ring centre (mirrored with the part)
};

struct Part {
  std::string name;
  glm::vec3 start, end, e1;
  int rings;      // body rings, caps not counted
  int segments;   // points per ring
  std::vector<ProfileKey> keys;
  std::vector<float> joints;  // t of the joints the rings crowd around
  float cap_start = 1.0f, cap_end = 1.0f;  // cap length / mean end radius
};

ProfileKey profile(const Part& part, float t) {
  const std::vector<ProfileKey>& k = part.keys;
  if (t <= k.front().t) return k.front();
  for (std::size_t i = 1; i < k.size(); ++i)
    if (t <= k[i].t) {
      const float s = (t - k[i - 1].t) / (k[i].t - k[i - 1].t);
      const float f = s * s * (3.0f - 2.0f * s);  // smoothstep: no creases at the keys
      return {t, k[i - 1].r1 + f * (k[i].r1 - k[i - 1].r1), k[i - 1].r2 + f * (k[i].r2 - k[i - 1].r2),
              k[i - 1].shift + f * (k[i].shift - k[i - 1].shift)};
    }
  return k.back();
}

// Ring parameters in [0, 1]: equal steps of a density that is three times higher near each joint.
std::vector<float> ring_positions(const Part& part) {
  constexpr int samples = 1024;
  std::vector<float> cumulative(samples + 1, 0.0f);
  for (int i = 0; i < samples; ++i) {
    const float t = (static_cast<float>(i) + 0.5f) / samples;
    float density = 1.0f;
    for (float j : part.joints) density += 2.0f * std::exp(-(t - j) * (t - j) / (0.07f * 0.07f));
    cumulative[static_cast<std::size_t>(i) + 1] = cumulative[static_cast<std::size_t>(i)] + density;
  }
  std::vector<float> rings;
  std::size_t i = 0;
  for (int r = 0; r < part.rings; ++r) {
    const float target = cumulative.back() * static_cast<float>(r) / static_cast<float>(part.rings - 1);
    while (i + 1 < samples && cumulative[i + 1] < target) ++i;
    const float span = cumulative[i + 1] - cumulative[i];
    const float within = span > 0.0f ? std::clamp((target - cumulative[i]) / span, 0.0f, 1.0f) : 0.0f;
    rings.push_back((static_cast<float>(i) + within) / samples);
  }
  return rings;
}

Part mirror_part(Part part) {
  part.name.back() = 'r';
  auto s = [](glm::vec3 v) { return glm::vec3(-v.x, v.y, v.z); };
  part.start = s(part.start);
  part.end = s(part.end);
  part.e1 = s(part.e1);
  for (ProfileKey& k : part.keys) k.shift = s(k.shift);
  return part;
}

std::vector<Part> character_parts() {
  const glm::vec3 x(1, 0, 0), y(0, 1, 0);
  std::vector<Part> parts;
  parts.push_back({"torso", {0.0f, 0.83f, 0.0f}, {0.0f, 1.50f, 0.0f}, x, 18, 20,
                   {{0.00f, 0.120f, 0.090f},
                    {0.10f, 0.160f, 0.105f},
                    {0.21f, 0.165f, 0.105f, {0.0f, 0.0f, -0.010f}},
                    {0.36f, 0.140f, 0.095f},
                    {0.51f, 0.145f, 0.100f},
                    {0.67f, 0.160f, 0.110f, {0.0f, 0.0f, 0.010f}},
                    {0.85f, 0.170f, 0.100f},
                    {1.00f, 0.100f, 0.070f}},
                   {0.33f, 0.63f},
                   0.6f,
                   0.5f});
  parts.push_back({"neck", {0.0f, 1.46f, -0.005f}, {0.0f, 1.64f, 0.0f}, x, 4, 12,
                   {{0.0f, 0.055f, 0.060f}, {1.0f, 0.050f, 0.055f}}, {}, 0.5f, 0.5f});
  parts.push_back({"head", {0.0f, 1.60f, 0.01f}, {0.0f, 1.75f, 0.01f}, x, 10, 16,
                   {{0.00f, 0.055f, 0.060f},
                    {0.20f, 0.080f, 0.090f, {0.0f, 0.0f, 0.010f}},
                    {0.45f, 0.090f, 0.105f},
                    {0.75f, 0.085f, 0.100f},
                    {1.00f, 0.050f, 0.060f}},
                   {},
                   0.6f,
                   1.0f});
  const Part arm{"arm_l", {0.10f, 1.45f, 0.0f}, {0.71f, 1.45f, 0.0f}, y, 18, 12,
                 {{0.000f, 0.060f, 0.060f},
                  {0.115f, 0.062f, 0.065f},
                  {0.328f, 0.050f, 0.052f},
                  {0.525f, 0.043f, 0.045f},
                  {0.574f, 0.042f, 0.044f},
                  {0.689f, 0.044f, 0.047f},
                  {0.902f, 0.032f, 0.038f},
                  {1.000f, 0.025f, 0.033f}},
                 {0.115f, 0.574f, 1.0f},
                 0.6f,
                 0.6f};
  const Part hand{"hand_l", {0.69f, 1.45f, 0.0f}, {0.88f, 1.45f, 0.0f}, y, 7, 10,
                  {{0.00f, 0.022f, 0.035f},
                   {0.26f, 0.022f, 0.045f},
                   {0.58f, 0.018f, 0.045f},
                   {0.84f, 0.015f, 0.040f},
                   {1.00f, 0.012f, 0.032f}},
                  {0.58f},
                  0.6f,
                  0.8f};
  // Along the thumb bones (45° between +X and +Z), from just behind thumb1's head to near thumb2's tip.
  const glm::vec3 thumb_direction = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f));
  const glm::vec3 thumb_head(0.73f, 1.445f, 0.03f);
  const Part thumb{"thumb_l", thumb_head - 0.01f * thumb_direction, thumb_head + 0.07f * thumb_direction, y, 4, 8,
                   {{0.0f, 0.013f, 0.016f}, {0.6f, 0.012f, 0.014f}, {1.0f, 0.010f, 0.012f}}, {0.625f}, 1.0f, 1.0f};
  const Part leg{"leg_l", {0.09f, 0.98f, 0.0f}, {0.09f, 0.07f, 0.0f}, x, 20, 14,
                 {{0.000f, 0.075f, 0.080f},
                  {0.088f, 0.085f, 0.090f},
                  {0.253f, 0.075f, 0.080f},
                  {0.440f, 0.055f, 0.060f},
                  {0.527f, 0.050f, 0.055f},
                  {0.615f, 0.052f, 0.060f, {0.0f, 0.0f, -0.010f}},
                  {0.747f, 0.045f, 0.050f, {0.0f, 0.0f, -0.005f}},
                  {0.912f, 0.035f, 0.038f},
                  {1.000f, 0.033f, 0.035f}},
                 {0.088f, 0.527f, 0.99f},
                 0.5f,
                 0.6f};
  const Part foot{"foot_l", {0.09f, 0.04f, -0.05f}, {0.09f, 0.02f, 0.17f}, x, 7, 10,
                  {{0.00f, 0.035f, 0.040f},
                   {0.25f, 0.040f, 0.045f, {0.0f, 0.015f, 0.0f}},
                   {0.55f, 0.045f, 0.035f, {0.0f, 0.005f, 0.0f}},
                   {0.76f, 0.047f, 0.022f},
                   {1.00f, 0.040f, 0.016f}},
                  {0.77f},
                  0.8f,
                  0.8f};
  for (const Part& p : {arm, hand, thumb, leg, foot}) {
    parts.push_back(p);
    parts.push_back(mirror_part(p));
  }
  return parts;
}

// Atlas: a 4 × 4 grid of cells, one per part (part index = cell index, row-major from the bottom-left).
constexpr int atlas_cells = 4;
constexpr float atlas_margin = 0.04f;  // of a cell, so bilinear filtering never mixes parts

glm::vec2 atlas_uv(std::size_t part, float u, float v) {
  const float cell = 1.0f / atlas_cells;
  const glm::vec2 origin(static_cast<float>(part % atlas_cells) * cell, static_cast<float>(part / atlas_cells) * cell);
  const float inner = 1.0f - 2.0f * atlas_margin;
  return origin + cell * glm::vec2(atlas_margin + inner * u, atlas_margin + inner * v);
}

// Appends one tube: its points, its render vertices (a seam column duplicated for u = 1, one pole vertex per fan
// triangle) and its triangles, wound counter-clockwise seen from outside.
void add_part(Mesh& mesh, const Part& part, std::size_t part_index) {
  const glm::vec3 t = glm::normalize(part.end - part.start);
  const glm::vec3 e1 = glm::normalize(part.e1 - glm::dot(part.e1, t) * t);
  const glm::vec3 e2 = glm::cross(t, e1);
  const float length = glm::length(part.end - part.start);

  struct Ring {
    glm::vec3 centre;
    float r1, r2;
  };
  std::vector<Ring> rings;
  const std::vector<float> body = ring_positions(part);
  auto body_ring = [&](float s) {
    const ProfileKey k = profile(part, s);
    return Ring{part.start + s * length * t + k.shift, k.r1, k.r2};
  };
  // Caps: rings at 35° and 65° of a quarter ellipse whose length is cap × the mean end radius, then the pole.
  const float cap_angles[2] = {35.0f, 65.0f};
  auto cap_ring = [&](const Ring& end, float direction, float cap, float degrees) {
    const float a = degrees * std::numbers::pi_v<float> / 180.0f;
    const float cap_length = cap * 0.5f * (end.r1 + end.r2);
    return Ring{end.centre + direction * cap_length * std::sin(a) * t, end.r1 * std::cos(a), end.r2 * std::cos(a)};
  };
  const Ring first = body_ring(body.front()), last = body_ring(body.back());
  for (int i = 1; i >= 0; --i) rings.push_back(cap_ring(first, -1.0f, part.cap_start, cap_angles[i]));
  for (float s : body) rings.push_back(body_ring(s));
  for (int i = 0; i < 2; ++i) rings.push_back(cap_ring(last, 1.0f, part.cap_end, cap_angles[i]));
  const glm::vec3 pole_start = first.centre - part.cap_start * 0.5f * (first.r1 + first.r2) * t;
  const glm::vec3 pole_end = last.centre + part.cap_end * 0.5f * (last.r1 + last.r2) * t;

  const auto segments = static_cast<std::uint32_t>(part.segments);
  const auto ring_count = static_cast<std::uint32_t>(rings.size());
  const auto point_base = static_cast<std::uint32_t>(mesh.positions.size());
  const auto vertex_base = static_cast<std::uint32_t>(mesh.vertex_point.size());
  const float v_step = 1.0f / static_cast<float>(ring_count + 1);  // poles at v = 0 and 1

  // Points: pole_start, the rings, pole_end.
  mesh.positions.push_back(pole_start);
  for (const Ring& ring : rings)
    for (std::uint32_t j = 0; j < segments; ++j) {
      const float a = 2.0f * std::numbers::pi_v<float> * static_cast<float>(j) / static_cast<float>(segments);
      mesh.positions.push_back(ring.centre + ring.r1 * std::cos(a) * e1 + ring.r2 * std::sin(a) * e2);
    }
  mesh.positions.push_back(pole_end);
  const std::uint32_t pole_end_point = point_base + 1 + ring_count * segments;

  // Render vertices: `segments` for the start pole, (segments + 1) per ring, `segments` for the end pole.
  auto add_vertex = [&](std::uint32_t point, float u, float v) {
    mesh.vertex_point.push_back(point);
    mesh.vertex_uvs.push_back(atlas_uv(part_index, u, v));
  };
  const float u_step = 1.0f / static_cast<float>(segments);
  for (std::uint32_t j = 0; j < segments; ++j) add_vertex(point_base, (static_cast<float>(j) + 0.5f) * u_step, 0.0f);
  for (std::uint32_t r = 0; r < ring_count; ++r)
    for (std::uint32_t j = 0; j <= segments; ++j)
      add_vertex(point_base + 1 + r * segments + j % segments, static_cast<float>(j) * u_step,
                 static_cast<float>(r + 1) * v_step);
  for (std::uint32_t j = 0; j < segments; ++j) add_vertex(pole_end_point, (static_cast<float>(j) + 0.5f) * u_step, 1.0f);

  auto ring_vertex = [&](std::uint32_t r, std::uint32_t j) { return vertex_base + segments + r * (segments + 1) + j; };
  auto triangle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    mesh.triangles.insert(mesh.triangles.end(), {a, b, c});
  };
  const auto first_triangle = static_cast<std::uint32_t>(mesh.triangle_count());
  for (std::uint32_t j = 0; j < segments; ++j) triangle(vertex_base + j, ring_vertex(0, j + 1), ring_vertex(0, j));
  for (std::uint32_t r = 0; r + 1 < ring_count; ++r)
    for (std::uint32_t j = 0; j < segments; ++j) {
      triangle(ring_vertex(r, j), ring_vertex(r, j + 1), ring_vertex(r + 1, j + 1));
      triangle(ring_vertex(r, j), ring_vertex(r + 1, j + 1), ring_vertex(r + 1, j));
    }
  const std::uint32_t end_pole_vertex = vertex_base + segments + ring_count * (segments + 1);
  for (std::uint32_t j = 0; j < segments; ++j)
    triangle(ring_vertex(ring_count - 1, j), ring_vertex(ring_count - 1, j + 1), end_pole_vertex + j);
  mesh.submeshes.push_back(
      {first_triangle, static_cast<std::uint32_t>(mesh.triangle_count()) - first_triangle, 0, "builtin", part.name});
}

}  // namespace

Model builtin_character() {
  Model model;
  model.name = "builtin";
  model.skeleton = Skeleton(character_bones(), "builtin");

  Mesh& mesh = model.mesh;
  const std::vector<Part> parts = character_parts();
  for (std::size_t i = 0; i < parts.size(); ++i) add_part(mesh, parts[i], i);
  mesh.face_sizes.assign(mesh.triangle_count(), 3);
  mesh.face_corners = mesh.triangles;
  Material skin;
  skin.name = "skin";
  skin.ambient = glm::vec3(0.2f);
  skin.diffuse = glm::vec3(1.0f);
  skin.specular = glm::vec3(0.1f);
  skin.shininess = 16.0f;
  skin.diffuse_map = "builtin.png";
  mesh.materials.push_back(skin);
  std::vector<glm::vec3> scratch(mesh.point_count());
  mesh.vertex_normals.resize(mesh.vertex_count());
  compute_vertex_normals(mesh, mesh.positions, scratch, mesh.vertex_normals);

  model.weights = compute_automatic_weights(mesh, model.skeleton);
  return model;
}

namespace {

// Value noise on a periodic lattice: smooth (smoothstep between hashed lattice values), in [0, 1], deterministic.
float lattice_value(int x, int y, int period) {
  auto h = static_cast<std::uint32_t>(((x % period) + period) % period) * 73856093u ^
           static_cast<std::uint32_t>(((y % period) + period) % period) * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return static_cast<float>(h & 0xffffu) / 65535.0f;
}

float value_noise(float x, float y, int period) {
  const auto xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y));
  const float fx = x - static_cast<float>(xi), fy = y - static_cast<float>(yi);
  const float sx = fx * fx * (3.0f - 2.0f * fx), sy = fy * fy * (3.0f - 2.0f * fy);
  const float a = lattice_value(xi, yi, period), b = lattice_value(xi + 1, yi, period);
  const float c = lattice_value(xi, yi + 1, period), d = lattice_value(xi + 1, yi + 1, period);
  return (a + sx * (b - a)) + sy * ((c + sx * (d - c)) - (a + sx * (b - a)));
}

float smooth_band(float x, float from, float to, float soft) {  // 1 inside [from, to], soft edges
  auto step = [](float e0, float e1, float v) {
    const float t = std::clamp((v - e0) / (e1 - e0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
  };
  return step(from - soft, from + soft, x) * (1.0f - step(to - soft, to + soft, x));
}

glm::vec3 mix3(glm::vec3 a, glm::vec3 b, float t) { return a + std::clamp(t, 0.0f, 1.0f) * (b - a); }

// The painted colour (linear 0..1 RGB) of body part `part` at atlas coordinates (u around the part, v along it).
glm::vec3 painted(int part, float u, float v) {
  const glm::vec3 skin(0.93f, 0.74f, 0.62f), skin_shadow(0.80f, 0.55f, 0.47f), blush(0.92f, 0.58f, 0.54f);
  const glm::vec3 shirt(0.36f, 0.55f, 0.66f), shirt_dark(0.26f, 0.42f, 0.53f);
  const glm::vec3 trousers(0.30f, 0.30f, 0.40f), belt(0.33f, 0.22f, 0.15f), shoe(0.38f, 0.25f, 0.18f);
  const glm::vec3 hair(0.33f, 0.21f, 0.13f), eye(0.16f, 0.12f, 0.10f), lips(0.78f, 0.45f, 0.42f);
  constexpr float tau = 2.0f * std::numbers::pi_v<float>;
  // Brush strokes: stretched noise along u (around the part), plus a softer large-scale wash.
  const float strokes = value_noise(u * 24.0f, v * 6.0f, 24) - 0.5f;
  const float wash = value_noise(u * 6.0f + 3.0f * static_cast<float>(part), v * 3.0f, 64) - 0.5f;
  glm::vec3 c = skin;
  switch (part) {
    case 0: {  // torso: trousers, a belt, a shirt with a skin neckline; u = 0.75 is the front, 0.25 the back
      c = mix3(trousers, belt, smooth_band(v, 0.20f, 0.25f, 0.01f));
      c = mix3(c, shirt, smooth_band(v, 0.25f, 2.0f, 0.01f));
      c = mix3(c, shirt_dark, 0.35f * smooth_band(v, 0.25f, 0.45f, 0.08f));  // folds above the belt
      c = mix3(c, skin, smooth_band(v, 0.90f, 2.0f, 0.02f));
      break;
    }
    case 1: c = mix3(skin, skin_shadow, 0.5f * (1.0f - v)); break;  // the neck: darker under the chin
    case 2: {  // the head: a face in front (u = 0.75), hair on top and at the back
      const float du = u - 0.75f;
      auto dot = [&](float cu, float cv, float ru, float rv) {
        const float x = (u - cu) / ru, y = (v - cv) / rv;
        return std::exp(-(x * x + y * y) * 1.2f);
      };
      c = mix3(skin, blush, 0.45f * (dot(0.67f, 0.44f, 0.04f, 0.05f) + dot(0.83f, 0.44f, 0.04f, 0.05f)));
      c = mix3(c, eye, std::min(1.0f, 1.6f * (dot(0.705f, 0.54f, 0.018f, 0.025f) + dot(0.795f, 0.54f, 0.018f, 0.025f))));
      c = mix3(c, lips, 0.9f * dot(0.75f, 0.37f, 0.04f, 0.015f));
      const float hairline = 0.66f + 0.22f * std::cos(tau * du) * (std::abs(du) < 0.25f ? 1.0f : 0.5f);
      c = mix3(c, hair, smooth_band(v + 0.03f * strokes, hairline, 2.0f, 0.05f));
      break;
    }
    case 3:
    case 4: c = mix3(skin, shirt, smooth_band(v, -1.0f, 0.30f, 0.015f)); break;  // arms: short sleeves
    case 9:
    case 10: c = mix3(trousers, shoe, smooth_band(v, 0.93f, 2.0f, 0.01f)); break;  // legs: trousers
    case 11:
    case 12: c = shoe; break;
    case 5:
    case 6:
    case 7:
    case 8: c = mix3(skin, blush, 0.2f); break;  // hands and thumbs: a little pinker
    default: c = glm::vec3(0.75f); break;
  }
  // Painted shading: darker towards the ends of a part (where it meets its neighbours) and on its underside
  // (a cosine around u; for the limbs u = 0.5 is underneath, for the trunk the back), then the brush texture.
  const float ends = 1.0f - 0.22f * (1.0f - smooth_band(v, 0.12f, 0.88f, 0.1f));
  const float around = 0.92f + 0.08f * std::cos(tau * u);
  c *= ends * around;
  c *= 1.0f + 0.06f * strokes + 0.08f * wash;
  return glm::clamp(c, glm::vec3(0.0f), glm::vec3(1.0f));
}

}  // namespace

std::vector<std::uint8_t> builtin_texture(int size) {
  if (size < 16 || size > 4096 || (size & (size - 1)) != 0)
    throw Error::in_file("builtin texture", "size " + std::to_string(size), "must be a power of two from 16 to 4096");
  const auto n = static_cast<std::size_t>(size);
  std::vector<std::uint8_t> pixels(n * n * 3);
  const float cell = 1.0f / atlas_cells;
  const float inner = 1.0f - 2.0f * atlas_margin;
  for (int row = 0; row < size; ++row)
    for (int column = 0; column < size; ++column) {
      // Texel centre in UV space (row 0 is the top of the image, v = 1), then the cell and the part's own (u, v),
      // continued into the margin so that bilinear filtering at a cell's edge sees the same colours.
      const float s = (static_cast<float>(column) + 0.5f) / static_cast<float>(size);
      const float t = 1.0f - (static_cast<float>(row) + 0.5f) / static_cast<float>(size);
      const int cx = std::min(static_cast<int>(s / cell), atlas_cells - 1);
      const int cy = std::min(static_cast<int>(t / cell), atlas_cells - 1);
      const float u = std::clamp(((s - static_cast<float>(cx) * cell) / cell - atlas_margin) / inner, 0.0f, 1.0f);
      const float v = std::clamp(((t - static_cast<float>(cy) * cell) / cell - atlas_margin) / inner, 0.0f, 1.0f);
      const glm::vec3 c = painted(cy * atlas_cells + cx, u, v);
      for (int k = 0; k < 3; ++k)
        pixels[(static_cast<std::size_t>(row) * n + static_cast<std::size_t>(column)) * 3 + static_cast<std::size_t>(k)] =
            static_cast<std::uint8_t>(std::lround(255.0f * c[k]));
    }
  return pixels;
}

}  // namespace deform
