// IK solvers: seeded random chains and targets, limits, unreachable targets, degenerate limbs, invalid input.
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/pose_json.hpp"
#include "ik_random_rigs.hpp"  // fixtures/: random rigs (the IK benchmarks use them too)

#include "allocation_counter.hpp"  // allocations: a solve allocates nothing

using namespace deform;
using ik_rigs::RandomChain;

namespace {

constexpr float not_a_number = std::numeric_limits<float>::quiet_NaN();
constexpr float inf = std::numeric_limits<float>::infinity();

// World matrices of every bone by the skeleton module's FK (LocalToWorldJob).
Status world_matrices(const Skeleton& skeleton, const Pose& pose, std::span<glm::mat4> world) {
  LocalToWorldJob fk;
  fk.skeleton = &skeleton;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  return fk.run();
}

// Effector head by the skeleton module's full FK, independent of the solvers' chain FK.
glm::vec3 reference_effector(const Skeleton& skeleton, const Pose& pose, std::int32_t effector) {
  std::vector<glm::mat4> world(skeleton.bone_count());
  REQUIRE(world_matrices(skeleton, pose, world));
  return glm::vec3(world[static_cast<std::size_t>(effector)][3]);
}

// One CCD or FABRIK solve by the job: its base from chain_base, a scratch of the size the job states.
Status solve(IkMethod method, const IkChain& chain, Pose& pose, glm::vec3 target, const IkSettings& settings,
             IkResult& result) {
  RigidTransform base;
  if (const Status status = chain_base(chain, pose.rotations, pose.translations, base); !status) return status;
  std::vector<std::byte> scratch(IkJob::scratch_size(chain.joint_count()));
  IkJob job;
  job.method = method;
  job.chain = &chain;
  job.base = base;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.target = target;
  job.settings = settings;
  job.scratch = scratch;
  job.result = &result;
  return job.run();
}

Status solve_two_bone(const IkChain& chain, Pose& pose, glm::vec3 target, glm::vec3 pole, float tolerance,
                      IkResult& result) {
  TwoBoneIkJob job;
  job.chain = &chain;
  if (const Status status = chain_base(chain, pose.rotations, pose.translations, job.base); !status) return status;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.target = target;
  job.pole = pole;
  job.tolerance = tolerance;
  job.result = &result;
  return job.run();
}

// Every bone other than the chain's joints keeps its rotation; every joint is within its limits.
void check_pose(const RandomChain& rig, const Pose& before, const Pose& after) {
  for (std::size_t b = 0; b < rig.skeleton.bone_count(); ++b) {
    CHECK(after.translations[b] == before.translations[b]);
    const bool joint = b >= 1 && b <= rig.joints;
    if (!joint) CHECK(after.rotations[b] == before.rotations[b]);
    else CHECK(ik_rigs::rotation_within_limits(after.rotations[b], rig.skeleton.bones()[b].limits));
  }
}

struct Rates {
  int reached = 0, cases = 0;
  long iterations = 0;
  double rate() const { return double(reached) / cases; }
  double mean_iterations() const { return double(iterations) / cases; }
};

// Random chains of 2–6 joints, targets from random in-limit poses, tolerance 1e-4 of the chain length.
Rates reachable_targets(IkMethod method, bool escape_stalls, int cases, std::uint32_t seed, bool check_every_pose) {
  std::mt19937 random(seed);
  Rates rates;
  for (int c = 0; c < cases; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2 + c % 5);
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = rig.skeleton.bind_pose();
    const Pose before = pose;
    IkSettings settings;
    settings.tolerance = 1e-4f * rig.length;
    settings.max_iterations = 200;
    settings.escape_stalls = escape_stalls;
    IkResult result;
    REQUIRE(solve(method, chain, pose, target, settings, result));
    const glm::vec3 effector = reference_effector(rig.skeleton, pose, rig.effector);
    // The result describes the pose it leaves.
    CHECK(result.distance == doctest::Approx(glm::length(effector - target)).epsilon(1e-3).scale(rig.length));
    CHECK(result.reached == (result.distance <= settings.tolerance));
    CHECK(result.iterations <= settings.max_iterations);
    if (check_every_pose) check_pose(rig, before, pose);
    rates.reached += result.reached;
    rates.iterations += result.iterations;
    ++rates.cases;
  }
  return rates;
}

// Per-axis limits of every kind: free, locked, any range within [-180, 180] (y beyond ±90 too, so that either Euler
// triple can be the one within the limits). y bounds keep 1° from ±90: there a float quaternion cannot hold x and z
// apart to the tests' 0.01°, whichever clamp made it.
DofLimits general_limits(std::mt19937& random) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto near_gimbal = [](float y) { return std::abs(std::abs(y) - 90.0f) < 1.0f; };
  DofLimits limits;
  for (int axis = 0; axis < 3; ++axis) {
    do {
      const float kind = unit(random);
      limits.min[axis] = -180.0f, limits.max[axis] = 180.0f;
      if (kind < 0.3f) {
        limits.min[axis] = limits.max[axis] = -180.0f + 360.0f * unit(random);
      } else if (kind >= 0.45f) {
        limits.min[axis] = -180.0f + 360.0f * unit(random);
        limits.max[axis] = limits.min[axis] + (180.0f - limits.min[axis]) * unit(random);
      }
    } while (axis == 1 && (near_gimbal(limits.min.y) || near_gimbal(limits.max.y)));
  }
  return limits;
}

// Skeleton::clamp_to_limits picks the nearer of a rotation's two Euler triples; when both are equally far (common:
// moving x and z by 180° moves one axis' excess up and the other's down by 180°) rounding decides, and the other
// triple clamped is as correct an answer. That answer, when the two distances tie within 1e-3°, else none.
std::optional<glm::quat> tied_answer(glm::quat rotation, const DofLimits& limits) {
  auto wrap = [](float a) { return a > 180.0f ? a - 360.0f : (a <= -180.0f ? a + 360.0f : a); };
  auto excess = [&](glm::vec3 e) {
    const glm::vec3 d = e - clamp_euler(e, limits);
    return std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  };
  auto nearest_turn = [&](glm::vec3 e) {  // each angle ± 360 to the value nearest its range
    for (int axis = 0; axis < 3; ++axis)
      for (const float shift : {-360.0f, 360.0f})
        if (excess(glm::vec3(e[axis] + shift) * glm::vec3(axis == 0, axis == 1, axis == 2) +
                   e * glm::vec3(axis != 0, axis != 1, axis != 2)) < excess(e))
          e[axis] += shift;
    return e;
  };
  const glm::vec3 canonical = euler_from_quat(rotation);
  const glm::vec3 first = nearest_turn(canonical);
  const glm::vec3 second =
      nearest_turn(glm::vec3(wrap(canonical.x + 180.0f), wrap(180.0f - canonical.y), wrap(canonical.z + 180.0f)));
  if (std::abs(excess(first) - excess(second)) > 1e-3f) return std::nullopt;
  return quat_from_euler(clamp_euler(excess(second) < excess(first) ? first : second, limits));
}

// The angle between two rotations, radians (small angles exact to rounding).
double rotation_difference(glm::quat a, glm::quat b) {
  const glm::dquat p(a), q(glm::dot(a, b) < 0.0f ? -b : b);
  return 2.0 * glm::length(glm::dvec4(p.x - q.x, p.y - q.y, p.z - q.z, p.w - q.w));
}

}  // namespace

TEST_CASE("clamp_rotation agrees with the double-precision Skeleton::clamp_to_limits") {
  std::mt19937 random(606);
  std::normal_distribution<float> normal;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  int changed = 0, ties = 0;
  double worst = 0.0;
  for (int c = 0; c < 20000; ++c) {
    // The solvers' random limits and limits of every kind; uniform rotations, and every tenth near gimbal lock.
    const DofLimits limits = c % 2 ? general_limits(random) : ik_rigs::random_limits(random);
    glm::quat rotation = glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
    if (c % 10 == 0) {
      const float y = (c % 20 ? 90.0f : -90.0f) - 1e-3f * unit(random);
      rotation = quat_from_euler(glm::vec3{360.0f * unit(random) - 180.0f, y, 360.0f * unit(random) - 180.0f});
    }
    std::vector<Bone> bones(1);
    bones[0].limits = limits;
    const Skeleton skeleton(bones);
    Pose reference{{rotation}, {glm::vec3(0.0f)}};
    skeleton.clamp_to_limits(reference, 0);
    glm::quat fast = rotation;
    const bool clamped = clamp_rotation(prepare_limits(limits), fast);
    REQUIRE(clamped == (reference.rotations[0] != rotation));
    CHECK(ik_rigs::rotation_within_limits(fast, limits));
    double difference = rotation_difference(fast, reference.rotations[0]);
    if (difference > 4e-6) {
      const std::optional<glm::quat> other = tied_answer(rotation, limits);
      REQUIRE(other);
      difference = rotation_difference(fast, *other);
      ++ties;
    }
    CHECK(difference <= 4e-6);
    worst = std::max(worst, difference);
    changed += clamped;
  }
  MESSAGE("clamp_rotation vs clamp_to_limits: 20000 rotations, ", changed, " clamped, ", ties,
          " ties resolved the other way, largest difference ", worst, " rad");
  CHECK(changed > 15000);

  // Strictly within the limits nothing changes, to the bit (after normalisation); free limits change nothing at all.
  // (A rotation made from angles on a bound, a locked axis say, reads back a hair outside and is clamped onto it.)
  for (int c = 0; c < 2000; ++c) {
    DofLimits limits = ik_rigs::random_limits(random);
    glm::vec3 angles;
    for (int axis = 0; axis < 3; ++axis) {
      if (limits.min[axis] == limits.max[axis]) limits.min[axis] -= 10.0f, limits.max[axis] += 10.0f;
      angles[axis] = limits.min[axis] + (0.01f + 0.98f * unit(random)) * (limits.max[axis] - limits.min[axis]);
    }
    const glm::quat inside = quat_from_euler(angles);
    glm::quat rotation = inside;
    CHECK_FALSE(clamp_rotation(prepare_limits(limits), rotation));
    CHECK(rotation == glm::normalize(inside));
    const glm::quat any = glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
    rotation = any;
    CHECK_FALSE(clamp_rotation(prepare_limits(DofLimits{}), rotation));
    CHECK(rotation == glm::normalize(any));
  }
  CHECK(prepare_limits(DofLimits{}).free);
  CHECK(EulerLimits{}.free);
}

// Exactly within: an angle compared with its float limits, no slack (the contract the CLI's printed angles keep).
bool angles_within(glm::vec3 degrees, const DofLimits& limits) { return within_limits(degrees, limits, 0.0f); }

TEST_CASE("euler_within_limits: the triple the limits mean, within them; the rotation itself when it is within") {
  std::mt19937 random(77);
  std::normal_distribution<float> normal;
  int second_triple = 0;
  double worst = 0.0;
  for (int c = 0; c < 20000; ++c) {
    const DofLimits limits = ik_rigs::random_wide_limits(random);
    // In-limit rotations (every 8th exactly on a bound, y at ±90° among them): the same rotation back, inside.
    glm::vec3 angles = ik_rigs::random_in_limits(random, limits);
    if (c % 8 == 0) angles[c % 3] = c % 16 ? limits.min[c % 3] : limits.max[c % 3];
    const glm::quat inside = quat_from_euler(angles);
    const glm::vec3 e = euler_within_limits(inside, limits);
    CHECK(angles_within(e, limits));
    const double difference = rotation_difference(quat_from_euler(e), inside);
    CHECK(difference <= 1e-5);
    worst = std::max(worst, difference);
    second_triple += !within_limits(euler_from_quat(inside), limits, 1e-3f);
    // Any rotation: within the limits, and a fixed point (what is printed reads back as itself).
    const glm::quat any = glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
    const glm::vec3 clamped = euler_within_limits(any, limits);
    CHECK(angles_within(clamped, limits));
    const glm::quat back = quat_from_euler(clamped);
    CHECK(rotation_difference(quat_from_euler(euler_within_limits(back, limits)), back) <= 1e-5);
  }
  MESSAGE("euler_within_limits: 20000 in-limit rotations, ", second_triple,
          " of them only within in the non-canonical triple; largest difference ", worst, " rad");
  CHECK(second_triple > 1000);
  // Never NaN: a NaN or zero rotation reads as the identity, NaN angles clamp to the value nearest 0.
  const DofLimits limits{glm::vec3(10.0f, -30.0f, -180.0f), glm::vec3(20.0f, 30.0f, 180.0f)};
  const float nan = not_a_number;
  CHECK(euler_within_limits(glm::quat(nan, 0.0f, 0.0f, 0.0f), limits) == glm::vec3(10.0f, 0.0f, 0.0f));
  CHECK(euler_within_limits(glm::quat(0.0f, 0.0f, 0.0f, 0.0f), limits) == glm::vec3(10.0f, 0.0f, 0.0f));
  CHECK(clamp_euler(glm::vec3(nan, nan, 5.0f), limits) == glm::vec3(10.0f, 0.0f, 5.0f));
  glm::quat q(nan, nan, 0.0f, 1.0f);
  CHECK(clamp_rotation(prepare_limits(limits), q));
  CHECK(rotation_difference(q, quat_from_euler(glm::vec3(10.0f, 0.0f, 0.0f))) <= 1e-6);
  q = glm::quat(inf, 0.0f, 0.0f, 0.0f);
  CHECK(clamp_rotation(prepare_limits(DofLimits{}), q));
  CHECK(q == glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
}

// The contract, over random chains with limits up to ±180° on every axis: what the CLI prints of a solve
// (format_pose_bones_json: euler_within_limits of each joint) is within the limits, and reading it back as `deform
// skin --pose` does (parse_pose_json, clamping) gives the solver's own effector.
TEST_CASE(
    "property: printed angles of CCD and FABRIK solves are within limits up to ±180° and give the solver's effector") {
  std::mt19937 random(20261123);
  int cases = 0, non_canonical = 0;
  float worst = 0.0f;
  for (int c = 0; c < 4000; ++c) {
    const std::size_t joints = 2 + static_cast<std::size_t>(c % 5);
    const RandomChain rig = ik_rigs::random_chain(random, joints, false, -1, true);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    // Reachable targets, and every fourth anywhere around (often out of reach: the clamps work hardest there).
    const glm::vec3 target = c % 4 == 3 ? ik_rigs::chain_root_head(rig.skeleton.bind_pose()) +
                                              rig.length * 1.3f * ik_rigs::random_direction(random)
                                        : ik_rigs::random_reachable_target(random, rig);
    Pose pose = rig.skeleton.bind_pose();
    IkSettings settings;
    settings.tolerance = 1e-4f * rig.length;
    settings.max_iterations = 100;
    IkResult result;
    REQUIRE(solve(c % 2 ? IkMethod::fabrik : IkMethod::ccd, chain, pose, target, settings, result));
    const glm::vec3 solved = ik_rigs::effector_of(chain, pose.rotations, pose.translations);
    const std::span<const std::int32_t> bones(chain.bones);
    const Pose printed =
        parse_pose_json("{\"bones\": " + format_pose_bones_json(rig.skeleton, pose, bones) + "}", rig.skeleton);
    for (std::size_t k = 0; k < joints; ++k) {
      const auto b = static_cast<std::size_t>(chain.bones[k]);
      const DofLimits& limits = rig.skeleton.bones()[b].limits;
      const glm::vec3 e = euler_within_limits(pose.rotations[b], limits);
      CHECK(angles_within(e, limits));
      non_canonical += !within_limits(euler_from_quat(pose.rotations[b]), limits, 1e-3f);
    }
    const float moved = glm::length(ik_rigs::effector_of(chain, printed.rotations, printed.translations) - solved);
    CHECK(moved <= 2e-5f * rig.length);
    worst = std::max(worst, moved / rig.length);
    ++cases;
  }
  MESSAGE("printed solves: ", cases, " chains of 2-6 joints, ", non_canonical,
          " joints within their limits only in the non-canonical triple; largest effector move ", worst,
          " x chain length");
  CHECK(non_canonical > 500);
}

// The plain reference split, written differently from the library's: the swing is the shortest arc taking the axis
// to where the rotation takes it (so q = swing · twist with the swing's axis perpendicular to the axis), the twist
// what remains. (s1, s2, τ), radians.
glm::dvec3 reference_swing_twist(const SwingTwistLimits& limits, glm::quat rotation) {
  glm::dquat q = glm::normalize(glm::dquat(rotation));
  const glm::dvec3 a = glm::normalize(glm::dvec3(limits.axis)), b1(limits.reference), b2 = glm::cross(a, b1);
  const glm::dvec3 moved = q * a;
  const glm::dvec3 normal = glm::cross(a, moved);
  const double angle = std::atan2(glm::length(normal), glm::dot(a, moved));
  const glm::dvec3 u = glm::length(normal) > 1e-15 ? glm::normalize(normal) : glm::dvec3(0.0);
  const glm::dquat swing = glm::angleAxis(angle, glm::length(normal) > 1e-15 ? u : b1);
  glm::dquat twist = glm::conjugate(swing) * q;
  if (twist.w < 0.0) twist = -twist;
  const double tau = 2.0 * std::atan2(glm::dot(glm::dvec3(twist.x, twist.y, twist.z), a), twist.w);
  return {angle * glm::dot(u, b1), angle * glm::dot(u, b2), tau};
}

bool reference_within(const SwingTwistLimits& limits, glm::dvec3 split, double slack) {
  const double a = limits.swing1, b = limits.swing2;
  const double x = a > 0.0 ? split.x / (a + slack) : (std::abs(split.x) <= slack ? 0.0 : 2.0);
  const double y = b > 0.0 ? split.y / (b + slack) : (std::abs(split.y) <= slack ? 0.0 : 2.0);
  const double tau = split.z;
  const bool twist = (tau >= limits.twist_min - slack && tau <= limits.twist_max + slack) ||
                     (std::abs(std::abs(tau) - std::numbers::pi) <= slack &&
                      (limits.twist_min <= -std::numbers::pi + slack || limits.twist_max >= std::numbers::pi - slack));
  return x * x + y * y <= 1.0 && twist;
}

SwingTwistLimits random_swing_twist(std::mt19937& random) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float kind = unit(random);
  const float swing1 = kind < 0.1f ? 0.0f : 180.0f * unit(random);
  const float swing2 = kind < 0.3f ? swing1 : (kind < 0.35f ? 0.0f : 180.0f * unit(random));  // circular, flat
  float t0 = -180.0f + 360.0f * unit(random), t1 = -180.0f + 360.0f * unit(random);
  if (kind > 0.9f) t0 = -180.0f, t1 = 180.0f;
  if (kind > 0.8f && kind <= 0.85f) t1 = t0;  // locked twist
  return make_swing_twist_limits(ik_rigs::random_direction(random), swing1, swing2, t0, t1);
}

TEST_CASE("swing-twist limits: the split agrees with a plain reference; projection lands inside, nearest, idempotent") {
  std::mt19937 random(4242);
  std::normal_distribution<float> normal;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int inside = 0, projected = 0;
  for (int c = 0; c < 20000; ++c) {
    const SwingTwistLimits limits = random_swing_twist(random);
    const glm::quat q = glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
    const glm::dvec3 reference = reference_swing_twist(limits, q);
    const glm::vec3 split = swing_twist_angles(limits, q);
    if (glm::length(glm::dvec2(reference)) < 3.1) {  // away from a half-turn swing, where the split is not unique
      CHECK(std::abs(split.x - reference.x) <= 1e-5);
      CHECK(std::abs(split.y - reference.y) <= 1e-5);
      const double twist_gap = std::remainder(split.z - reference.z, 2.0 * std::numbers::pi);
      CHECK(std::abs(twist_gap) <= 1e-5);
    }
    glm::quat clamped = q;
    const bool changed = clamp_swing_twist(limits, clamped);
    if (reference_within(limits, reference, -1e-5)) {  // strictly inside: untouched
      CHECK_FALSE(changed);
      CHECK(clamped == glm::normalize(q));
      ++inside;
    }
    const glm::dvec3 after = reference_swing_twist(limits, clamped);
    CHECK(reference_within(limits, after, 1e-5));
    glm::quat again = clamped;
    clamp_swing_twist(limits, again);
    CHECK(rotation_difference(again, clamped) <= 1e-6);
    if (!changed) continue;
    ++projected;
    // Nearest: no sampled point of the ellipse is nearer the input's swing than the projected one, and the twist
    // went to its nearer limit.
    const glm::dvec2 from(reference), to(after);
    if (glm::length(from) < 3.1 && !reference_within(limits, glm::dvec3(from, limits.twist_min), 1e-9)) {
      for (int k = 0; k < 64; ++k) {
        const double phi = 2.0 * std::numbers::pi * unit(random);
        const glm::dvec2 rim(limits.swing1 * std::cos(phi), limits.swing2 * std::sin(phi));
        CHECK(glm::length(to - from) <= glm::length(rim - from) + 1e-5);
      }
      if (limits.swing1 == limits.swing2)  // a circular cone keeps the swing's direction
        CHECK(glm::length(to - from * (limits.swing1 / glm::length(from))) <= 1e-5);
    }
  }
  MESSAGE("swing-twist: 20000 random rotations, ", inside, " strictly inside, ", projected, " projected");
  CHECK(inside > 1000);
  CHECK(projected > 10000);
  // Never NaN.
  glm::quat bad(not_a_number, 0.0f, 1.0f, 0.0f);
  const SwingTwistLimits cone = make_swing_twist_limits(glm::vec3(0, 1, 0), 30.0f, 45.0f, 10.0f, 20.0f);
  CHECK(clamp_swing_twist(cone, bad));
  CHECK(reference_within(cone, reference_swing_twist(cone, bad), 1e-5));
  CHECK(std::isfinite(bad.w));
}

TEST_CASE("swing-twist limits: a flat cone (one swing limit thousands of times the other) still projects inside") {
  // A hinge-like joint given as a cone: 20° one way and (after degrees -> radians) a ten-thousandth of that or less the
  // other. The projection onto so flat an ellipse once stopped outside it.
  std::mt19937 random(77);
  std::normal_distribution<float> normal;
  int outside_before = 0;
  for (const float flat : {1e-2f, 1e-3f, 1e-4f, 1e-5f, 1e-6f}) {
    for (int c = 0; c < 500; ++c) {
      const SwingTwistLimits limits =
          make_swing_twist_limits(ik_rigs::random_direction(random), 20.0f, 20.0f * flat, -30.0f, 30.0f);
      const glm::quat q = glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
      if (!reference_within(limits, reference_swing_twist(limits, q), 0.0)) ++outside_before;
      glm::quat clamped = q;
      clamp_swing_twist(limits, clamped);
      CHECK(reference_within(limits, reference_swing_twist(limits, clamped), 1e-5));
      glm::quat again = clamped;
      clamp_swing_twist(limits, again);
      CHECK(rotation_difference(again, clamped) <= 1e-6);
    }
  }
  CHECK(outside_before > 2000);  // nearly every rotation needed the projection
}

TEST_CASE("swing-twist joints in CCD and FABRIK chains end within their cones; bad chains are refused") {
  std::mt19937 random(9191);
  int reached = 0, cases = 0;
  for (int c = 0; c < 600; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2 + c % 4);
    IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    for (std::size_t k = 0; k < chain.joint_count(); ++k)
      if ((c + k) % 3 != 0) {
        const glm::vec3 bone = rig.skeleton.bones()[static_cast<std::size_t>(chain.bones[k + 1])].bind_translation;
        set_swing_twist(
            chain, k,
            swing_twist_from_euler(rig.skeleton.bones()[static_cast<std::size_t>(chain.bones[k])].limits, bone));
      }
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    Pose pose = rig.skeleton.bind_pose();
    IkSettings settings;
    settings.tolerance = 1e-4f * rig.length;
    settings.max_iterations = 200;
    IkResult result;
    REQUIRE(solve(c % 2 ? IkMethod::fabrik : IkMethod::ccd, chain, pose, target, settings, result));
    for (std::size_t k = 0; k < chain.joint_count(); ++k) {
      const glm::quat q = pose.rotations[static_cast<std::size_t>(chain.bones[k])];
      if (chain.swing_twist[k].active)
        CHECK(reference_within(chain.swing_twist[k], reference_swing_twist(chain.swing_twist[k], q), 1e-4));
      else
        CHECK(
            ik_rigs::rotation_within_limits(q, rig.skeleton.bones()[static_cast<std::size_t>(chain.bones[k])].limits));
    }
    CHECK(result.distance == doctest::Approx(glm::length(reference_effector(rig.skeleton, pose, rig.effector) - target))
                                 .scale(rig.length)
                                 .epsilon(1e-3));
    reached += result.reached;
    ++cases;
  }
  MESSAGE("swing-twist chains: ", reached, " of ", cases, " reachable-by-Euler targets reached");
  CHECK(reached > cases / 2);
  IkChain chain = make_chain(ik_rigs::random_chain(random, 3).skeleton, 1, 4);
  CHECK_THROWS_AS(set_swing_twist(chain, 3, SwingTwistLimits{}), Error);
  chain.swing_twist.resize(1);
  Pose pose = ik_rigs::random_chain(random, 3).skeleton.bind_pose();
  IkResult result;
  const Status status = solve(IkMethod::ccd, chain, pose, glm::vec3(0.0f), IkSettings{}, result);
  CHECK_FALSE(status);
  CHECK(std::string(status.reason()) == "swing_twist has neither 0 nor one entry per joint");
}

TEST_CASE("make_chain finds root..effector and rejects anything else") {
  std::mt19937 random(1);
  const RandomChain rig = ik_rigs::random_chain(random, 3);
  const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
  CHECK(chain.bones == std::vector<std::int32_t>{1, 2, 3, 4});
  CHECK(chain.ancestors == std::vector<std::int32_t>{0});
  CHECK(chain.joint_count() == 3);
  CHECK(chain.limits.size() == 3);
  CHECK(chain.max_bone == 4);
  for (std::size_t k = 0; k < 3; ++k) {
    const EulerLimits expected = prepare_limits(rig.skeleton.bones()[k + 1].limits);
    CHECK(chain.limits[k].min == expected.min);
    CHECK(chain.limits[k].max == expected.max);
    CHECK(chain.limits[k].free == expected.free);
  }
  CHECK(chain_length(chain, rig.skeleton.bind_pose().translations) == doctest::Approx(rig.length));
  // The sibling (last bone) is not below the chain root's chain; the effector is not an ancestor of the root.
  const auto sibling = static_cast<std::int32_t>(rig.skeleton.bone_count() - 1);
  CHECK_THROWS_AS(make_chain(rig.skeleton, rig.root, sibling), Error);
  CHECK_THROWS_AS(make_chain(rig.skeleton, rig.effector, rig.root), Error);
  CHECK_THROWS_AS(make_chain(rig.skeleton, rig.root, rig.root), Error);
  CHECK_THROWS_AS(make_chain(rig.skeleton, -1, rig.effector), Error);
  CHECK_THROWS_AS(make_chain(rig.skeleton, rig.root, 99), Error);
  // effector_position and chain_base agree with the skeleton module's FK.
  const Pose pose = ik_rigs::random_in_limit_pose(random, rig);
  const glm::vec3 e = ik_rigs::effector_of(chain, pose.rotations, pose.translations);
  CHECK(glm::length(e - reference_effector(rig.skeleton, pose, rig.effector)) < 1e-5f * rig.length);
  std::vector<glm::mat4> world(rig.skeleton.bone_count());
  REQUIRE(world_matrices(rig.skeleton, pose, world));
  RigidTransform base;
  REQUIRE(chain_base(chain, pose.rotations, pose.translations, base));
  const RigidTransform from_fk = RigidTransform::from_matrix(world[0]);
  CHECK(glm::length(base.translation - from_fk.translation) < 1e-6f);
  CHECK(std::abs(glm::dot(base.rotation, from_fk.rotation)) == doctest::Approx(1.0f).epsilon(1e-6));
  for (int c = 0; c < 4; ++c) CHECK(glm::length(base.matrix()[c] - world[0][c]) < 1e-6f);
  // Spans too short: nothing computed.
  const std::span<const glm::quat> short_rotations = std::span<const glm::quat>(pose.rotations).first(4);
  CHECK_FALSE(chain_base(chain, short_rotations, pose.translations, base));
  glm::vec3 unwritten(7.0f);
  CHECK_FALSE(effector_position(chain, short_rotations, pose.translations, unwritten));
  CHECK(unwritten == glm::vec3(7.0f));
  CHECK_FALSE(effector_position(IkChain{}, pose.rotations, pose.translations, unwritten));
  CHECK(chain_length(chain, std::span<const glm::vec3>(pose.translations).first(4)) == 0.0f);
}

TEST_CASE("assign_chain rebuilds a chain in its own storage: no allocation once reserved, reasons for bad chains") {
  std::mt19937 random(2);
  const RandomChain rig = ik_rigs::random_chain(random, 5);
  IkChain chain;
  chain.bones.reserve(max_chain_bones);
  chain.ancestors.reserve(rig.skeleton.bone_count());
  chain.limits.reserve(max_chain_bones);
  std::vector<IkChain> made;
  for (std::int32_t effector = 2; effector <= rig.effector; ++effector)
    for (std::int32_t root = 0; root < effector; ++root) made.push_back(make_chain(rig.skeleton, root, effector));
  std::size_t n = 0;
  const long before = allocations.load();
  for (std::int32_t effector = 2; effector <= rig.effector; ++effector) {
    for (std::int32_t root = 0; root < effector; ++root, ++n) {
      REQUIRE(assign_chain(chain, rig.skeleton, root, effector));
      CHECK(chain.bones == made[n].bones);
      CHECK(chain.ancestors == made[n].ancestors);
      CHECK(chain.max_bone == made[n].max_bone);
      REQUIRE(chain.limits.size() == made[n].limits.size());
      for (std::size_t k = 0; k < chain.limits.size(); ++k) CHECK(chain.limits[k].min == made[n].limits[k].min);
    }
  }
  CHECK(allocations.load() == before);
  const auto sibling = static_cast<std::int32_t>(rig.skeleton.bone_count() - 1);
  CHECK(std::string(assign_chain(chain, rig.skeleton, rig.root, sibling).reason()) ==
        "root is not an ancestor of the effector");
  CHECK(chain.bones.empty());
  CHECK(chain.max_bone == -1);
  CHECK(std::string(assign_chain(chain, rig.skeleton, -1, 2).reason()) == "root bone out of range");
  CHECK(std::string(assign_chain(chain, rig.skeleton, 0, 99).reason()) == "effector out of range");
  CHECK_FALSE(assign_chain(chain, rig.skeleton, 2, 2));

  // A chain of 256 bones is the longest.
  std::vector<Bone> bones(300);
  for (std::size_t b = 0; b < bones.size(); ++b) {
    bones[b].parent = static_cast<std::int32_t>(b) - 1;
    if (b + 1 < bones.size()) bones[b].children = {static_cast<std::int32_t>(b + 1)};
    bones[b].bind_translation = glm::vec3(0.0f, b == 0 ? 0.0f : 0.01f, 0.0f);
  }
  const Skeleton rope(bones);
  CHECK(assign_chain(chain, rope, 10, 10 + 255));
  CHECK(chain.bones.size() == max_chain_bones);
  CHECK(std::string(assign_chain(chain, rope, 10, 10 + 256).reason()) == "chain longer than 256 bones");
  CHECK_THROWS_AS(make_chain(rope, 10, 10 + 256), Error);
}

TEST_CASE("CCD reaches >= 99.5% of reachable targets within limits; the stall escape is measured against plain CCD") {
  const Rates improved = reachable_targets(IkMethod::ccd, true, 3000, 2024, true);
  const Rates plain = reachable_targets(IkMethod::ccd, false, 3000, 2024, false);
  MESSAGE("CCD, 3000 chains of 2-6 joints, tolerance 1e-4 x length, cap 200: improved ", improved.rate() * 100,
          "% reached, ", improved.mean_iterations(), " mean iterations; plain ", plain.rate() * 100, "% reached, ",
          plain.mean_iterations(), " mean iterations");
  CHECK(improved.rate() >= 0.995);
  CHECK(improved.rate() > plain.rate());
}

TEST_CASE("FABRIK reaches >= 99.5% of reachable targets within limits") {
  const Rates improved = reachable_targets(IkMethod::fabrik, true, 3000, 7, true);
  const Rates plain = reachable_targets(IkMethod::fabrik, false, 3000, 7, false);
  MESSAGE("FABRIK, 3000 chains of 2-6 joints, tolerance 1e-4 x length, cap 200: improved ", improved.rate() * 100,
          "% reached, ", improved.mean_iterations(), " mean iterations; plain ", plain.rate() * 100, "% reached, ",
          plain.mean_iterations(), " mean iterations");
  CHECK(improved.rate() >= 0.995);
}

TEST_CASE("an unconstrained chain ends straight and pointing at an unreachable target") {
  std::mt19937 random(99);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int c = 0; c < 500; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2 + c % 5, /*free_joints=*/true);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    const Pose bind = rig.skeleton.bind_pose();
    const glm::vec3 root = ik_rigs::chain_root_head(bind);
    glm::vec3 direction{unit(random), unit(random), unit(random)};
    if (glm::length(direction) < 0.1f) direction = glm::vec3(1, 0, 0);
    const glm::vec3 target = root + glm::normalize(direction) * rig.length * (1.05f + 2.0f * (unit(random) + 1.0f));
    const float best = glm::length(target - root) - rig.length;
    // The solver stops within its tolerance of its own floor, which it computes through another float path:
    // allow the rounding of |target - root| (a few ulp) on top.
    const float slack = 1e-4f * rig.length + 4.0f * std::numeric_limits<float>::epsilon() * glm::length(target - root);
    IkSettings settings;
    settings.tolerance = 1e-4f * rig.length;
    settings.max_iterations = 200;
    IkResult ccd, fabrik;
    Pose ccd_pose = bind, fabrik_pose = bind;
    REQUIRE(solve(IkMethod::ccd, chain, ccd_pose, target, settings, ccd));
    REQUIRE(solve(IkMethod::fabrik, chain, fabrik_pose, target, settings, fabrik));
    CHECK_FALSE(ccd.reached);
    CHECK_FALSE(fabrik.reached);
    CHECK(std::abs(ccd.distance - best) <= slack);
    CHECK(std::abs(fabrik.distance - best) <= slack);
    CHECK(std::abs(glm::length(ik_rigs::effector_of(chain, ccd_pose.rotations, ccd_pose.translations) - target) -
                   best) <= slack);
  }
}

TEST_CASE("with limits, an unreachable target leaves the pose in limits and no farther than the start") {
  std::mt19937 random(5);
  for (int c = 0; c < 300; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2 + c % 5);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    const Pose bind = rig.skeleton.bind_pose();
    const glm::vec3 root = ik_rigs::chain_root_head(bind);
    const glm::vec3 target = root + glm::vec3(0.6f, -0.8f, 0.0f) * (3.0f * rig.length);
    const float start = glm::length(reference_effector(rig.skeleton, bind, rig.effector) - target);
    for (int which = 0; which < 2; ++which) {
      Pose pose = bind;
      IkResult result;
      IkSettings settings;
      REQUIRE(solve(which == 0 ? IkMethod::ccd : IkMethod::fabrik, chain, pose, target, settings, result));
      CHECK_FALSE(result.reached);
      CHECK(result.distance <= start + 1e-5f * rig.length);
      CHECK(result.distance >= glm::length(target - root) - rig.length - 1e-5f * rig.length);
      check_pose(rig, bind, pose);
    }
  }
}

TEST_CASE("a starting pose outside the limits is clamped; a solve allocates nothing") {
  std::mt19937 random(11);
  const RandomChain rig = ik_rigs::random_chain(random, 4);
  Pose pose = rig.skeleton.bind_pose();
  for (std::size_t b = 1; b <= rig.joints; ++b) pose.rotations[b] = glm::angleAxis(3.0f, glm::vec3(0.6f, 0.0f, 0.8f));
  const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
  std::vector<std::byte> scratch(IkJob::scratch_size(chain.joint_count()));
  IkResult result;
  IkJob job;
  job.chain = &chain;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.target = ik_rigs::random_reachable_target(random, rig);
  job.scratch = scratch;
  job.result = &result;
  CHECK(job.scratch_size() == scratch.size());
  const RandomChain limb = ik_rigs::random_chain(random, 2);
  const IkChain limb_chain = make_chain(limb.skeleton, limb.root, limb.effector);
  Pose limb_pose = limb.skeleton.bind_pose();
  TwoBoneIkJob two_bone;
  two_bone.chain = &limb_chain;
  two_bone.rotations = limb_pose.rotations;
  two_bone.translations = limb_pose.translations;
  two_bone.target = ik_rigs::random_reachable_target(random, limb);
  const long allocations_before = allocations.load();
  REQUIRE(chain_base(chain, pose.rotations, pose.translations, job.base));
  REQUIRE(job.run());
  job.method = IkMethod::fabrik;
  REQUIRE(job.run());
  REQUIRE(chain_base(limb_chain, limb_pose.rotations, limb_pose.translations, two_bone.base));
  REQUIRE(two_bone.run());
  CHECK(allocations.load() == allocations_before);
  for (std::size_t b = 1; b <= rig.joints; ++b)
    CHECK(ik_rigs::rotation_within_limits(pose.rotations[b], rig.skeleton.bones()[b].limits));
}

TEST_CASE("IK jobs: count() is 1, run(begin, end) solves for [0, 1), the same as run(); equal inputs, equal outputs") {
  std::mt19937 random(12);
  const RandomChain rig = ik_rigs::random_chain(random, 5);
  const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
  std::vector<std::byte> scratch(IkJob::scratch_size(chain.joint_count()));
  for (const IkMethod method : {IkMethod::ccd, IkMethod::fabrik}) {
    Pose first = rig.skeleton.bind_pose(), second = first;
    IkResult a, b;
    IkJob job;
    job.method = method;
    job.chain = &chain;
    job.target = ik_rigs::random_reachable_target(random, rig);
    job.settings.tolerance = 1e-5f * rig.length;
    job.scratch = scratch;
    REQUIRE(chain_base(chain, first.rotations, first.translations, job.base));
    CHECK(job.count() == 1);
    job.rotations = first.rotations, job.translations = first.translations, job.result = &a;
    REQUIRE(job.run());
    job.rotations = second.rotations, job.translations = second.translations, job.result = &b;
    CHECK(job.run(0, 0));
    CHECK(second.rotations == rig.skeleton.bind_pose().rotations);
    REQUIRE(job.run(0, 1));
    CHECK(first.rotations == second.rotations);
    CHECK(a.distance == b.distance);
    CHECK(a.iterations == b.iterations);
    CHECK_FALSE(job.run(0, 2));
    CHECK_FALSE(job.run(1, 0));
  }
}

TEST_CASE("random_state carries the stall escape's generator from solve to solve") {
  // Hard targets (limits that pin joints) send the solver into its random kicks; a carried state differs from the
  // seed after the first kick, and a solve started from a given state repeats exactly.
  std::mt19937 random(13);
  int kicked = 0;
  for (int c = 0; c < 200 && kicked < 5; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 4);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    std::vector<std::byte> scratch(IkJob::scratch_size(chain.joint_count()));
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    Pose pose = rig.skeleton.bind_pose(), again = pose;
    std::uint32_t state = ik_random_seed;
    IkJob job;
    job.chain = &chain;
    job.target = target;
    job.settings.tolerance = 1e-6f * rig.length;
    job.settings.max_iterations = 200;
    job.scratch = scratch;
    job.random_state = &state;
    REQUIRE(chain_base(chain, pose.rotations, pose.translations, job.base));
    job.rotations = pose.rotations, job.translations = pose.translations;
    REQUIRE(job.run());
    if (state == ik_random_seed) continue;
    ++kicked;
    job.random_state = nullptr;  // from the seed again: the same solve
    job.rotations = again.rotations, job.translations = again.translations;
    REQUIRE(job.run());
    CHECK(again.rotations == pose.rotations);
  }
  CHECK(kicked > 0);
}

// One solve by the job with a pole and a weight.
Status solve_with(IkMethod method, const IkChain& chain, Pose& pose, glm::vec3 target, const IkSettings& settings,
                  std::optional<glm::vec3> pole, float weight, IkResult& result) {
  std::vector<std::byte> scratch(IkJob::scratch_size(chain.joint_count()));
  IkJob job;
  job.method = method;
  job.chain = &chain;
  if (const Status status = chain_base(chain, pose.rotations, pose.translations, job.base); !status) return status;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.target = target;
  job.settings = settings;
  job.scratch = scratch;
  job.use_pole = pole.has_value();
  job.pole = pole.value_or(glm::vec3(0.0f));
  job.weight = weight;
  job.result = &result;
  return job.run();
}

// The mean of the inner joints' heads, across the line root → effector (model space), and the pole's part across it.
std::pair<glm::vec3, glm::vec3> across_line(const RandomChain& rig, const Pose& pose, glm::vec3 pole) {
  std::vector<glm::mat4> world(rig.skeleton.bone_count());
  REQUIRE(world_matrices(rig.skeleton, pose, world));
  const glm::vec3 root(world[1][3]), axis = glm::normalize(glm::vec3(world[rig.joints + 1][3]) - root);
  glm::vec3 middle(0.0f);
  for (std::size_t b = 2; b <= rig.joints; ++b) middle += glm::vec3(world[b][3]) - root;
  middle /= static_cast<float>(rig.joints - 1);
  const glm::vec3 p = pole - root;
  return {middle - glm::dot(middle, axis) * axis, p - glm::dot(p, axis) * axis};
}

TEST_CASE("a pole swivels CCD and FABRIK chains toward it, keeping the effector; free chains face it exactly") {
  std::mt19937 random(515);
  int faced = 0, cases = 0, kept = 0;
  for (int c = 0; c < 400; ++c) {
    const bool free_joints = c % 2 == 0;
    const RandomChain rig = ik_rigs::random_chain(random, 2 + c % 4, free_joints);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    const glm::vec3 pole =
        ik_rigs::chain_root_head(rig.skeleton.bind_pose()) + 3.0f * ik_rigs::random_direction(random);
    IkSettings settings;
    settings.tolerance = 1e-4f * rig.length;
    settings.max_iterations = 200;
    const IkMethod method = c % 4 < 2 ? IkMethod::ccd : IkMethod::fabrik;
    Pose plain = rig.skeleton.bind_pose(), poled = plain;
    const Pose before = plain;
    IkResult plain_result, poled_result;
    REQUIRE(solve_with(method, chain, plain, target, settings, std::nullopt, 1.0f, plain_result));
    REQUIRE(solve_with(method, chain, poled, target, settings, pole, 1.0f, poled_result));
    check_pose(rig, before, poled);
    const glm::vec3 effector = reference_effector(rig.skeleton, poled, rig.effector);
    CHECK(poled_result.distance == doctest::Approx(glm::length(effector - target)).epsilon(1e-3).scale(rig.length));
    // The swivel never loses the solve: reached stays reached, unreached gets no farther.
    if (plain_result.reached) CHECK(poled_result.reached);
    else CHECK(poled_result.distance <= plain_result.distance + 1e-5f * rig.length);
    const auto [middle, wanted] = across_line(rig, poled, pole);
    if (glm::length(middle) < 1e-3f * rig.length || glm::length(wanted) < 1e-3f) continue;
    const float cosine = glm::dot(middle, wanted) / (glm::length(middle) * glm::length(wanted));
    ++cases;
    kept += plain_result.reached == poled_result.reached;
    if (free_joints) CHECK(cosine >= 0.9999f);  // nothing limits the root: the middle faces the pole
    faced += cosine > 0.0f;
  }
  MESSAGE("pole: ", faced, " of ", cases, " bent chains end with their middle on the pole's side");
  CHECK(faced >= cases * 3 / 4);
  CHECK(kept == cases);
}

TEST_CASE("weight blends the solve with the input pose: 0 leaves it bit-identical, 1 is the solve") {
  std::mt19937 random(616);
  for (int c = 0; c < 300; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2 + c % 5);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    IkSettings settings;
    settings.tolerance = 1e-4f * rig.length;
    const IkMethod method = c % 2 ? IkMethod::ccd : IkMethod::fabrik;
    // Start out of the limits too: weight 0 must not even clamp.
    Pose start = ik_rigs::random_in_limit_pose(random, rig);
    if (c % 3 == 0) start.rotations[1] = glm::normalize(glm::quat(0.3f, 0.9f, -0.2f, 0.4f));
    Pose zero = start, full = start, half = start, plain = start;
    IkResult zero_result, full_result, half_result, plain_result;
    REQUIRE(solve(method, chain, plain, target, settings, plain_result));
    REQUIRE(solve_with(method, chain, zero, target, settings, std::nullopt, 0.0f, zero_result));
    REQUIRE(solve_with(method, chain, full, target, settings, std::nullopt, 1.0f, full_result));
    REQUIRE(solve_with(method, chain, half, target, settings, std::nullopt, 0.5f, half_result));
    CHECK(std::memcmp(zero.rotations.data(), start.rotations.data(), start.rotations.size() * sizeof(glm::quat)) == 0);
    CHECK(zero_result.iterations == 0);
    CHECK(
        zero_result.distance ==
        doctest::Approx(glm::length(reference_effector(rig.skeleton, start, rig.effector) - target)).scale(rig.length));
    CHECK(std::memcmp(full.rotations.data(), plain.rotations.data(), plain.rotations.size() * sizeof(glm::quat)) == 0);
    CHECK(full_result.distance == plain_result.distance);
    check_pose(rig, start, half);
    CHECK(
        half_result.distance ==
        doctest::Approx(glm::length(reference_effector(rig.skeleton, half, rig.effector) - target)).scale(rig.length));
    // Halfway: each joint is the shortest-path slerp halfway from its input to the solve, clamped.
    for (std::size_t k = 0; k < chain.joint_count(); ++k) {
      const auto b = static_cast<std::size_t>(chain.bones[k]);
      const glm::quat from = start.rotations[b], to = full.rotations[b];
      glm::quat expected = glm::slerp(from, glm::dot(from, to) < 0.0f ? -to : to, 0.5f);
      clamp_rotation(chain.limits[k], expected);
      CHECK(rotation_difference(half.rotations[b], expected) <= 1e-6);
    }
  }
}

TEST_CASE("max_step_degrees caps each CCD update and still converges") {
  std::mt19937 random(3);
  int reached = 0;
  for (int c = 0; c < 200; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 3, /*free_joints=*/true);
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    Pose pose = rig.skeleton.bind_pose();
    const Pose before = pose;
    IkSettings settings;
    settings.max_step_degrees = 2.0f;
    settings.max_iterations = 1;
    settings.escape_stalls = false;
    IkResult result;
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    REQUIRE(solve(IkMethod::ccd, chain, pose, target, settings, result));
    // One sweep turns each joint by at most 2 degrees.
    for (std::size_t b = 1; b <= rig.joints; ++b) {
      const float angle =
          glm::degrees(glm::angle(glm::normalize(glm::conjugate(before.rotations[b]) * pose.rotations[b])));
      CHECK(std::min(angle, 360.0f - angle) <= 2.0f + 1e-2f);
    }
    settings.max_iterations = 400;
    settings.tolerance = 1e-3f * rig.length;
    settings.escape_stalls = true;
    REQUIRE(solve(IkMethod::ccd, chain, pose, target, settings, result));
    reached += result.reached;
  }
  CHECK(reached >= 198);
}

TEST_CASE(
    "non-finite targets, poses and bases, overflowing chains, bad settings and scratch are refused, writing nothing") {
  std::mt19937 random(4);
  const RandomChain rig = ik_rigs::random_chain(random, 2);
  const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
  Pose pose = rig.skeleton.bind_pose();
  const Pose before = pose;
  IkResult result{true, 42.0f, 7};
  std::uint32_t state = 5;
  std::vector<std::byte> scratch(IkJob::scratch_size(chain.joint_count()) + IkJob::scratch_alignment);
  IkJob good;
  good.chain = &chain;
  good.rotations = pose.rotations;
  good.translations = pose.translations;
  good.target = glm::vec3(1, 0, 0);
  good.scratch = std::span<std::byte>(scratch).first(good.scratch_size());
  good.random_state = &state;
  good.result = &result;
  TwoBoneIkJob good_two;
  good_two.chain = &chain;
  good_two.rotations = pose.rotations;
  good_two.translations = pose.translations;
  good_two.target = glm::vec3(1, 0, 0);
  good_two.pole = glm::vec3(0, 0, 1);
  good_two.result = &result;
  REQUIRE(good.validate());
  REQUIRE(good_two.validate());

  auto refused = [&](const auto& job, const char* why) {
    const Status validated = job.validate(), ran = job.run();
    CHECK_FALSE(validated);
    CHECK_FALSE(ran);
    CHECK(std::string(ran.reason()) == why);
    CHECK(std::string(validated.reason()) == why);
  };
  for (const glm::vec3 bad : {glm::vec3(not_a_number, 0, 0), glm::vec3(0, inf, 0), glm::vec3(0, 0, -inf)}) {
    IkJob job = good;
    job.target = bad;
    refused(job, "target is not finite");
    job.method = IkMethod::fabrik;
    refused(job, "target is not finite");
    TwoBoneIkJob two = good_two;
    two.target = bad;
    refused(two, "target is not finite");
    two = good_two;
    two.pole = bad;
    refused(two, "pole is not finite");
    job = good;
    job.base.translation = bad;
    refused(job, "base is not finite");
    two = good_two;
    two.base.rotation.x = bad.x + bad.y + bad.z;
    refused(two, "base is not finite");
    job = good;
    job.pole = bad;
    CHECK(job.validate());  // an unused pole is not read
    job.use_pole = true;
    refused(job, "pole is not finite");
  }
  for (const float weight : {not_a_number, -0.01f, 1.01f, inf}) {
    IkJob job = good;
    job.weight = weight;
    refused(job, "weight not within [0, 1]");
  }
  // Non-finite entries of the chain's pose (other bones are not read), an overflowing chain length.
  for (const std::size_t bone : {std::size_t{1}, std::size_t{2}, std::size_t{3}}) {
    Pose broken = pose;
    broken.rotations[bone].y = not_a_number;
    IkJob job = good;
    job.rotations = broken.rotations;
    refused(job, "chain pose is not finite");
    TwoBoneIkJob two = good_two;
    two.rotations = broken.rotations;
    refused(two, "chain pose is not finite");
    broken = pose;
    broken.translations[bone].z = inf;
    job = good;
    job.translations = broken.translations;
    refused(job, "chain pose is not finite");
  }
  {
    Pose huge = pose;
    huge.translations[2] = glm::vec3(3e38f, 0, 0);
    huge.translations[3] = glm::vec3(3e38f, 0, 0);
    IkJob job = good;
    job.translations = huge.translations;
    refused(job, "chain length overflows");
    TwoBoneIkJob two = good_two;
    two.translations = huge.translations;
    refused(two, "chain length overflows");
    Pose sibling_nan = pose;  // a bone outside the chain and its ancestors is not read
    sibling_nan.rotations.back() = glm::quat(not_a_number, 0, 0, 0);
    job = good;
    job.rotations = sibling_nan.rotations;
    CHECK(job.validate());
  }
  IkJob job = good;
  job.settings.tolerance = not_a_number;
  refused(job, "tolerance not finite and >= 0");
  job = good;
  job.settings.max_iterations = 0;
  refused(job, "max_iterations below 1");
  job = good;
  job.settings.max_step_degrees = -1.0f;
  refused(job, "max_step_degrees not finite and >= 0");
  job = good;
  job.scratch = std::span<std::byte>(scratch).first(good.scratch_size() - 1);
  refused(job, "scratch smaller than scratch_size()");
  job = good;
  job.scratch = std::span<std::byte>(scratch).subspan(1, good.scratch_size());
  refused(job, "scratch misaligned");
  job = good;
  job.chain = nullptr;
  refused(job, "no chain");
  CHECK(job.scratch_size() == 0);
  job = good;
  job.rotations = std::span<glm::quat>(pose.rotations).first(3);
  refused(job, "pose spans do not hold every chain bone");
  TwoBoneIkJob two = good_two;
  two.tolerance = -1.0f;
  refused(two, "tolerance not finite and >= 0");
  two = good_two;
  two.translations = std::span<const glm::vec3>(pose.translations).first(2);
  refused(two, "pose spans do not hold every chain bone");
  const IkChain three = make_chain(rig.skeleton, 0, rig.effector);
  two = good_two;
  two.chain = &three;
  refused(two, "chain does not have two joints");
  for (std::size_t b = 0; b < pose.rotations.size(); ++b) CHECK(pose.rotations[b] == before.rotations[b]);
  CHECK(result.iterations == 7);
  CHECK(result.distance == 42.0f);
  CHECK(state == 5);
}

TEST_CASE("two-bone: exact for reachable targets, bends toward the pole, straight when out of reach") {
  std::mt19937 random(21);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int c = 0; c < 2000; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2, /*free_joints=*/true);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = ik_rigs::random_in_limit_pose(random, rig);
    const Pose before = pose;
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    const glm::vec3 pole{unit(random), unit(random), unit(random)};
    IkResult result;
    REQUIRE(solve_two_bone(chain, pose, target, pole, 1e-5f * rig.length, result));
    CHECK(result.iterations == 1);
    const glm::vec3 effector = reference_effector(rig.skeleton, pose, rig.effector);
    CHECK(glm::length(effector - target) <= 2e-5f * rig.length);
    CHECK(result.distance == doctest::Approx(glm::length(effector - target)).scale(rig.length).epsilon(1e-4));
    check_pose(rig, before, pose);
    // The middle joint is on the pole's side of the line root→target (outside the cone where the pose's plane
    // takes over).
    std::vector<glm::mat4> world(rig.skeleton.bone_count());
    REQUIRE(world_matrices(rig.skeleton, pose, world));
    const glm::vec3 root(world[1][3]), mid(world[2][3]);
    const glm::vec3 d = glm::normalize(target - root);
    const glm::vec3 mid_across = (mid - root) - d * glm::dot(mid - root, d);
    const glm::vec3 pole_across = pole - d * glm::dot(pole, d);
    if (glm::length(mid_across) > 1e-3f * rig.length &&
        glm::length(pole_across) >= two_bone_pole_cone_sine * glm::length(pole))
      CHECK(glm::dot(glm::normalize(mid_across), glm::normalize(pole_across)) > 0.999f);

    // Out of reach: the straight limb pointing at the target.
    Pose far_pose = before;
    const glm::vec3 far_target = root + glm::normalize(target - root + glm::vec3(1e-3f)) * (rig.length * 1.5f);
    REQUIRE(solve_two_bone(chain, far_pose, far_target, pole, 1e-5f * rig.length, result));
    CHECK_FALSE(result.reached);
    CHECK(std::abs(result.distance - 0.5f * rig.length) <= 1e-5f * rig.length);
    CHECK(glm::length(ik_rigs::effector_of(chain, far_pose.rotations, far_pose.translations) -
                      (root + glm::normalize(far_target - root) * rig.length)) <= 2e-5f * rig.length);
  }
}

TEST_CASE("two-bone degenerate limbs: zero-length bone, target on the root, pole on the line, straight start") {
  std::mt19937 random(8);
  SUBCASE("zero-length upper bone: refused, the pose untouched") {
    const RandomChain rig = ik_rigs::random_chain(random, 2, true, /*zero_bone=*/1);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = rig.skeleton.bind_pose();
    const Pose before = pose;
    const glm::vec3 root = ik_rigs::chain_root_head(pose);
    IkResult result;
    const Status status = solve_two_bone(chain, pose, root + glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), 1e-4f, result);
    CHECK_FALSE(status);
    CHECK(std::string(status.reason()) == "limb has a zero-length bone");
    CHECK(pose.rotations == before.rotations);
  }
  SUBCASE("target on the root: folded as far as the bones allow") {
    const RandomChain rig = ik_rigs::random_chain(random, 2, true);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = rig.skeleton.bind_pose();
    const glm::vec3 root = ik_rigs::chain_root_head(pose);
    const float a = glm::length(pose.translations[2]), b = glm::length(pose.translations[3]);
    IkResult result;
    REQUIRE(solve_two_bone(chain, pose, root, glm::vec3(0, 1, 0), 1e-4f, result));
    CHECK(result.distance == doctest::Approx(std::abs(a - b)).scale(a + b).epsilon(1e-4));
    CHECK(ik_rigs::finite_pose(pose));
  }
  SUBCASE("pole along root→target or zero keeps the bend plane; a straight start bends toward the pole") {
    const RandomChain rig = ik_rigs::random_chain(random, 2, true);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = rig.skeleton.bind_pose();
    const glm::vec3 root = ik_rigs::chain_root_head(pose);
    const glm::vec3 target = root + glm::vec3(0.3f, 0.4f, 0.2f) * rig.length;
    IkResult result;
    for (const glm::vec3 pole : {target - root, glm::vec3(0.0f), root - target}) {
      REQUIRE(solve_two_bone(chain, pose, target, pole, 1e-5f * rig.length, result));
      CHECK(result.reached);
      CHECK(ik_rigs::finite_pose(pose));
    }
    // Straight limb (every joint at identity, bones along one line) and a pole: bends toward it.
    std::vector<Bone> bones(3);
    bones[0].name = "upper";
    bones[0].children = {1};
    bones[1].name = "lower";
    bones[1].parent = 0;
    bones[1].children = {2};
    bones[1].bind_translation = glm::vec3(0, 1, 0);
    bones[2].name = "hand";
    bones[2].parent = 1;
    bones[2].bind_translation = glm::vec3(0, 1, 0);
    const Skeleton straight(bones);
    const IkChain limb = make_chain(straight, 0, 2);
    Pose straight_pose = straight.bind_pose();
    REQUIRE(solve_two_bone(limb, straight_pose, glm::vec3(0, 1.2f, 0), glm::vec3(0, 0, 1), 1e-5f, result));
    CHECK(result.reached);
    std::vector<glm::mat4> world(3);
    REQUIRE(world_matrices(straight, straight_pose, world));
    CHECK(world[1][3].z > 0.5f);  // the elbow went toward +z
    CHECK(std::abs(world[1][3].x) < 1e-5f);
  }
}

TEST_CASE("two-bone with limits never leaves them; exact whenever the closed form is inside them") {
  std::mt19937 random(31);
  int exact = 0;
  for (int c = 0; c < 2000; ++c) {
    const RandomChain rig = ik_rigs::random_chain(random, 2);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = rig.skeleton.bind_pose();
    const Pose before = pose;
    const glm::vec3 target = ik_rigs::random_reachable_target(random, rig);
    IkResult result;
    REQUIRE(solve_two_bone(chain, pose, target, glm::vec3(0, 0, 1), 1e-4f * rig.length, result));
    check_pose(rig, before, pose);
    exact += result.reached;
  }
  MESSAGE("two-bone with random limits: ", exact / 20.0, "% of reachable targets met exactly after clamping");
  CHECK(exact > 0);
}
