// TwoBoneIkJob's rigger parameters (pole, swivel, soften, stretch, weight): a plain double-precision reference of the
// geometry over thousands of seeded random limbs, the properties ik.hpp states, degenerate input, refusals.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/skeleton.hpp"
#include "ik_random_rigs.hpp"  // fixtures/: random rigs (the IK benchmarks use them too)

#include "allocation_counter.hpp"  // allocations: a solve allocates nothing

using namespace deform;

namespace {

constexpr double pi = 3.14159265358979323846;

// base (bone 0, the chain root's parent) → root (1) → middle (2) → effector (3), no limits. The job reads the bone
// lengths from the pose's translations, so one skeleton serves every random limb.
struct Limb {
  Skeleton skeleton;
  IkChain chain;
};

Limb make_limb() {
  std::vector<Bone> bones(4);
  for (int b = 0; b < 4; ++b) {
    bones[static_cast<std::size_t>(b)].name = "b" + std::to_string(b);
    bones[static_cast<std::size_t>(b)].parent = b - 1;
    if (b < 3) bones[static_cast<std::size_t>(b)].children = {b + 1};
    bones[static_cast<std::size_t>(b)].bind_translation = glm::vec3(0, 1, 0);
  }
  Skeleton skeleton(std::move(bones));
  IkChain chain = make_chain(skeleton, 1, 3);
  return {std::move(skeleton), std::move(chain)};
}

// A random limb pose at scale `scale`: base anywhere, random unit (and some non-unit) joint rotations.
struct LimbPose {
  std::vector<glm::quat> rotations;
  std::vector<glm::vec3> translations;
  double scale = 1.0;
};

glm::dvec3 random_unit(std::mt19937& random) {
  std::normal_distribution<double> normal;
  for (;;) {
    const glm::dvec3 v{normal(random), normal(random), normal(random)};
    if (glm::length(v) > 1e-3) return glm::normalize(v);
  }
}

glm::quat random_rotation(std::mt19937& random) {
  std::normal_distribution<float> normal;
  return glm::normalize(glm::quat{normal(random), normal(random), normal(random), normal(random)});
}

LimbPose random_limb_pose(std::mt19937& random) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  LimbPose pose;
  pose.scale = std::pow(10.0, -2.0 + 4.0 * unit(random));  // 0.01 .. 100
  const double s = pose.scale;
  pose.rotations = {random_rotation(random), random_rotation(random), random_rotation(random), random_rotation(random)};
  // A random direction, then a length between low and high (times the scale).
  const auto offset = [&](double low, double high) {
    const glm::dvec3 direction = random_unit(random);
    return glm::vec3(direction * (s * (low + (high - low) * unit(random))));
  };
  pose.translations = {offset(0.0, 3.0), offset(0.0, 0.5), offset(0.05, 1.5), offset(0.05, 1.5)};
  return pose;
}

// Model-space heads of root, middle and effector by plain forward kinematics in double.
struct Heads {
  glm::dvec3 root, middle, effector;
};

Heads heads(std::span<const glm::quat> rotations, std::span<const glm::vec3> translations) {
  glm::dquat frame(1.0, 0.0, 0.0, 0.0);
  glm::dvec3 head(0.0);
  glm::dvec3 out[4];
  for (std::size_t b = 0; b < 4; ++b) {
    head += frame * glm::dvec3(translations[b]);
    frame = frame * glm::normalize(glm::dquat(rotations[b]));
    out[b] = head;
  }
  return {out[1], out[2], out[3]};
}

// The reference: what ik.hpp says the limb ends as, from the geometry alone. Given the root head, the target, the
// bone lengths and the pole's unit direction across root → target (before swivel), the effector lies on the line at
// σ·c from the root and the middle joint on the circle of radius h about that line, in the reference half-plane.
struct Reference {
  double c = 0.0, stretch = 1.0;
  glm::dvec3 middle{0.0}, effector{0.0};
  bool pole_outside_cone = false;  // the middle joint's place is fixed by the pole alone
};

double soft_distance(double r, double a, double b, double soften) {
  const double reach = a + b;
  double c = std::min(r, reach);
  if (soften > 0.0) {
    const double zone = soften * reach;
    if (r > reach - zone) c = reach - zone * std::exp((reach - r) / zone - 1.0);
  }
  return std::max(c, std::abs(a - b));
}

Reference reference(const Heads& input, glm::dvec3 target, double a, double b, glm::dvec3 pole_vector, double soften,
                    double max_stretch, double swivel_degrees) {
  Reference ref;
  const glm::dvec3 to_target = target - input.root;
  const double r = glm::length(to_target);
  ref.c = soft_distance(r, a, b, soften);
  ref.stretch = std::clamp(r / ref.c, 1.0, max_stretch);
  const glm::dvec3 d = to_target / r;
  const double A = a * ref.stretch, B = b * ref.stretch, C = ref.c * ref.stretch;
  ref.effector = input.root + d * C;
  const glm::dvec3 across = pole_vector - d * glm::dot(pole_vector, d);
  ref.pole_outside_cone = glm::length(across) >= 1.0001 * two_bone_pole_cone_sine * glm::length(pole_vector);
  if (!ref.pole_outside_cone) return ref;
  glm::dvec3 e = glm::normalize(across);
  const double angle = swivel_degrees * pi / 180.0;
  e = e * std::cos(angle) + glm::cross(d, e) * std::sin(angle);
  const double x = (A * A - B * B + C * C) / (2.0 * C);  // along the line, from the law of cosines
  ref.middle = input.root + d * x + e * std::sqrt(std::max(0.0, A * A - x * x));
  return ref;
}

struct Params {
  glm::vec3 target{0.0f}, pole{0.0f};
  PoleKind kind = PoleKind::direction;
  float swivel = 0.0f, soften = 0.0f, weight = 1.0f, max_stretch = 1.0f;
};

struct Solve {
  Status status;
  IkResult result;
  float stretch = -1.0f;
  std::vector<glm::quat> rotations;
  std::vector<glm::vec3> translations;  // the stretched translations the job wrote (the input elsewhere)
};

Solve run_job(const IkChain& chain, const LimbPose& pose, const Params& p, float tolerance) {
  Solve out;
  out.rotations = pose.rotations;
  out.translations = pose.translations;
  TwoBoneIkJob job;
  job.chain = &chain;
  REQUIRE(chain_base(chain, pose.rotations, pose.translations, job.base));
  job.rotations = out.rotations;
  job.translations = pose.translations;
  job.target = p.target;
  job.pole = p.pole;
  job.pole_kind = p.kind;
  job.swivel_degrees = p.swivel;
  job.soften = p.soften;
  job.weight = p.weight;
  job.max_stretch = p.max_stretch;
  job.tolerance = tolerance;
  job.stretched_translations = out.translations;
  job.result = &out.result;
  job.stretch = &out.stretch;
  out.status = job.run();
  return out;
}

bool finite(glm::dvec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

TEST_CASE("two-bone matches the double-precision reference over 6,000 random limbs, scales 0.01 to 100") {
  const Limb limb = make_limb();
  std::mt19937 random(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int compared_middles = 0, reached_cases = 0, stretched = 0;
  double worst_effector = 0.0, worst_middle = 0.0;
  for (int c = 0; c < 6000; ++c) {
    const LimbPose pose = random_limb_pose(random);
    const Heads input = heads(pose.rotations, pose.translations);
    const double a = glm::length(glm::dvec3(pose.translations[2])), b = glm::length(glm::dvec3(pose.translations[3]));
    const double reach = a + b;
    Params p;
    p.soften = c % 3 == 0 ? 0.0f : static_cast<float>(unit(random));
    p.max_stretch = c % 4 == 0 ? 1.0f : static_cast<float>(1.0 + 2.0 * unit(random));
    p.swivel = c % 2 == 0 ? 0.0f : static_cast<float>(360.0 * unit(random) - 180.0);
    // Targets inside the folded reach, between, and beyond even the stretched reach.
    const double spread = unit(random);
    const double r = reach * 3.5 * spread * unit(random) + 1e-3 * reach;
    p.target = glm::vec3(input.root + random_unit(random) * r);
    p.kind = c % 5 < 2 ? PoleKind::point : PoleKind::direction;
    const glm::dvec3 pole_direction = random_unit(random);
    const glm::dvec3 pole_vector = pole_direction * (pose.scale * (0.1 + 3.0 * unit(random)));
    p.pole = glm::vec3(p.kind == PoleKind::point ? input.root + pole_vector : pole_vector);
    const glm::dvec3 read_pole = p.kind == PoleKind::point ? glm::dvec3(p.pole) - input.root : glm::dvec3(p.pole);

    const float tolerance = static_cast<float>(1e-5 * reach);
    const Solve solved = run_job(limb.chain, pose, p, tolerance);
    REQUIRE(solved.status);
    const Heads out = heads(solved.rotations, solved.translations);
    const glm::dvec3 target(p.target);
    const Reference ref = reference(input, target, a, b, read_pole, p.soften, p.max_stretch, p.swivel);
    const double limb_scale = reach * ref.stretch;

    // The stretch used, the translations written with it; the bones keep their lengths times the stretch.
    CHECK(solved.stretch == doctest::Approx(ref.stretch).epsilon(1e-5));
    CHECK(solved.stretch >= 1.0f);
    CHECK(solved.stretch <= p.max_stretch);
    stretched += solved.stretch > 1.0f;
    CHECK(glm::length(out.middle - out.root) == doctest::Approx(a * ref.stretch).epsilon(1e-5));
    CHECK(glm::length(out.effector - out.middle) == doctest::Approx(b * ref.stretch).epsilon(1e-5));
    CHECK(glm::length(out.root - input.root) <= 1e-6 * (glm::length(input.root) + limb_scale));

    // The effector where the reference puts it; at the target whenever the (softened, stretched) limb reaches.
    // (A target near the root has a direction known only to the float rounding of its coordinates.)
    const double direction_error = 1e-6 * (glm::length(target) + glm::length(input.root) + reach) / r;
    const double effector_error = glm::length(out.effector - ref.effector) / limb_scale;
    worst_effector = std::max(worst_effector, effector_error);
    CHECK(effector_error <= 2e-5 + direction_error);
    const double remaining = glm::length(out.effector - target);
    CHECK(solved.result.distance == doctest::Approx(remaining).scale(limb_scale).epsilon(2e-5));
    CHECK(solved.result.reached == (solved.result.distance <= tolerance));
    CHECK(solved.result.iterations == 1);
    if (p.soften == 0.0f && r <= reach * ref.stretch * (1.0 - 1e-4) && r >= std::abs(a - b) * (1.0 + 1e-4)) {
      CHECK(remaining <= 2e-5 * limb_scale);
      reached_cases += remaining <= tolerance;
    }

    // The middle joint: in the plane of root, target and pole on the pole's side (turned by the swivel), where
    // the reference puts it, unless the pole lies inside the cone about the line.
    if (ref.pole_outside_cone) {
      // Near straight or folded the middle's offset from the line is a square root of a small difference: its
      // error grows as 1 / that offset, so the bound follows it.
      const double x = glm::dot(ref.middle - input.root, glm::normalize(target - input.root));
      const double offset = std::sqrt(std::max(0.0, a * a * ref.stretch * ref.stretch - x * x));
      const double bound = 3e-5 + 1e-6 * limb_scale / std::max(offset, 1e-3 * limb_scale);
      const double middle_error = glm::length(out.middle - ref.middle) / limb_scale;
      worst_middle = std::max(worst_middle, middle_error);
      CHECK(middle_error <= bound);
      if (p.swivel == 0.0f) {
        const glm::dvec3 normal = glm::normalize(glm::cross(target - input.root, read_pole));
        CHECK(std::abs(glm::dot(out.middle - out.root, normal)) <= bound * limb_scale);
      }
      ++compared_middles;
    }
  }
  MESSAGE("worst effector error ", worst_effector, ", worst middle error ", worst_middle, " (of the limb length); ",
          compared_middles, " middles compared, ", reached_cases, " reachable targets met, ", stretched, " stretched");
  CHECK(compared_middles > 5000);
  CHECK(reached_cases > 500);
  CHECK(stretched > 1000);
}

TEST_CASE("two-bone weight: 0 leaves the pose bit-identical, between turns each joint by that part of the solve") {
  const Limb limb = make_limb();
  std::mt19937 random(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int c = 0; c < 2000; ++c) {
    LimbPose pose = random_limb_pose(random);
    // Not quite unit rotations: weight 0 must not even normalise them.
    pose.rotations[1] *= static_cast<float>(0.9 + 0.2 * unit(random));
    pose.rotations[2] *= static_cast<float>(0.9 + 0.2 * unit(random));
    const Heads input = heads(pose.rotations, pose.translations);
    const double reach = glm::length(glm::dvec3(pose.translations[2])) + glm::length(glm::dvec3(pose.translations[3]));
    Params p;
    const glm::dvec3 direction = random_unit(random);
    p.target = glm::vec3(input.root + direction * (2.5 * reach * unit(random)));
    p.pole = glm::vec3(random_unit(random));
    p.soften = static_cast<float>(unit(random));
    p.max_stretch = static_cast<float>(1.0 + 2.0 * unit(random));
    p.swivel = static_cast<float>(90.0 * unit(random));

    p.weight = 0.0f;
    const Solve none = run_job(limb.chain, pose, p, 1e-4f);
    REQUIRE(none.status);
    CHECK(std::memcmp(none.rotations.data(), pose.rotations.data(), sizeof(glm::quat) * 4) == 0);
    CHECK(std::memcmp(none.translations.data(), pose.translations.data(), sizeof(glm::vec3) * 4) == 0);
    CHECK(none.stretch == 1.0f);
    CHECK(none.result.distance ==
          doctest::Approx(glm::length(input.effector - glm::dvec3(p.target))).scale(reach).epsilon(1e-5));

    p.weight = 1.0f;
    const Solve full = run_job(limb.chain, pose, p, 1e-4f);
    p.weight = static_cast<float>(unit(random));
    const Solve part = run_job(limb.chain, pose, p, 1e-4f);
    REQUIRE(full.status);
    REQUIRE(part.status);
    const double w = p.weight;
    for (const std::size_t joint : {std::size_t{1}, std::size_t{2}}) {
      const glm::dquat from = glm::normalize(glm::dquat(pose.rotations[joint]));
      glm::dquat to(full.rotations[joint]);
      if (glm::dot(from, to) < 0.0) to = -to;
      // The shortest rotation from the input to the solve, by the angle times w (slerp, written as an axis-angle).
      const glm::dquat correction = to * glm::conjugate(from);
      const double half = std::acos(std::clamp(correction.w, -1.0, 1.0));
      const glm::dvec3 axis = std::sin(half) > 1e-12
                                  ? glm::dvec3(correction.x, correction.y, correction.z) / std::sin(half)
                                  : glm::dvec3(1.0, 0.0, 0.0);
      const glm::dquat part_correction(std::cos(w * half), axis * std::sin(w * half));
      const glm::dquat expected = part_correction * from;
      glm::dquat got(part.rotations[joint]);
      if (glm::dot(got, expected) < 0.0) got = -got;
      CHECK(glm::length(glm::dvec4(got.x - expected.x, got.y - expected.y, got.z - expected.z, got.w - expected.w)) <=
            1e-5);
    }
    CHECK(part.stretch == doctest::Approx(1.0 + w * (full.stretch - 1.0)).epsilon(1e-6));
    const Heads blended = heads(part.rotations, part.translations);
    CHECK(part.result.distance ==
          doctest::Approx(glm::length(blended.effector - glm::dvec3(p.target))).scale(reach).epsilon(2e-5));
  }
}

TEST_CASE(
    "two-bone soften: the limb's extension is continuous and increasing in the target's distance, decreasing "
    "in soften, and below the reach") {
  const Limb limb = make_limb();
  std::mt19937 random(5);
  for (int c = 0; c < 50; ++c) {
    const LimbPose pose = random_limb_pose(random);
    const Heads input = heads(pose.rotations, pose.translations);
    const double a = glm::length(glm::dvec3(pose.translations[2])), b = glm::length(glm::dvec3(pose.translations[3]));
    const double reach = a + b;
    const glm::dvec3 direction = random_unit(random);
    std::vector<double> previous_soften;  // extension per distance for the previous soften
    for (const float soften : {0.0f, 0.05f, 0.2f, 0.5f, 1.0f}) {
      Params p;
      p.pole = glm::vec3(random_unit(random));
      p.soften = soften;
      std::vector<double> extension;
      constexpr int steps = 400;
      for (int i = 0; i <= steps; ++i) {
        const double r = 2.0 * reach * i / steps;
        p.target = glm::vec3(input.root + direction * r);
        const Solve solved = run_job(limb.chain, pose, p, 0.0f);
        REQUIRE(solved.status);
        const Heads out = heads(solved.rotations, solved.translations);
        extension.push_back(glm::length(out.effector - out.root));
        // As the formula says, and below the reach once softening.
        CHECK(extension.back() == doctest::Approx(soft_distance(r, a, b, soften)).scale(reach).epsilon(2e-5));
        // At the rest reach the softened limb is still bent by soften · reach / e.
        if (i == steps / 2)
          CHECK(extension.back() <= std::max(reach * (1.0 - 0.3 * soften), std::abs(a - b)) + 2e-6 * reach);
      }
      const double step = 2.0 * reach / steps;
      for (std::size_t i = 1; i < extension.size(); ++i) {
        CHECK(extension[i] >= extension[i - 1] - 2e-6 * reach);         // increasing
        CHECK(extension[i] - extension[i - 1] <= step + 2e-6 * reach);  // continuous: slope at most 1
      }
      if (!previous_soften.empty())
        for (std::size_t i = 0; i < extension.size(); ++i) CHECK(extension[i] <= previous_soften[i] + 2e-6 * reach);
      previous_soften = extension;
    }
  }
}

TEST_CASE("two-bone pole: the middle joint moves continuously as the target crosses the pole's line") {
  const Limb limb = make_limb();
  std::mt19937 random(9);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst_rate = 0.0;
  for (int c = 0; c < 400; ++c) {
    const LimbPose pose = random_limb_pose(random);
    const Heads input = heads(pose.rotations, pose.translations);
    const double a = glm::length(glm::dvec3(pose.translations[2])), b = glm::length(glm::dvec3(pose.translations[3]));
    // The line within 65° of the pose's effector direction: the pose's bend direction, carried onto the line by the
    // shortest arc, then turns slowly with the target (the shortest arc's own singularity is the opposite direction).
    const glm::dvec3 line = glm::normalize(glm::normalize(input.effector - input.root) + 0.9 * random_unit(random));
    const double r = std::abs(a - b) + (a + b - std::abs(a - b)) * (0.2 + 0.6 * unit(random));
    Params p;
    p.pole = glm::vec3(c % 4 < 2 ? line : -line);  // the target crosses the pole's line on the pole's side, or opposite
    p.swivel = c % 3 == 0 ? 30.0f : 0.0f;
    // On the line the pose's own bend direction holds; the target sweeps an arc of ±40° about the root across the
    // line (through it every other case, else passing it at up to 2°), sideways to that direction: not through the
    // one direction ik.hpp names where the bend direction cannot be continuous.
    p.target = glm::vec3(input.root + line * r);
    const Solve on_line = run_job(limb.chain, pose, p, 0.0f);
    REQUIRE(on_line.status);
    const glm::dvec3 bend = heads(on_line.rotations, on_line.translations).middle - input.root;
    const glm::dvec3 side = glm::normalize(glm::cross(line, bend));
    const glm::dvec3 miss = glm::normalize(glm::cross(line, side)) * (c % 2 == 0 ? 0.0 : 0.035 * unit(random));
    constexpr int steps = 4000;
    const double sweep = 80.0 * pi / 180.0;
    glm::dvec3 previous_middle(0.0);
    double worst = 0.0;
    for (int i = 0; i <= steps; ++i) {
      const double angle = -0.5 * sweep + sweep * i / steps;
      const glm::dvec3 direction = glm::normalize(line * std::cos(angle) + side * std::sin(angle) + miss);
      p.target = glm::vec3(input.root + direction * r);
      const Solve solved = run_job(limb.chain, pose, p, 0.0f);
      REQUIRE(solved.status);
      const Heads out = heads(solved.rotations, solved.translations);
      REQUIRE(finite(out.middle));
      if (i > 0) worst = std::max(worst, glm::length(out.middle - previous_middle));
      previous_middle = out.middle;
    }
    // Per step the target turns by sweep / steps. The middle joint (at distance a from the root) turns with the
    // line and about it: across the cone by 180° as the blend goes from 0 to 1, at most 1.5 / cone sine per radian
    // of target turn with the blended direction's length about 1/√2 (measured: up to 28× the target's turn). A flip
    // would be a step of the order of a, thousands of times the target's.
    const double step_angle = sweep / steps;
    worst_rate = std::max(worst_rate, worst / (a * step_angle));
    CHECK(worst <= a * step_angle * 40.0);
  }
  MESSAGE("fastest swing of the middle joint: ", worst_rate, " × the target's turn");
}

TEST_CASE("two-bone degenerate targets and poles give finite poses") {
  const Limb limb = make_limb();
  std::mt19937 random(3);
  for (int c = 0; c < 500; ++c) {
    LimbPose pose = random_limb_pose(random);
    if (c % 3 == 0) pose.rotations[2] = glm::quat(1, 0, 0, 0), pose.translations[3] = pose.translations[2];  // straight
    if (c % 3 == 1) pose.rotations[2] = glm::quat(1, 0, 0, 0), pose.translations[3] = -pose.translations[2];  // folded
    // Every other limb has an identity base: a target on the root is then exactly on it in the job's arithmetic too.
    if (c % 2 == 0) pose.rotations[0] = glm::quat(1, 0, 0, 0), pose.translations[0] = glm::vec3(0.0f);
    const Heads input = heads(pose.rotations, pose.translations);
    const glm::dvec3 direction = random_unit(random);
    const double reach = glm::length(glm::dvec3(pose.translations[2])) + glm::length(glm::dvec3(pose.translations[3]));
    for (int kind = 0; kind < 6; ++kind) {
      Params p;
      const double fold =
          std::abs(glm::length(glm::dvec3(pose.translations[2])) - glm::length(glm::dvec3(pose.translations[3])));
      p.target = glm::vec3(input.root + direction * (0.5 * (fold + reach)));  // reachable, the limb bent
      p.soften = c % 2 == 0 ? 0.5f : 0.0f;
      p.max_stretch = 2.0f;
      switch (kind) {
        case 0:
          p.target = glm::vec3(input.root);
          p.pole = glm::vec3(direction);
          break;                                        // target on the root
        case 1: p.pole = glm::vec3(direction); break;   // pole along the line
        case 2: p.pole = glm::vec3(-direction); break;  // and opposite
        case 3:
          p.kind = PoleKind::point;
          p.pole = glm::vec3(input.root);
          break;  // pole point on the root
        case 4:
          p.kind = PoleKind::point;
          p.pole = p.target;
          p.swivel = 45.0f;
          break;  // pole point on the target
        default:
          p.pole = glm::vec3(0.0f);
          p.swivel = -90.0f;
          break;  // no pole, a swivel
      }
      const Solve solved = run_job(limb.chain, pose, p, 1e-4f);
      REQUIRE(solved.status);
      const Heads out = heads(solved.rotations, solved.translations);
      CHECK(finite(out.middle));
      CHECK(finite(out.effector));
      CHECK(std::isfinite(solved.result.distance));
      CHECK(std::isfinite(solved.stretch));
      if (kind >= 1) CHECK(glm::length(out.effector - glm::dvec3(p.target)) <= 3e-5 * reach);  // reachable
    }
  }
}

TEST_CASE("two-bone with limits, soften, stretch and weight never leaves the limits") {
  std::mt19937 random(31);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int c = 0; c < 1000; ++c) {
    const ik_rigs::RandomChain rig = ik_rigs::random_chain(random, 2);
    const IkChain chain = make_chain(rig.skeleton, rig.root, rig.effector);
    Pose pose = ik_rigs::random_in_limit_pose(random, rig);
    TwoBoneIkJob job;
    job.chain = &chain;
    REQUIRE(chain_base(chain, pose.rotations, pose.translations, job.base));
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    const glm::vec3 reachable = ik_rigs::random_reachable_target(random, rig);
    job.target = reachable * (0.5f + unit(random));
    job.pole = glm::vec3(ik_rigs::random_direction(random));
    job.soften = unit(random);
    job.weight = unit(random);
    job.max_stretch = 1.0f + 2.0f * unit(random);
    REQUIRE(job.run());
    for (std::size_t b = 1; b <= 2; ++b)
      CHECK(ik_rigs::rotation_within_limits(pose.rotations[b], rig.skeleton.bones()[b].limits));
  }
}

TEST_CASE(
    "two-bone validate refuses bad parameters and zero-length bones with reasons, writing nothing; run "
    "allocates nothing") {
  const Limb limb = make_limb();
  std::mt19937 random(1);
  const LimbPose pose = random_limb_pose(random);
  std::vector<glm::quat> rotations = pose.rotations;
  std::vector<glm::vec3> stretched(4, glm::vec3(7.0f));
  IkResult result{true, 42.0f, 7};
  float stretch = -1.0f;
  TwoBoneIkJob good;
  good.chain = &limb.chain;
  REQUIRE(chain_base(limb.chain, pose.rotations, pose.translations, good.base));
  good.rotations = rotations;
  good.translations = pose.translations;
  good.target = glm::vec3(1, 2, 3);
  good.pole = glm::vec3(0, 0, 1);
  good.soften = 0.3f;
  good.weight = 0.5f;
  good.max_stretch = 2.0f;
  good.swivel_degrees = 20.0f;
  good.stretched_translations = stretched;
  good.result = &result;
  good.stretch = &stretch;
  REQUIRE(good.validate());

  auto refused = [&](const TwoBoneIkJob& job, const char* why) {
    const Status validated = job.validate(), ran = job.run();
    CHECK_FALSE(validated);
    CHECK_FALSE(ran);
    CHECK(std::string(validated.reason()) == why);
    CHECK(std::string(ran.reason()) == why);
  };
  constexpr float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const float bad : {nan, inf, -inf, -0.01f, 1.01f}) {
    TwoBoneIkJob job = good;
    job.soften = bad;
    refused(job, "soften not within [0, 1]");
    job = good;
    job.weight = bad;
    refused(job, "weight not within [0, 1]");
  }
  for (const float bad : {nan, inf, 0.99f, 0.0f, -2.0f}) {
    TwoBoneIkJob job = good;
    job.max_stretch = bad;
    refused(job, "max_stretch not finite and >= 1");
  }
  for (const float bad : {nan, inf, 360.5f, -361.0f}) {
    TwoBoneIkJob job = good;
    job.swivel_degrees = bad;
    refused(job, "swivel_degrees not within [-360, 360]");
  }
  TwoBoneIkJob job = good;
  job.pole_kind = static_cast<PoleKind>(7);
  refused(job, "pole_kind is not direction or point");
  job = good;
  job.pole = glm::vec3(0, nan, 0);
  refused(job, "pole is not finite");
  job = good;
  job.pole_kind = PoleKind::point;
  job.pole = glm::vec3(0, 0, inf);
  refused(job, "pole is not finite");
  job = good;
  job.target = glm::vec3(inf, 0, 0);
  refused(job, "target is not finite");
  job = good;
  job.stretched_translations = std::span<glm::vec3>(stretched).first(3);
  refused(job, "stretched_translations do not hold every chain bone");
  IkChain swing_twist_chain = limb.chain;
  set_swing_twist(swing_twist_chain, 1, make_swing_twist_limits(glm::vec3(1, 0, 0), 30.0f, 30.0f, -10.0f, 10.0f));
  job = good;
  job.chain = &swing_twist_chain;
  refused(job, "chain has swing-twist limits (the two-bone solver takes Euler limits)");
  for (const std::size_t bone : {std::size_t{2}, std::size_t{3}}) {
    for (const float length : {0.0f, 1e-9f}) {
      std::vector<glm::vec3> translations = pose.translations;
      translations[bone] = glm::normalize(translations[bone]) * length;
      job = good;
      job.translations = translations;
      refused(job, "limb has a zero-length bone");
    }
  }
  CHECK(rotations == pose.rotations);
  CHECK(stretched == std::vector<glm::vec3>(4, glm::vec3(7.0f)));
  CHECK(result.distance == 42.0f);
  CHECK(stretch == -1.0f);

  const long before = allocations.load();
  REQUIRE(good.run());
  job = good;
  job.pole_kind = PoleKind::point;
  job.weight = 1.0f;
  REQUIRE(job.run());
  CHECK(allocations.load() == before);
  CHECK(stretch >= 1.0f);
  CHECK(stretched[2] != glm::vec3(7.0f));
  CHECK(stretched[0] == glm::vec3(7.0f));  // only the middle and effector entries are written
}
