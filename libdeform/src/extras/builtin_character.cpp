// The built-in character: skeleton, body (a box-modelled cage, Catmull–Clark subdivided), atlas UVs, texture, weights.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/runtime/error.hpp"
#include "deform/offline/topology.hpp"
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
  // Ponytail (29–32), appended so the limbs keep their ids: from the back of the skull, backward then down behind
  // the neck (world X angles -120°, -160°, -175°, -180°), 0.30 m to its tip (the spring chain's, builtin_rig.cpp),
  // which stays above the shoulders: hanging lower, it would lie nearer the upper back than the chest bone does and
  // take the back's weights.
  // Each bone points along its local +Y. Its first bone is the head's only child, so the head's weight segment
  // (docs/builtin-character.md, "Automatic weights") runs from the head to the ponytail's root.
  bones.push_back(
      {"ponytail1", 4, {}, {0.0f, 0.16f, -0.085f}, {-120.0f, 0.0f, 0.0f}, limits({-170, -45, -45}, {-70, 45, 45})});
  bones.push_back(
      {"ponytail2", 29, {}, {0.0f, 0.10f, 0.0f}, {-40.0f, 0.0f, 0.0f}, limits({-90, -45, -45}, {10, 45, 45})});
  bones.push_back(
      {"ponytail3", 30, {}, {0.0f, 0.07f, 0.0f}, {-15.0f, 0.0f, 0.0f}, limits({-65, -45, -45}, {35, 45, 45})});
  bones.push_back(
      {"ponytail4", 31, {}, {0.0f, 0.07f, 0.0f}, {-5.0f, 0.0f, 0.0f}, limits({-55, -45, -45}, {45, 45, 45})});
  for (std::size_t b = 1; b < bones.size(); ++b)
    bones[static_cast<std::size_t>(bones[b].parent)].children.push_back(static_cast<std::int32_t>(b));
  return bones;
}

// ----------------------------------------------------------------------------------------------------------------
// Body: one closed, connected surface. A coarse quad cage is box-modelled in code — an octagonal torso whose side,
// top and bottom faces are extruded into the arms, the neck and head, and the legs; hands (mittens with a thumb) and
// feet are extruded from those — and refined by two Catmull–Clark subdivisions into a smooth, organic limit-like
// surface (every cage quad becomes 16). Every face keeps the body part (OBJ group, atlas cell) of its cage face.

enum BodyPart : int {
  torso,
  neck,
  head_part,
  arm_l,
  arm_r,
  hand_l,
  hand_r,
  thumb_l,
  thumb_r,
  leg_l,
  leg_r,
  foot_l,
  foot_r,
  hair_part
};
constexpr int body_part_count = 14;
constexpr std::array<std::string_view, body_part_count> body_part_names = {
    "torso",   "neck",    "head",  "arm_l", "arm_r",  "hand_l", "hand_r",
    "thumb_l", "thumb_r", "leg_l", "leg_r", "foot_l", "foot_r", "hair"};

struct Cage {
  std::vector<glm::vec3> points;
  std::vector<std::array<std::uint32_t, 4>> faces;  // counter-clockwise seen from outside
  std::vector<int> parts;                           // body part of each face

  std::uint32_t add(glm::vec3 p) {
    points.push_back(p);
    return static_cast<std::uint32_t>(points.size() - 1);
  }
  // A loop of a bending extrusion: its centre, its own cross-section axes and the half-widths along them.
  struct TubeLoop {
    glm::vec3 centre, a1, a2;
    float r1, r2;
  };
  // Extrudes face `f` through `loops` (one ring of 4 points each): side quads for each loop, the last loop's quad
  // replaces the face. Each loop has its own axes (turning continuously from e1, e2, so the winding is kept): the
  // corner with signs (s1, s2) of its offset from the face's centre along e1, e2 goes to centre + s1·r1·a1 + s2·r2·a2.
  // Returns the index of the cap face (the last loop's quad).
  std::size_t extrude_tube(std::size_t f, glm::vec3 e1, glm::vec3 e2, const std::vector<TubeLoop>& loops, int part) {
    std::array<std::uint32_t, 4> ring = faces[f];
    glm::vec3 centre(0.0f);
    for (std::uint32_t p : ring) centre += 0.25f * points[p];
    std::array<glm::vec2, 4> sign{};
    for (std::size_t k = 0; k < 4; ++k) {
      const glm::vec3 o = points[ring[k]] - centre;
      sign[k] = {glm::dot(o, e1) >= 0.0f ? 1.0f : -1.0f, glm::dot(o, e2) >= 0.0f ? 1.0f : -1.0f};
    }
    for (const TubeLoop& loop : loops) {
      std::array<std::uint32_t, 4> next{};
      for (std::size_t k = 0; k < 4; ++k)
        next[k] = add(loop.centre + sign[k].x * loop.r1 * loop.a1 + sign[k].y * loop.r2 * loop.a2);
      for (std::size_t k = 0; k < 4; ++k) {
        faces.push_back({ring[k], ring[(k + 1) % 4], next[(k + 1) % 4], next[k]});
        parts.push_back(part);
      }
      ring = next;
    }
    faces[f] = ring;
    parts[f] = part;
    return f;
  }
  // A loop of a straight extrusion: centre and the half-widths along the face's own axes.
  struct Loop {
    glm::vec3 centre;
    float r1, r2;
  };
  // extrude_tube() with every loop on the face's own axes: a new corner lies at its loop's centre ± r1·e1 ± r2·e2.
  std::size_t extrude(std::size_t f, glm::vec3 e1, glm::vec3 e2, const std::vector<Loop>& loops, int part) {
    std::vector<TubeLoop> tube;
    for (const Loop& loop : loops) tube.push_back({loop.centre, e1, e2, loop.r1, loop.r2});
    return extrude_tube(f, e1, e2, tube, part);
  }
};

// The left half's extrusions are mirrored for the right one; `side` is +1 (left, +X) or -1.
Cage body_cage() {
  Cage cage;
  // Torso: octagonal rings (flat faces at x = ±rx and z = ±rz), bottom to top.
  struct TorsoRing {
    float y, rx, rz, dz;
  };
  const TorsoRing torso_rings[] = {{0.80f, 0.160f, 0.115f, 0.000f},
                                   {0.98f, 0.165f, 0.120f, -0.005f},
                                   {1.18f, 0.150f, 0.115f, 0.005f},
                                   {1.37f, 0.185f, 0.120f, 0.000f},
                                   {1.535f, 0.170f, 0.095f, 0.000f}};
  const float c = std::tan(std::numbers::pi_v<float> / 8.0f);  // 0.414: octagon corners on the flat faces
  const glm::vec2 octagon[8] = {{1, c}, {c, 1}, {-c, 1}, {-1, c}, {-1, -c}, {-c, -1}, {c, -1}, {1, -c}};
  std::vector<std::array<std::uint32_t, 8>> rings;
  for (const TorsoRing& r : torso_rings) {
    std::array<std::uint32_t, 8> ring{};
    for (std::size_t k = 0; k < 8; ++k) ring[k] = cage.add({r.rx * octagon[k].x, r.y, r.rz * octagon[k].y + r.dz});
    rings.push_back(ring);
  }
  // Angles grow from +X towards +Z, so seen from outside (+Y is up) a side quad runs k → k+1 on the upper ring first.
  std::size_t arm_face[2] = {0, 0};
  for (std::size_t i = 0; i + 1 < rings.size(); ++i)
    for (std::size_t k = 0; k < 8; ++k) {
      const std::size_t k1 = (k + 1) % 8;
      if (i == 3 && k == 7) arm_face[0] = cage.faces.size();  // the +X face between the two top rings
      if (i == 3 && k == 3) arm_face[1] = cage.faces.size();  // the -X face
      cage.faces.push_back({rings[i][k], rings[i + 1][k], rings[i + 1][k1], rings[i][k1]});
      cage.parts.push_back(torso);
    }
  // Caps: the octagon as three quads (left, middle, right); wound outward (top seen from +Y, bottom from -Y).
  const auto& top = rings.back();
  const auto& bottom = rings.front();
  cage.faces.push_back({top[1], top[0], top[7], top[6]});
  const std::size_t neck_face = cage.faces.size();
  cage.faces.push_back({top[6], top[5], top[2], top[1]});
  cage.faces.push_back({top[5], top[4], top[3], top[2]});
  const std::size_t leg_face[2] = {cage.faces.size(), cage.faces.size() + 2};
  cage.faces.push_back({bottom[6], bottom[7], bottom[0], bottom[1]});
  cage.faces.push_back({bottom[1], bottom[2], bottom[5], bottom[6]});
  cage.faces.push_back({bottom[2], bottom[3], bottom[4], bottom[5]});
  for (int i = 0; i < 6; ++i) cage.parts.push_back(torso);

  const glm::vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  // Neck and head.
  const std::size_t head_top = cage.extrude(neck_face, x, z, {{{0.0f, 1.62f, 0.000f}, 0.050f, 0.055f}}, neck);
  cage.extrude(head_top, x, z,
               {{{0.0f, 1.665f, 0.012f}, 0.075f, 0.085f},
                {{0.0f, 1.75f, 0.010f}, 0.092f, 0.105f},
                {{0.0f, 1.815f, 0.000f}, 0.070f, 0.085f}},
               head_part);
  // Ponytail: from the upper back face of the head (between the loops at y = 1.75 and 1.815), a tube that leaves the
  // skull backward and bends down behind the neck to y ≈ 1.51, its loops following the ponytail bones.
  {
    std::size_t back = cage.faces.size();
    for (std::size_t f = 0; f < cage.faces.size(); ++f) {
      if (cage.parts[f] != head_part) continue;
      glm::vec3 centre(0.0f);
      for (std::uint32_t p : cage.faces[f]) centre += 0.25f * cage.points[p];
      if (centre.z < -0.05f && centre.y > 1.76f) back = f;
    }
    // Cross-section axes: x, and the tube's direction d turned +90° about x (+Y where the tube leaves backward).
    auto loop = [&](glm::vec3 centre, float angle_deg, float r1, float r2) {
      const float a = glm::radians(angle_deg);  // the tube's direction (0, cos a, sin a), as a bone's Euler X
      return Cage::TubeLoop{centre, x, {0.0f, -std::sin(a), std::cos(a)}, r1, r2};
    };
    cage.extrude_tube(
        back, x, y,
        {loop({0.0f, 1.775f, -0.140f}, -100.0f, 0.034f, 0.032f), loop({0.0f, 1.705f, -0.178f}, -135.0f, 0.028f, 0.027f),
         loop({0.0f, 1.632f, -0.200f}, -165.0f, 0.030f, 0.028f), loop({0.0f, 1.567f, -0.205f}, -178.0f, 0.024f, 0.022f),
         loop({0.0f, 1.515f, -0.205f}, -180.0f, 0.012f, 0.011f)},
        hair_part);
  }
  for (int s = 0; s < 2; ++s) {
    const float side = s == 0 ? 1.0f : -1.0f;
    const glm::vec3 out = side * x;  // along the arm
    // Arm: shoulder, elbow, wrist (y and z half-widths).
    const std::size_t wrist = cage.extrude(arm_face[s], y, z,
                                           {{{side * 0.25f, 1.45f, 0.0f}, 0.078f, 0.074f},
                                            {{side * 0.45f, 1.45f, 0.0f}, 0.056f, 0.058f},
                                            {{side * 0.71f, 1.45f, 0.0f}, 0.030f, 0.038f}},
                                           s == 0 ? arm_l : arm_r);
    // Hand: a mitten, flat (thin along y, wide along z), then the fingers' tip.
    cage.extrude(wrist, y, z,
                 {{{side * 0.79f, 1.45f, 0.0f}, 0.030f, 0.062f}, {{side * 0.93f, 1.45f, 0.0f}, 0.020f, 0.054f}},
                 s == 0 ? hand_l : hand_r);
    // Thumb: from the palm's front (+Z) face, towards the front and out.
    std::size_t front = cage.faces.size();
    for (std::size_t f = 0; f < cage.faces.size(); ++f) {
      if (cage.parts[f] != (s == 0 ? hand_l : hand_r)) continue;
      glm::vec3 centre(0.0f);
      for (std::uint32_t p : cage.faces[f]) centre += 0.25f * cage.points[p];
      if (centre.z > 0.03f && side * centre.x < 0.76f) front = f;
    }
    const glm::vec3 thumb_dir = glm::normalize(out + z);
    cage.extrude(front, y, glm::normalize(out - z),
                 {{glm::vec3(side * 0.745f, 1.445f, 0.075f) + 0.035f * thumb_dir, 0.015f, 0.016f}},
                 s == 0 ? thumb_l : thumb_r);
    // Leg: two thigh loops, knee, calf, ankle, heel.
    const float lx = side * 0.095f;
    const std::size_t sole = cage.extrude(leg_face[s], x, z,
                                          {{{lx, 0.72f, 0.008f}, 0.074f, 0.072f},
                                           {{lx, 0.61f, 0.004f}, 0.054f, 0.054f},
                                           {{lx, 0.47f, 0.005f}, 0.050f, 0.054f},
                                           {{lx, 0.30f, -0.010f}, 0.058f, 0.062f},
                                           {{lx, 0.12f, -0.005f}, 0.040f, 0.045f},
                                           {{lx, -0.005f, -0.010f}, 0.048f, 0.058f}},
                                          s == 0 ? leg_l : leg_r);
    cage.parts[sole] = s == 0 ? foot_l : foot_r;
    // Foot: from the front face of the heel block, forward; flat underneath.
    std::size_t instep = cage.faces.size();
    for (std::size_t f = 0; f < cage.faces.size(); ++f) {
      if (cage.parts[f] != (s == 0 ? leg_l : leg_r)) continue;
      glm::vec3 centre(0.0f);
      for (std::uint32_t p : cage.faces[f]) centre += 0.25f * cage.points[p];
      if (centre.y < 0.1f && centre.z > 0.03f) instep = f;
    }
    cage.parts[instep] = s == 0 ? foot_l : foot_r;
    cage.extrude(instep, x, y, {{{lx, 0.040f, 0.19f}, 0.048f, 0.040f}}, s == 0 ? foot_l : foot_r);
  }
  return cage;
}

// One Catmull–Clark step of a closed quad mesh. (GCC 12 at -O3, with order_points_by_part below in the same file,
// reports a free of a vector's buffer "with nonzero offset" here: a false positive of -Wfree-nonheap-object, which
// no line of this function matches.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wfree-nonheap-object"
#endif
Cage subdivide(const Cage& in) {
  Cage out;
  const std::size_t n = in.points.size();
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edge_index;  // → edge number
  std::vector<std::array<std::uint32_t, 2>> edges;
  std::vector<std::vector<std::size_t>> edge_faces;
  auto edge = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::minmax(a, b);
    const auto [it, inserted] =
        edge_index.try_emplace({key.first, key.second}, static_cast<std::uint32_t>(edges.size()));
    if (inserted) {
      edges.push_back({key.first, key.second});
      edge_faces.emplace_back();
    }
    return it->second;
  };
  std::vector<glm::vec3> face_point(in.faces.size());
  for (std::size_t f = 0; f < in.faces.size(); ++f) {
    glm::vec3 c(0.0f);
    for (std::uint32_t p : in.faces[f]) c += 0.25f * in.points[p];
    face_point[f] = c;
    for (std::size_t k = 0; k < 4; ++k) edge_faces[edge(in.faces[f][k], in.faces[f][(k + 1) % 4])].push_back(f);
  }
  // Vertex points: (F + 2R + (valence - 3)·P) / valence.
  std::vector<glm::vec3> face_sum(n, glm::vec3(0.0f)), mid_sum(n, glm::vec3(0.0f));
  std::vector<float> valence(n, 0.0f), face_count(n, 0.0f);
  for (std::size_t f = 0; f < in.faces.size(); ++f)
    for (std::uint32_t p : in.faces[f]) {
      face_sum[p] += face_point[f];
      face_count[p] += 1.0f;
    }
  for (const auto& e : edges) {
    const glm::vec3 mid = 0.5f * (in.points[e[0]] + in.points[e[1]]);
    for (std::uint32_t p : e) {
      mid_sum[p] += mid;
      valence[p] += 1.0f;
    }
  }
  for (std::size_t p = 0; p < n; ++p) {
    const float v = valence[p];
    out.points.push_back((face_sum[p] / face_count[p] + 2.0f * mid_sum[p] / v + (v - 3.0f) * in.points[p]) / v);
  }
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto& f = edge_faces[e];
    if (f.size() != 2) throw Error::in_file("builtin character", "body cage", "is not a closed 2-manifold");
    out.points.push_back(0.25f *
                         (in.points[edges[e][0]] + in.points[edges[e][1]] + face_point[f[0]] + face_point[f[1]]));
  }
  const auto face_base = static_cast<std::uint32_t>(out.points.size());
  for (const glm::vec3& c : face_point) out.points.push_back(c);
  for (std::size_t f = 0; f < in.faces.size(); ++f) {
    const auto& q = in.faces[f];
    for (std::size_t k = 0; k < 4; ++k) {
      const std::uint32_t next = static_cast<std::uint32_t>(n) + edge(q[k], q[(k + 1) % 4]);
      const std::uint32_t previous = static_cast<std::uint32_t>(n) + edge(q[(k + 3) % 4], q[k]);
      out.faces.push_back({q[k], next, face_base + static_cast<std::uint32_t>(f), previous});
      out.parts.push_back(in.parts[f]);
    }
  }
  return out;
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

// UVs: a 4 × 4 atlas, one cell per body part. Around a part's axis, u is the angle from the part's `front`
// direction over π (0 in front or on top, 1 behind or underneath: the two sides share the texture, so no part has a
// seam); v runs along the axis from `start` (0) to `end` (1).
struct PartAxis {
  glm::vec3 start, end, front;
};

PartAxis part_axis(int part) {
  const glm::vec3 y(0, 1, 0), z(0, 0, 1);
  auto mirror = [](PartAxis a) {
    a.start.x = -a.start.x;
    a.end.x = -a.end.x;
    return a;
  };
  switch (part) {
    case torso: return {{0.0f, 0.80f, 0.0f}, {0.0f, 1.52f, 0.0f}, z};
    case neck: return {{0.0f, 1.50f, 0.0f}, {0.0f, 1.63f, 0.0f}, z};
    case head_part: return {{0.0f, 1.60f, 0.0f}, {0.0f, 1.80f, 0.0f}, z};
    case arm_l: return {{0.17f, 1.45f, 0.0f}, {0.71f, 1.45f, 0.0f}, y};
    case hand_l: return {{0.71f, 1.45f, 0.0f}, {0.90f, 1.45f, 0.0f}, y};
    case thumb_l: return {{0.73f, 1.445f, 0.03f}, {0.79f, 1.445f, 0.11f}, y};
    case leg_l: return {{0.09f, 0.86f, 0.0f}, {0.09f, 0.04f, 0.0f}, z};
    case foot_l: return {{0.09f, 0.03f, -0.06f}, {0.09f, 0.03f, 0.22f}, y};
    case hair_part: return {{0.0f, 1.79f, -0.09f}, {0.0f, 1.50f, -0.205f}, -z};
    default: return mirror(part_axis(part - 1));  // the _r parts follow their _l ones
  }
}

glm::vec2 part_uv(int part, glm::vec3 p) {
  const PartAxis a = part_axis(part);
  const glm::vec3 t = glm::normalize(a.end - a.start);
  const float length = glm::length(a.end - a.start);
  const glm::vec3 d = p - a.start;
  const float v = std::clamp(glm::dot(d, t) / length, 0.0f, 1.0f);
  const glm::vec3 radial = d - glm::dot(d, t) * t;
  const glm::vec3 front = glm::normalize(a.front - glm::dot(a.front, t) * t);
  const float r = glm::length(radial);
  const float u =
      r > 1e-6f ? std::acos(std::clamp(glm::dot(radial / r, front), -1.0f, 1.0f)) / std::numbers::pi_v<float> : 0.5f;
  return {u, v};
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

// Renumbers the points part by part (the first part whose faces use them), along each part's axis: subdivision
// leaves a part's points spread over the whole array. A part's points then lie together, along a limb in the order
// of its bones, so that a lattice's bound points and the few points of the 33rd bone (whose skinning blocks look
// it up in a wider table) fill few blocks of 16 (the whole frame 2% faster).
void order_points_by_part(Mesh& mesh) {
  std::vector<std::pair<std::size_t, float>> key(mesh.positions.size(), {mesh.submeshes.size(), 0.0f});  // unused last
  for (std::size_t part = 0; part < mesh.submeshes.size(); ++part) {
    const Submesh& submesh = mesh.submeshes[part];
    const std::size_t first = 3 * std::size_t{submesh.first_triangle};
    for (std::size_t c = first; c < first + 3 * std::size_t{submesh.triangle_count}; ++c) {
      const std::uint32_t p = mesh.vertex_point[mesh.triangles[c]];
      if (key[p].first == mesh.submeshes.size()) key[p] = {part, part_uv(int(part), mesh.positions[p]).y};
    }
  }
  std::vector<std::uint32_t> order(mesh.positions.size());
  for (std::uint32_t p = 0; p < order.size(); ++p) order[p] = p;
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  std::vector<std::uint32_t> renumbered(order.size());
  std::vector<glm::vec3> positions(order.size());
  for (std::uint32_t n = 0; n < order.size(); ++n) renumbered[order[n]] = n, positions[n] = mesh.positions[order[n]];
  for (std::uint32_t& p : mesh.vertex_point) p = renumbered[p];
  mesh.positions = std::move(positions);
}

// The subdivided body as the model's mesh: triangles grouped by part (one submesh and OBJ group each), one render
// vertex per point and part it touches.
void build_body(Mesh& mesh) {
  Cage body = body_cage();
  for (int level = 0; level < 2; ++level) body = subdivide(body);
  mesh.positions = body.points;
  std::map<std::pair<std::uint32_t, int>, std::uint32_t> vertex_of;
  for (int part = 0; part < body_part_count; ++part) {
    const auto first = static_cast<std::uint32_t>(mesh.triangle_count());
    for (std::size_t f = 0; f < body.faces.size(); ++f) {
      if (body.parts[f] != part) continue;
      std::array<std::uint32_t, 4> v{};
      for (std::size_t k = 0; k < 4; ++k) {
        const std::uint32_t p = body.faces[f][k];
        const auto [it, inserted] =
            vertex_of.try_emplace({p, part}, static_cast<std::uint32_t>(mesh.vertex_point.size()));
        if (inserted) {
          mesh.vertex_point.push_back(p);
          const glm::vec2 uv = part_uv(part, mesh.positions[p]);
          mesh.vertex_uvs.push_back(atlas_uv(static_cast<std::size_t>(part), uv.x, uv.y));
        }
        v[k] = it->second;
      }
      // Split along the shorter diagonal.
      const auto& P = mesh.positions;
      const auto& q = body.faces[f];
      if (glm::length(P[q[0]] - P[q[2]]) <= glm::length(P[q[1]] - P[q[3]]))
        mesh.triangles.insert(mesh.triangles.end(), {v[0], v[1], v[2], v[0], v[2], v[3]});
      else mesh.triangles.insert(mesh.triangles.end(), {v[0], v[1], v[3], v[1], v[2], v[3]});
    }
    mesh.submeshes.push_back({first, static_cast<std::uint32_t>(mesh.triangle_count()) - first, 0});
  }
  order_points_by_part(mesh);
}

}  // namespace

std::span<const std::string_view> builtin_part_names() noexcept { return body_part_names; }

Model builtin_character() {
  Model model;
  model.name = "builtin";
  model.skeleton = Skeleton(character_bones(), "builtin");

  Mesh& mesh = model.mesh;
  build_body(mesh);
  mesh.face_sizes.assign(mesh.triangle_count(), 3);
  mesh.face_corners = mesh.triangles;
  order_vertices_by_point(mesh);  // render vertex p is point p's: normals() gathers in place with a move per seam copy
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
  // Brush strokes: stretched noise along u (around the part), plus a softer large-scale wash.
  const float strokes = value_noise(u * 24.0f, v * 6.0f, 24) - 0.5f;
  const float wash = value_noise(u * 6.0f + 3.0f * static_cast<float>(part), v * 3.0f, 64) - 0.5f;
  glm::vec3 c = skin;
  // u = 0 is the part's front (trunk, head, legs) or top (arms, hands, feet), u = 1 its back or underside; both
  // sides of a part share its cell (docs/builtin-character.md).
  auto dot = [&](float cu, float cv, float ru, float rv) {
    const float x = (u - cu) / ru, y = (v - cv) / rv;
    return std::exp(-(x * x + y * y) * 1.2f);
  };
  switch (part) {
    case 0: {  // torso: trousers, a belt, a shirt, folds above the belt, a collar line at the neck
      c = mix3(trousers, belt, smooth_band(v, 0.20f, 0.245f, 0.012f));
      c = mix3(c, shirt, smooth_band(v, 0.245f, 2.0f, 0.012f));
      c = mix3(c, shirt_dark, 0.35f * smooth_band(v, 0.25f, 0.45f, 0.08f));
      c = mix3(c, shirt_dark, 0.5f * smooth_band(v, 0.985f, 2.0f, 0.01f));
      break;
    }
    case 1: c = mix3(skin, skin_shadow, 0.45f * (1.0f - v) * (1.0f - v)); break;  // the neck: darker at the collar
    case 2: {  // the head: a face in front (u = 0), hair on the crown and at the back
      c = mix3(skin, blush, 0.45f * dot(0.17f, 0.38f, 0.05f, 0.05f));
      c = mix3(c, eye, std::min(1.0f, 1.6f * dot(0.095f, 0.50f, 0.025f, 0.025f)));
      c = mix3(c, lips, 0.9f * dot(0.0f, 0.30f, 0.10f, 0.03f));
      const float hairline = 0.80f - 0.48f * smooth_band(u, 0.55f, 2.0f, 0.2f);
      c = mix3(c, hair, smooth_band(v + 0.03f * strokes, hairline, 2.0f, 0.04f));
      break;
    }
    case 3:
    case 4: c = mix3(skin, shirt, smooth_band(v, -1.0f, 0.25f, 0.015f)); break;  // arms: short sleeves
    case 9:
    case 10: c = mix3(trousers, shoe, smooth_band(v, 0.95f, 2.0f, 0.012f)); break;  // legs: trousers to the ankle
    case 11:
    case 12: c = mix3(shoe, shoe * 0.6f, smooth_band(u, 0.85f, 2.0f, 0.04f)); break;  // shoes, darker soles
    case 5:
    case 6:
    case 7:
    case 8: c = mix3(skin, blush, 0.2f); break;                    // hands and thumbs: a little pinker
    case 13: c = mix3(hair, hair * 0.75f, 0.5f + strokes); break;  // the ponytail: hair, streaked along its length
    default: c = glm::vec3(0.75f); break;
  }
  // Painted shading: lighter in front or on top, darker behind or underneath, then the brush texture.
  c *= 0.92f + 0.08f * std::cos(std::numbers::pi_v<float> * u);
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
        pixels[(static_cast<std::size_t>(row) * n + static_cast<std::size_t>(column)) * 3 +
               static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(std::lround(255.0f * c[k]));
    }
  return pixels;
}

}  // namespace deform
