// Secondary motion: the forced oscillator step, lattices that feel their bone's motion, and spring chains — each
// against a plain double-precision reference, and the same curve at any frame rate and any scale.
#include "deform/offline/hierarchy_binding.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/spring_chain.hpp"
#include <doctest/doctest.h>

#include "study.hpp"  // tools/motion_study: frame times landing on every 1/15 s, the spread of paths

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <random>
#include <string>
#include <vector>

namespace {

using motion_study::at_checkpoint;
using motion_study::frame_times;
using motion_study::spread_of;
using Spread = motion_study::Spread;

constexpr double pi = 3.14159265358979323846;

// --- plain references -------------------------------------------------------------------------------------------

// y'' = -ω² y - 2ζω y' + f(t) in double, by RK4 with `steps` steps over [0, t].
struct State1 {
  double y = 0.0;
  double v = 0.0;
};
State1 rk4_oscillator(double omega, double zeta, State1 s, double t, const std::function<double(double)>& f,
                      int steps = 20000) {
  const double h = t / steps;
  const auto accel = [&](double time, double y, double v) {
    return -omega * omega * y - 2 * zeta * omega * v + f(time);
  };
  for (int i = 0; i < steps; ++i) {
    const double t0 = i * h;
    const double k1y = s.v, k1v = accel(t0, s.y, s.v);
    const double k2y = s.v + 0.5 * h * k1v, k2v = accel(t0 + 0.5 * h, s.y + 0.5 * h * k1y, s.v + 0.5 * h * k1v);
    const double k3y = s.v + 0.5 * h * k2v, k3v = accel(t0 + 0.5 * h, s.y + 0.5 * h * k2y, s.v + 0.5 * h * k2v);
    const double k4y = s.v + h * k3v, k4v = accel(t0 + h, s.y + h * k3y, s.v + h * k3v);
    s.y += h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y);
    s.v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  return s;
}

deform::ElasticParams params_of(double omega, double zeta) {
  deform::ElasticParams p;
  p.stiffness = float(omega * omega);
  p.damping_ratio = float(zeta);
  p.mass = 1.0f;
  return p;
}

}  // namespace

// --- the forced step --------------------------------------------------------------------------------------------

TEST_CASE("forced_step: the exact response to an acceleration linear in time, in every regime, against RK4") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int cases = 0;
  for (const double zeta : {0.0, 0.05, 0.3, 1.0, 1.0 + 1e-7, 1.7, 6.0}) {
    for (int n = 0; n < 12; ++n) {
      const double omega = 0.5 + 40.0 * unit(rng);
      const double t = std::pow(10.0, -3.0 + 3.3 * unit(rng));  // 1 ms to 2 s
      const double f0 = 20.0 * unit(rng) - 10.0, f1 = 20.0 * unit(rng) - 10.0;
      const State1 start{unit(rng) - 0.5, 4.0 * unit(rng) - 2.0};
      const auto f = [&](double s) { return f0 + (f1 - f0) * s / t; };
      const deform::ElasticParams p = params_of(omega, zeta);  // the reference takes the parameters as stored
      const State1 ref = rk4_oscillator(std::sqrt(double(p.stiffness)), double(p.damping_ratio), start, t, f);
      const deform::OscillatorStep m = deform::oscillator_step(p, t);
      const deform::ForcedStep fs = deform::forced_step(p, t);
      const double y = m.position_from_offset * start.y + m.position_from_velocity * start.v +
                       fs.position_from_start * f0 + fs.position_from_end * f1;
      const double v = m.velocity_from_offset * start.y + m.velocity_from_velocity * start.v +
                       fs.velocity_from_start * f0 + fs.velocity_from_end * f1;
      const double scale = 1.0 + std::abs(ref.y) + std::abs(ref.v) + (std::abs(f0) + std::abs(f1)) / (omega * omega);
      INFO("zeta " << zeta << " omega " << omega << " t " << t);
      CHECK(std::abs(y - ref.y) <= 1e-7 * scale);
      CHECK(std::abs(v - ref.v) <= 1e-7 * scale * omega);
      ++cases;
    }
  }
  CHECK(cases == 84);
}

TEST_CASE("forced_step: the Taylor branch meets the closed form at ω·t = 1e-4, and a zero step adds nothing") {
  const deform::ElasticParams p = params_of(10.0, 0.3);
  const deform::ForcedStep below = deform::forced_step(p, 0.999999e-5);
  const deform::ForcedStep above = deform::forced_step(p, 1.000001e-5);
  CHECK(below.position_from_start == doctest::Approx(above.position_from_start).epsilon(1e-3));
  CHECK(below.position_from_end == doctest::Approx(above.position_from_end).epsilon(1e-3));
  CHECK(below.velocity_from_start == doctest::Approx(above.velocity_from_start).epsilon(1e-3));
  CHECK(below.velocity_from_end == doctest::Approx(above.velocity_from_end).epsilon(1e-3));
  const deform::ForcedStep zero = deform::forced_step(p, 0.0);
  CHECK(zero.position_from_start == 0.0);
  CHECK(zero.velocity_from_end == 0.0);
}

TEST_CASE("hermite_accelerations: a cubic's second derivative at both ends; zero for linear motion") {
  const glm::vec3 a(0.3f, -1.0f, 2.0f), b(1.0f, 0.5f, -0.25f), c(-2.0f, 0.75f, 1.5f), d(0.5f, 3.0f, -1.0f);
  const float h = 0.1f;
  const auto p = [&](float t) { return a + b * t + c * t * t + d * t * t * t; };
  const auto v = [&](float t) { return b + 2.0f * c * t + 3.0f * d * t * t; };
  const deform::HermiteAccelerations acc = deform::hermite_accelerations(p(0), v(0), p(h), v(h), h);
  for (int i = 0; i < 3; ++i) {
    CHECK(acc.start[i] == doctest::Approx(2.0f * c[i]).epsilon(1e-3));
    CHECK(acc.end[i] == doctest::Approx(2.0f * c[i] + 6.0f * d[i] * h).epsilon(1e-3));
  }
  const glm::vec3 chord = (p(h) - p(0)) / h;
  const deform::HermiteAccelerations none = deform::hermite_accelerations(p(0), chord, p(h), chord, h);
  CHECK(glm::length(none.start) < 1e-3f);
  CHECK(glm::length(none.end) < 1e-3f);
}

TEST_CASE("ElasticLattice::step with accelerations is the exact flow: any split of a linear forcing agrees") {
  const std::vector<glm::vec3> rest = {glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f)};
  deform::ElasticSettings settings;
  settings.oscillator = params_of(12.0, 0.15);
  const double total = 0.9;
  const glm::vec3 f0(3.0f, -2.0f, 1.0f), f1(-4.0f, 1.0f, 0.5f);
  const auto force = [&](double t) { return f0 + (f1 - f0) * float(t / total); };
  deform::ElasticLattice whole(rest, settings);
  std::vector<glm::vec3> start(2, f0), end(2, f1);
  REQUIRE(whole.step(float(total), rest, start, end));
  for (const bool jitter : {false, true}) {
    deform::ElasticLattice split(rest, settings);
    std::mt19937 rng(3);
    double t = 0.0;
    while (t < total - 1e-12) {
      const double h = jitter ? std::min(total - t, std::uniform_real_distribution<double>(0.001, 0.05)(rng))
                              : std::min(total - t, 1.0 / 60.0);
      std::fill(start.begin(), start.end(), force(t));
      std::fill(end.begin(), end.end(), force(t + h));
      REQUIRE(split.step(float(h), rest, start, end));
      t += h;
    }
    for (std::size_t i = 0; i < rest.size(); ++i) {
      CHECK(glm::length(split.positions()[i] - whole.positions()[i]) < 2e-5f);
      CHECK(glm::length(split.velocities()[i] - whole.velocities()[i]) < 2e-4f);
    }
  }
  // Refusals change nothing.
  deform::ElasticLattice lattice(rest, settings);
  CHECK_FALSE(lattice.step(0.01f, rest, start, std::vector<glm::vec3>(1)));
  CHECK_FALSE(lattice.add_velocity(std::vector<glm::vec3>(3)));
  CHECK(lattice.positions()[0] == rest[0]);
}

// --- lattices that feel their bone's motion ----------------------------------------------------------------------

namespace {

// A limb along +Y: root (0), bone 1 from y = 0 to 1 (its child 2 at y = 1). A cylinder of points on bone 1.
struct MovingLimb {
  deform::Skeleton skeleton;
  std::vector<glm::vec3> points;
  deform::SkinWeights weights;
};

MovingLimb moving_limb() {
  std::vector<deform::Bone> bones(3);
  bones[0] = {"root", -1, {1}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
  bones[1] = {"arm", 0, {2}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
  bones[2] = {"hand", 1, {}, glm::vec3(0, 1, 0), glm::vec3(0.0f), {}};
  MovingLimb limb{deform::Skeleton(bones), {}, {}};
  for (int r = 0; r <= 20; ++r) {
    for (int a = 0; a < 8; ++a) {
      const float angle = 2.0f * float(pi) * float(a) / 8.0f;
      limb.points.emplace_back(0.15f * std::cos(angle), 0.05f * float(r), 0.15f * std::sin(angle));
      limb.weights.bones.emplace_back(1, 0, 0, 0);
      limb.weights.weights.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
    }
  }
  return limb;
}

deform::DeformerHierarchy inertial_hierarchy(const MovingLimb& limb, const deform::LatticeMotion& motion, double omega,
                                             double zeta) {
  deform::LatticeSpec spec;
  spec.name = "arm";
  spec.bone = 1;
  spec.degree = glm::ivec3(2, 1, 1);
  spec.elastic.oscillator = params_of(omega, zeta);
  spec.shape.min_length_fraction = 0.0f;  // the plain springs: nothing shapes what they show
  spec.shape.volume = 0.0f;
  spec.motion = motion;
  return deform::bind_hierarchy(limb.skeleton, limb.points, limb.weights, {spec});
}

// The arm's world matrix: a sway along X and a swing about Z, scaled by `scale` about the origin, and its rate.
struct Motion {
  double sway = 0.3;   // m
  double swing = 0.6;  // rad
  double scale = 1.0;
  glm::dmat4 at(double t) const {
    const double theta = swing * std::sin(2 * pi * 1.3 * t) * (1 - std::exp(-4 * t));
    const double x = sway * std::sin(2 * pi * 0.9 * t + 0.4) - sway * std::sin(0.4);
    glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(x, 0, 0));
    m = glm::rotate(m, theta, glm::dvec3(0, 0, 1));
    return glm::scale(glm::dmat4(1.0), glm::dvec3(scale)) * m;
  }
  glm::dmat4 rate(double t) const { return (at(t + 1e-6) - at(t - 1e-6)) / 2e-6; }
};

std::vector<glm::mat4> bone_matrices(const glm::dmat4& arm) {
  return {glm::mat4(1.0f), glm::mat4(arm), glm::mat4(arm * glm::translate(glm::dmat4(1.0), glm::dvec3(0, 1, 0)))};
}

// The far control points' displacement in the bone's frame at every checkpoint (what the lattice shows, taken back
// by the bone's 3×3: the same at every scale).
std::vector<glm::vec3> run_lattice(const MovingLimb& limb, const deform::LatticeMotion& lattice_motion,
                                   const Motion& motion, const std::vector<double>& times, bool rates) {
  deform::DeformerHierarchy hierarchy = inertial_hierarchy(limb, lattice_motion, 9.0, 0.2);
  std::vector<glm::vec3> out;
  REQUIRE(hierarchy.step(0.0f, bone_matrices(motion.at(0.0)), bone_matrices(motion.rate(0.0))));
  for (std::size_t n = 1; n < times.size(); ++n) {
    const std::vector<glm::mat4> world = bone_matrices(motion.at(times[n]));
    const std::vector<glm::mat4> rate = bone_matrices(motion.rate(times[n]));
    REQUIRE(hierarchy.step(float(times[n] - times[n - 1]), world,
                           rates ? std::span<const glm::mat4>(rate) : std::span<const glm::mat4>()));
    if (!at_checkpoint(times[n])) continue;
    REQUIRE(hierarchy.update(world));
    const std::size_t far = hierarchy.rest_lattice(0).index(2, 0, 0);
    out.push_back(glm::inverse(glm::mat3(world[1])) * hierarchy.displacements(0)[far]);
  }
  return out;
}

}  // namespace

TEST_CASE("inertial lattice: against a double-precision reference of the forced oscillator") {
  const MovingLimb limb = moving_limb();
  deform::LatticeMotion lattice_motion;
  lattice_motion.inertia = 1.0f;
  const Motion motion;
  // The reference, per axis in the bone's frame: y'' = -ω²y - 2ζωy' - L⁻¹ r''.
  // The far face shows its mean displacement, the response to the forcing at its points' mean (all is linear).
  deform::DeformerHierarchy probe = inertial_hierarchy(limb, lattice_motion, 9.0, 0.2);
  glm::dvec3 x(0.0);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      x += 0.25 * glm::dvec3(probe.rest_lattice(0).control_points()[probe.rest_lattice(0).index(2, j, k)]);
  const auto forcing = [&](double t, int axis) {
    const double e = 1e-4;
    const auto r = [&](double s) { return glm::dvec3(motion.at(s) * glm::dvec4(x, 1.0)); };
    const glm::dvec3 acceleration = (r(t + e) - 2.0 * r(t) + r(t - e)) / (e * e);
    return -(glm::inverse(glm::dmat3(motion.at(t))) * acceleration)[axis];
  };
  // Along the bone (U) the offset is shown through the bound b·tanh(z / b) (LatticeMotion::along_bound).
  const glm::dvec3 u = glm::normalize(glm::dvec3(probe.rest_lattice(0).frame().u_axis));
  const double bound = double(lattice_motion.along_bound) * double(probe.length(0));
  // Checkpoint c every 1/15 s, each continuing the last: 4000 RK4 steps a checkpoint (from 0 each time, it took 15×
  // the steps, 4.6 minutes under ASan).
  std::vector<glm::dvec3> reference;
  State1 state[3];
  for (int c = 1; c <= 30; ++c) {
    glm::dvec3 y;
    for (int axis = 0; axis < 3; ++axis) {
      const double start = (c - 1) / 15.0;
      state[axis] = rk4_oscillator(
          9.0, 0.2, state[axis], 1.0 / 15.0, [&](double t) { return forcing(start + t, axis); }, 4000);
      y[axis] = state[axis].y;
    }
    const double along = glm::dot(y, u);
    reference.push_back(y + u * (bound * std::tanh(along / bound) - along));
  }
  double largest = 0.0;
  for (const glm::dvec3& y : reference) largest = std::max(largest, glm::length(y));
  REQUIRE(largest > 0.02);  // the motion does excite the lattice
  for (const bool rates : {true, false}) {
    const std::vector<glm::vec3> shown = run_lattice(limb, lattice_motion, motion, frame_times(60, 2.0, false), rates);
    double error = 0.0;
    for (std::size_t c = 0; c < reference.size(); ++c)
      error = std::max(error, glm::length(glm::dvec3(shown[c]) - reference[c]));
    INFO("rates " << rates << ": error " << error << " of the largest offset " << largest);
    CHECK(error < (rates ? 0.005 : 0.03) * largest);
  }
}

TEST_CASE("inertial lattice: the same curve at 15, 30, 60, 144, 240 Hz and a jittered frame time, at any scale") {
  const MovingLimb limb = moving_limb();
  deform::LatticeMotion lattice_motion;
  lattice_motion.inertia = 0.8f;
  lattice_motion.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  for (const double scale : {1.0, 0.01, 100.0}) {
    Motion motion;
    motion.scale = scale;
    std::vector<std::vector<glm::vec3>> runs;
    for (const double hz : {15.0, 30.0, 60.0, 144.0, 240.0})
      runs.push_back(run_lattice(limb, lattice_motion, motion, frame_times(hz, 2.0, false), true));
    runs.push_back(run_lattice(limb, lattice_motion, motion, frame_times(240.0, 2.0, true), true));
    const Spread spread = spread_of(runs);
    INFO("scale " << scale << ": spread " << spread.percent() << "% of " << spread.amplitude);
    CHECK(spread.percent() < 0.5);
    // In the bone's frame the motion is the same at every scale.
    Motion unit;
    const std::vector<glm::vec3> reference = run_lattice(limb, lattice_motion, unit, frame_times(60, 2.0, false), true);
    double difference = 0.0;
    for (std::size_t c = 0; c < reference.size(); ++c)
      difference = std::max(difference, double(glm::length(runs[2][c] - reference[c])));
    CHECK(difference < 1e-3 * spread.amplitude);
  }
}

TEST_CASE(
    "inertial lattice: no inertia and no gravity is the bone-frame lattice exactly; steady motion excites nothing") {
  const MovingLimb limb = moving_limb();
  const Motion motion;
  deform::DeformerHierarchy plain = inertial_hierarchy(limb, {}, 9.0, 0.2);
  deform::DeformerHierarchy with_world = inertial_hierarchy(limb, {}, 9.0, 0.2);
  REQUIRE(plain.set_stretch_target(0, 0.4f));
  REQUIRE(with_world.set_stretch_target(0, 0.4f));
  for (int n = 1; n <= 40; ++n) {
    REQUIRE(plain.step(1.0f / 30.0f));
    REQUIRE(with_world.step(1.0f / 30.0f, bone_matrices(motion.at(n / 30.0)), bone_matrices(motion.rate(n / 30.0))));
  }
  CHECK(plain.stretch(0) == with_world.stretch(0));

  // Gliding at constant velocity, a lattice with inertia stays at rest (Galilean invariance), with or without rates.
  deform::LatticeMotion inertial;
  inertial.inertia = 1.0f;
  for (const bool rates : {true, false}) {
    deform::DeformerHierarchy glide = inertial_hierarchy(limb, inertial, 9.0, 0.2);
    for (int n = 0; n <= 60; ++n) {
      const glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(2.0 * n / 60.0, 0.5 * n / 60.0, 0.0));
      glm::dmat4 rate(0.0);
      rate[3] = glm::dvec4(2.0, 0.5, 0.0, 0.0);
      REQUIRE(glide.step(n == 0 ? 0.0f : 1.0f / 60.0f, bone_matrices(m),
                         rates ? std::span<const glm::mat4>(bone_matrices(rate)) : std::span<const glm::mat4>()));
    }
    REQUIRE(glide.update(bone_matrices(glm::dmat4(1.0))));
    for (const glm::vec3& d : glide.displacements(0)) CHECK(glm::length(d) < 1e-5f);
  }
}

TEST_CASE("inertial lattice: a constant acceleration settles at the offset -λ·a/ω²; gravity sags by g/ω²") {
  const MovingLimb limb = moving_limb();
  deform::LatticeMotion motion;
  motion.inertia = 0.5f;
  motion.gravity = glm::vec3(0.0f, 0.0f, -9.81f);
  motion.units_per_metre = 100.0f;  // a model in centimetres
  const double omega = 9.0, a = 3.0;
  deform::DeformerHierarchy h = inertial_hierarchy(limb, motion, omega, 0.7);
  double t = 0.0;
  for (int n = 0; n <= 600; ++n, t = n / 60.0) {
    const glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(0.5 * a * t * t, 0.0, 0.0));
    glm::dmat4 rate(0.0);
    rate[3] = glm::dvec4(a * t, 0.0, 0.0, 0.0);
    REQUIRE(h.step(n == 0 ? 0.0f : 1.0f / 60.0f, bone_matrices(m), bone_matrices(rate)));
  }
  REQUIRE(h.update(bone_matrices(glm::dmat4(1.0))));
  const glm::vec3 d = h.displacements(0)[h.rest_lattice(0).index(1, 0, 0)];
  CHECK(d.x == doctest::Approx(-0.5 * a / (omega * omega)).epsilon(1e-3));
  CHECK(d.z == doctest::Approx(-981.0 / (omega * omega)).epsilon(1e-3));
}

TEST_CASE("inertial lattice: the motion moves whole slices across the bone and along it within along_bound") {
  // The swing about Z flings the far points outward along the bone (centrifugal) and sideways: without the split the
  // lattice would stretch and its slices fan out.
  const MovingLimb limb = moving_limb();
  const Motion motion;
  for (const float bound : {0.02f, 1.0f}) {
    deform::LatticeMotion lattice_motion;
    lattice_motion.inertia = 1.0f;
    lattice_motion.along_bound = bound;
    deform::DeformerHierarchy h = inertial_hierarchy(limb, lattice_motion, 9.0, 0.2);
    const deform::BezierLattice& rest = h.rest_lattice(0);
    const glm::vec3 u = glm::normalize(rest.frame().u_axis);
    float along = 0.0f, across = 0.0f, within_slice = 0.0f;
    const std::vector<double> times = frame_times(60, 2.0, false);
    REQUIRE(h.step(0.0f, bone_matrices(motion.at(0.0)), bone_matrices(motion.rate(0.0))));
    for (std::size_t n = 1; n < times.size(); ++n) {
      const std::vector<glm::mat4> world = bone_matrices(motion.at(times[n]));
      REQUIRE(h.step(float(times[n] - times[n - 1]), world, bone_matrices(motion.rate(times[n]))));
      REQUIRE(h.update(world));
      const glm::mat3 back = glm::inverse(glm::mat3(world[1]));
      for (int i = 0; i < rest.point_counts().x; ++i) {
        const glm::vec3 first = back * h.displacements(0)[rest.index(i, 0, 0)];
        along = std::max(along, std::abs(glm::dot(first, u)));
        across = std::max(across, glm::length(first - u * glm::dot(first, u)));
        for (int k = 0; k < rest.point_counts().z; ++k)
          for (int j = 0; j < rest.point_counts().y; ++j)
            within_slice = std::max(within_slice, glm::length(back * h.displacements(0)[rest.index(i, j, k)] - first));
      }
    }
    INFO("bound " << bound << ": along " << along << ", across " << across << ", within a slice " << within_slice);
    CHECK(within_slice < 1e-5f * h.length(0));  // each slice translates: a shear, no swelling
    CHECK(across > 0.05f * h.length(0));        // the jiggle across the bone is free
    if (bound < 1.0f) {
      CHECK(along <= bound * h.length(0) * (1.0f + 1e-5f));  // tanh saturates at the bound, to rounding
      CHECK(along > 0.5f * bound * h.length(0));             // ... and along it, up to the bound
    } else {
      CHECK(along > 0.05f * h.length(0));  // unbounded, the swing would stretch the limb by more than 5%
    }
  }
}

TEST_CASE("set_motion and bind-time checks refuse bad values naming the field") {
  const MovingLimb limb = moving_limb();
  deform::DeformerHierarchy h = inertial_hierarchy(limb, {}, 9.0, 0.2);
  deform::LatticeMotion bad;
  bad.inertia = 1.5f;
  CHECK_THROWS_WITH_AS(h.set_motion(0, bad), doctest::Contains("inertia"), deform::Error);
  bad = {};
  bad.units_per_metre = 0.0f;
  CHECK_THROWS_WITH_AS(h.set_motion(0, bad), doctest::Contains("units_per_metre"), deform::Error);
  bad = {};
  bad.along_bound = -0.1f;
  CHECK_THROWS_WITH_AS(h.set_motion(0, bad), doctest::Contains("along_bound"), deform::Error);
  bad = {};
  bad.far_share = NAN;
  CHECK_THROWS_WITH_AS(h.set_motion(0, bad), doctest::Contains("far_share"), deform::Error);
  bad = {};
  bad.gravity.y = NAN;
  CHECK_THROWS_WITH_AS(inertial_hierarchy(limb, bad, 9.0, 0.2), doctest::Contains("gravity"), deform::Error);
  CHECK_FALSE(h.step(0.1f, std::vector<glm::mat4>(2)));
  CHECK_FALSE(h.step(0.1f, std::vector<glm::mat4>(3), std::vector<glm::mat4>(1)));
}

TEST_CASE("the inertia knob scales each part's tuned inertia: 1 the tuned motion, 0 rigid, no part the knob itself") {
  using deform::BodyPart;
  for (const BodyPart part : {BodyPart::upper_limb, BodyPart::lower_limb, BodyPart::hand, BodyPart::foot,
                              BodyPart::torso, BodyPart::head, BodyPart::appendage}) {
    CAPTURE(deform::body_part_name(part));
    const deform::LatticeMotion tuned = deform::default_lattice_motion(part);
    CHECK(tuned.part == part);
    CHECK(tuned.inertia > 0.0f);
    CHECK(tuned.inertia < 1.0f);  // every known part is tamer than a free mass
    CHECK(deform::scaled_inertia(part, 1.0f) == tuned.inertia);
    CHECK(deform::scaled_inertia(part, 0.5f) == 0.5f * tuned.inertia);
    CHECK(deform::scaled_inertia(part, 0.0f) == 0.0f);
    CHECK(deform::body_part_named(deform::body_part_name(part)) == part);
  }
  // A lattice with no part (set up by hand, or from a rig file older than parts): the knob is its inertia.
  CHECK(deform::scaled_inertia(BodyPart::unspecified, 0.7f) == 0.7f);
  deform::LatticeMotion unspecified;
  unspecified.inertia = 1.0f;
  CHECK(deform::default_lattice_motion(BodyPart::unspecified) == unspecified);
  CHECK(deform::body_part_named("unspecified") == BodyPart::unspecified);
  CHECK_FALSE(deform::body_part_named("elbow"));
  CHECK_FALSE(deform::body_part_named(""));
  for (const float bad : {-0.1f, 1.5f, NAN})
    CHECK_THROWS_WITH_AS(deform::scaled_inertia(BodyPart::hand, bad), doctest::Contains("scale"), deform::Error);
  const auto stray = static_cast<BodyPart>(200);
  CHECK(deform::body_part_name(stray).empty());
  CHECK_THROWS_WITH_AS(deform::scaled_inertia(stray, 1.0f), doctest::Contains("part"), deform::Error);
  deform::LatticeMotion bad;
  bad.part = stray;
  CHECK_THROWS_WITH_AS(deform::require_valid_motion(bad), doctest::Contains("part"), deform::Error);

  // A hierarchy: every lattice at the scale of its part's tuned inertia, the rest of its motion kept.
  const MovingLimb limb = moving_limb();
  deform::LatticeMotion rigid = deform::default_lattice_motion(BodyPart::upper_limb);
  rigid.inertia = 0.0f;
  rigid.gravity = glm::vec3(0.0f, -1.0f, 0.0f);
  deform::DeformerHierarchy h = inertial_hierarchy(limb, rigid, 9.0, 0.2);
  h.set_inertia_scale(1.0f);
  deform::LatticeMotion expected = rigid;
  expected.inertia = 0.3f;
  CHECK(h.spec(0).motion == expected);
  h.set_inertia_scale(0.5f);
  expected.inertia = 0.15f;
  CHECK(h.spec(0).motion == expected);
  CHECK_THROWS_WITH_AS(h.set_inertia_scale(2.0f), doctest::Contains("scale"), deform::Error);
  CHECK(h.spec(0).motion == expected);  // unchanged
}

// --- spring chains ------------------------------------------------------------------------------------------------

namespace {

// root (0) at the origin, then `links` bones along +X, `length` apart, the first at (0.1, 0, 0).
deform::Skeleton chain_skeleton(int links, float length) {
  std::vector<deform::Bone> bones(std::size_t(links) + 1);
  bones[0] = {"root", -1, {1}, glm::vec3(0.0f), glm::vec3(0.0f), {}};
  for (int i = 1; i <= links; ++i) {
    bones[std::size_t(i)] = {"link" + std::to_string(i),
                             i - 1,
                             i < links ? std::vector<std::int32_t>{i + 1} : std::vector<std::int32_t>{},
                             glm::vec3(i == 1 ? 0.1f : length, 0, 0),
                             glm::vec3(0.0f),
                             {}};
  }
  return deform::Skeleton(bones);
}

deform::SpringChainSpec whole_chain(int links) {
  deform::SpringChainSpec spec;
  spec.name = "tail";
  for (int i = 1; i <= links; ++i) spec.bones.push_back(i);
  spec.frequency = 2.5f;
  spec.damping_ratio = 0.25f;
  return spec;
}

// A whip: the root turns about Z and sways along Y; `scale` scales the world about the origin.
struct Whip {
  double scale = 1.0;
  double swing = 0.6;
  glm::dmat4 root(double t) const {
    const double ramp = 1.0 - std::exp(-3.0 * t);
    glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, 0.15 * std::sin(2 * pi * 1.1 * t) * ramp, 0.0));
    m = glm::rotate(m, swing * std::sin(2 * pi * 0.8 * t) * ramp, glm::dvec3(0, 0, 1));
    return glm::scale(glm::dmat4(1.0), glm::dvec3(scale)) * m;
  }
};

// The chain's animated world matrices: the root's times the bind pose's local matrices.
std::vector<glm::mat4> chain_world(const deform::Skeleton& skeleton, const glm::dmat4& root) {
  std::vector<glm::mat4> world(skeleton.bone_count());
  for (std::size_t b = 0; b < world.size(); ++b) world[b] = glm::mat4(root * glm::dmat4(skeleton.bind_world()[b]));
  return world;
}

std::vector<glm::vec3> run_whip(const deform::Skeleton& skeleton, const std::vector<deform::SpringChainSpec>& chains,
                                const std::vector<deform::SpringCollider>& colliders, const Whip& whip,
                                const std::vector<double>& times, bool rates, float* closest = nullptr) {
  deform::SpringChains springs(skeleton, chains, colliders);
  std::vector<glm::vec3> tips;
  for (std::size_t n = 0; n < times.size(); ++n) {
    std::vector<glm::mat4> world = chain_world(skeleton, whip.root(times[n]));
    const glm::dmat4 root_rate = (whip.root(times[n] + 1e-6) - whip.root(times[n] - 1e-6)) / 2e-6;
    std::vector<glm::mat4> rate(world.size());
    for (std::size_t b = 0; b < world.size(); ++b)
      rate[b] = glm::mat4(root_rate * glm::dmat4(skeleton.bind_world()[b]));
    const float dt = n == 0 ? 0.0f : float(times[n] - times[n - 1]);
    REQUIRE(springs.run(dt, world, rates ? std::span<const glm::mat4>(rate) : std::span<const glm::mat4>()));
    if (closest != nullptr && !colliders.empty()) {
      const glm::vec3 centre(world[0] * glm::vec4(colliders[0].start, 1.0f));
      for (const glm::vec3& p : springs.points(0)) *closest = std::min(*closest, glm::length(p - centre));
    }
    if (n > 0 && at_checkpoint(times[n])) tips.push_back(springs.points(0).back());
  }
  return tips;
}

}  // namespace

TEST_CASE("spring chain: a still pose stays exactly animated; lengths are kept every step") {
  const deform::Skeleton skeleton = chain_skeleton(5, 0.2f);
  deform::SpringChains springs(skeleton, {whole_chain(5)}, {});
  std::vector<glm::mat4> world = chain_world(skeleton, glm::dmat4(1.0));
  for (int n = 0; n < 30; ++n) {
    std::vector<glm::mat4> out = world;
    REQUIRE(springs.run(n == 0 ? 0.0f : 1.0f / 60.0f, out));
    for (std::size_t b = 0; b < out.size(); ++b)
      for (int c = 0; c < 4; ++c) CHECK(glm::length(out[b][c] - world[b][c]) < 1e-6f);
  }
  const Whip whip;
  deform::SpringChains moving(skeleton, {whole_chain(5)}, {});
  for (int n = 0; n <= 120; ++n) {
    std::vector<glm::mat4> w = chain_world(skeleton, whip.root(n / 60.0));
    REQUIRE(moving.run(n == 0 ? 0.0f : 1.0f / 60.0f, w));
    const std::span<const glm::vec3> points = moving.points(0);
    for (std::size_t i = 1; i < points.size(); ++i)
      CHECK(glm::length(points[i] - points[i - 1]) == doctest::Approx(i == 1 ? 0.2f : 0.2f).epsilon(1e-4));
    // The bent pose puts every chain bone's head on the simulated chain.
    for (std::size_t i = 2; i < points.size(); ++i) CHECK(glm::length(glm::vec3(w[i][3]) - points[i - 1]) < 1e-5f);
  }
}

TEST_CASE("spring chain: one link against a plain fine-step reference of the same model") {
  const deform::Skeleton skeleton = chain_skeleton(1, 0.3f);
  deform::SpringChainSpec spec = whole_chain(1);
  spec.tip = glm::vec3(0.3f, 0.0f, 0.0f);
  spec.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  const Whip whip;
  const std::vector<glm::vec3> tips = run_whip(skeleton, {spec}, {}, whip, frame_times(60, 2.0, false), true);
  // Reference: symplectic Euler at 10 µs in double toward the animated tail, then the length kept.
  const double omega = 2 * pi * spec.frequency, zeta = spec.damping_ratio, length = 0.3;
  const auto animated = [&](double t, glm::dvec3& head, glm::dvec3& tail) {
    const glm::dmat4 m = whip.root(t) * glm::dmat4(skeleton.bind_world()[1]);
    head = glm::dvec3(m[3]);
    tail = glm::dvec3(m * glm::dvec4(0.3, 0, 0, 1));
  };
  glm::dvec3 head, tail;
  animated(0.0, head, tail);
  glm::dvec3 p = tail, v(0.0);
  const double h = 1.0 / 90000.0;  // 6,000 steps per checkpoint
  std::vector<glm::dvec3> reference;
  for (int n = 1; n <= 180000; ++n) {
    glm::dvec3 head0, tail0;
    animated((n - 1) * h, head0, tail0);
    animated(n * h, head, tail);
    const glm::dvec3 rest_velocity = (tail - tail0) / h;
    v += h * (-omega * omega * (p - tail0) - 2 * zeta * omega * (v - rest_velocity) + glm::dvec3(0, -9.81, 0));
    p += h * v;
    const glm::dvec3 along = glm::normalize(p - head);
    p = head + along * length;
    v -= glm::dot(v - (head - head0) / h, along) * along;
    if (n % 6000 == 0) reference.push_back(p);
  }
  REQUIRE(reference.size() == tips.size());
  double error = 0.0, amplitude = 0.0;
  for (std::size_t c = 0; c < tips.size(); ++c) {
    error = std::max(error, glm::length(glm::dvec3(tips[c]) - reference[c]));
    amplitude = std::max(amplitude, glm::length(reference[c] - reference.front()));
  }
  INFO("error " << error << " of amplitude " << amplitude);
  CHECK(error < 0.01 * amplitude);
}

TEST_CASE("spring chain: a whip is the same at 15-240 Hz and jittered (0.5%, 2% with a collider), at any scale") {
  // Six links amplify what frames cannot show: between 15 Hz frames the pose is a cubic, off by about (Ωh)⁴/384 of
  // the motion, which a lightly damped long chain magnifies (docs/elasticity.md, "Spring chains"); these settings
  // stay within the target at 15 Hz too.
  const deform::Skeleton skeleton = chain_skeleton(6, 0.15f);
  deform::SpringChainSpec spec = whole_chain(6);
  spec.damping_ratio = 0.4f;
  spec.frequency = 4.0f;
  spec.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  spec.radius = 0.02f;
  deform::SpringCollider ball;
  ball.bone = 0;
  ball.start = ball.end = glm::vec3(0.55f, -0.35f, 0.0f);
  ball.radius = 0.2f;
  for (const bool with_collider : {false, true}) {
    deform::SpringChainSpec chain = spec;
    if (with_collider) chain.colliders = {0};
    const std::vector<deform::SpringCollider> colliders =
        with_collider ? std::vector{ball} : std::vector<deform::SpringCollider>{};
    std::vector<glm::vec3> at_unit;
    for (const double scale : {1.0, 0.01, 100.0}) {
      Whip whip;
      whip.scale = scale;
      std::vector<std::vector<glm::vec3>> runs;
      float closest = 1e30f;
      for (const double hz : {15.0, 30.0, 60.0, 144.0, 240.0})
        runs.push_back(run_whip(skeleton, {chain}, colliders, whip, frame_times(hz, 3.0, false), true, &closest));
      runs.push_back(run_whip(skeleton, {chain}, colliders, whip, frame_times(240.0, 3.0, true), true, &closest));
      const Spread spread = spread_of(runs);
      INFO("collider " << with_collider << " scale " << scale << ": spread " << spread.percent() << "%");
      CHECK(spread.percent() < (with_collider ? 2.0 : 0.5));
      if (with_collider) {  // touched, hardly entered
        CHECK(closest >= float(scale) * (0.2f + 0.02f) * 0.95f);
        CHECK(closest <= float(scale) * (0.2f + 0.02f) * 1.01f);
      }
      if (scale == 1.0) {
        at_unit = runs[2];
      } else {  // the same motion, scaled
        double difference = 0.0;
        for (std::size_t c = 0; c < at_unit.size(); ++c)
          difference = std::max(difference, double(glm::length(runs[2][c] / float(scale) - at_unit[c])));
        CHECK(100.0 * difference * scale / spread.amplitude < 0.5);
      }
    }
  }
}

TEST_CASE("spring chain: without rates the motion between frames is linear, and still close across rates") {
  const deform::Skeleton skeleton = chain_skeleton(4, 0.2f);
  const Whip whip;
  std::vector<std::vector<glm::vec3>> runs;
  deform::SpringChainSpec spec = whole_chain(4);
  spec.damping_ratio = 0.4f;
  spec.frequency = 4.0f;
  for (const double hz : {30.0, 60.0, 240.0})
    runs.push_back(run_whip(skeleton, {spec}, {}, whip, frame_times(hz, 2.0, false), false));
  const Spread spread = spread_of(runs);
  INFO("spread " << spread.percent() << "%");
  CHECK(spread.percent() < 8.0);
  CHECK(spread.percent() > 0.5);  // and the rates do matter
}

TEST_CASE("spring chain: gravity bends a chain down; the colliders keep it out; nothing else moves") {
  const deform::Skeleton skeleton = chain_skeleton(4, 0.2f);
  deform::SpringChainSpec spec = whole_chain(4);
  spec.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
  deform::SpringChains springs(skeleton, {spec}, {});
  std::vector<glm::mat4> world;
  for (int n = 0; n < 600; ++n) {
    world = chain_world(skeleton, glm::dmat4(1.0));
    REQUIRE(springs.run(n == 0 ? 0.0f : 1.0f / 60.0f, world));
  }
  const std::span<const glm::vec3> points = springs.points(0);
  CHECK(points.back().y < -0.05f);
  CHECK(glm::vec3(world[0][3]) == glm::vec3(0.0f));  // the root is not in the chain
  for (std::size_t i = 1; i + 1 < points.size(); ++i) CHECK(points[i + 1].y < points[i].y);
}

TEST_CASE("spring chains: bad set-ups throw naming the chain or collider; bad per-frame calls refuse") {
  const deform::Skeleton skeleton = chain_skeleton(4, 0.2f);
  const auto throws = [&](std::vector<deform::SpringChainSpec> chains, std::vector<deform::SpringCollider> colliders,
                          const char* what) {
    CHECK_THROWS_WITH_AS(deform::SpringChains(skeleton, chains, colliders), doctest::Contains(what), deform::Error);
  };
  deform::SpringChainSpec spec = whole_chain(4);
  spec.bones = {1, 3};
  throws({spec}, {}, "parent path");
  spec = whole_chain(4);
  spec.bones = {1, 9};
  throws({spec}, {}, "out of range");
  deform::SpringChainSpec a = whole_chain(4), b = whole_chain(4);
  a.bones = {1, 2};
  b.name = "other";
  b.bones = {2, 3};
  throws({a, b}, {}, "two chains");
  b.bones = {3, 4};
  throws({a, b}, {}, "nest");
  spec = whole_chain(4);
  spec.colliders = {0};
  throws({spec}, {}, "collider index");
  spec = whole_chain(4);
  spec.frequency = 0.0f;
  throws({spec}, {}, "frequency");
  deform::SpringCollider collider;
  collider.bone = 0;
  collider.radius = -1.0f;
  throws({}, {collider}, "collider 0");
  CHECK_THROWS_AS(deform::SpringChains(skeleton, {}, {}, 0.0f), deform::Error);

  deform::SpringChains springs(skeleton, {whole_chain(4)}, {});
  std::vector<glm::mat4> world = chain_world(skeleton, glm::dmat4(1.0));
  CHECK_FALSE(springs.run(-1.0f, world));
  CHECK_FALSE(springs.run(0.1f, std::span<glm::mat4>(world).first(2)));
  CHECK_FALSE(springs.run(0.1f, world, std::vector<glm::mat4>(1)));
  deform::SpringChainSpec tuned = whole_chain(4);
  tuned.damping_ratio = -1.0f;
  CHECK_THROWS_AS(springs.set_settings(0, tuned), deform::Error);
  CHECK_THROWS_AS(springs.set_settings(1, whole_chain(4)), deform::Error);
  CHECK_FALSE(springs.restart(1));
  CHECK(springs.restart(0));
}

TEST_CASE("vrm_spring_settings: at 60 Hz the converted chain moves as VRM's update does; bad parameters refused") {
  // One still link of 0.3 m, gravity switched on at t = 0: it falls, swings and settles where the stiffness holds
  // it (tan θ = gravityPower / stiffness in both). No rest motion, so VRM's drag (on the absolute velocity) and
  // libdeform's damping (on the velocity relative to the rest) act alike.
  deform::VrmSpringJoint joint;
  joint.stiffness = 0.5f;       // about 1.6 Hz on 0.3 m at 60 Hz
  joint.drag_force = 0.1f;      // ζ about 0.32
  joint.gravity_power = 0.15f;  // 9 m/s² at 60 Hz; settles 16.7° down
  const deform::SpringChainSpec converted = deform::vrm_spring_settings(joint, 0.3f);
  CHECK(converted.frequency == doctest::Approx(std::sqrt(0.5 * 60.0 / 0.3) / (2 * pi)).epsilon(1e-5));
  CHECK(converted.damping_ratio == doctest::Approx(-std::log(0.9) * 60.0 / (2 * std::sqrt(100.0))).epsilon(1e-5));
  CHECK(converted.gravity.y == doctest::Approx(-9.0f));
  const deform::Skeleton skeleton = chain_skeleton(1, 0.3f);
  deform::SpringChainSpec spec = converted;
  spec.name = "link";
  spec.bones = {1};
  spec.tip = glm::vec3(0.3f, 0.0f, 0.0f);
  deform::SpringChains ours(skeleton, {spec}, {});
  motion_study::VrmChain vrm({1}, spec.tip, joint, {});
  std::vector<glm::mat4> world = chain_world(skeleton, glm::dmat4(1.0));
  double error = 0.0, lowest = 0.0;
  for (int n = 0; n <= 240; ++n) {
    std::vector<glm::mat4> w = world;
    vrm.run(n == 0 ? 0.0f : 1.0f / 60.0f, w, 1.0f);
    REQUIRE(ours.run(n == 0 ? 0.0f : 1.0f / 60.0f, w));
    error = std::max(error, double(glm::length(ours.points(0).back() - vrm.tip())));
    lowest = std::min(lowest, double(vrm.tip().y));
  }
  const double settled = std::atan(0.15 / 0.5);
  INFO("largest difference " << error << " of the fall " << -lowest);
  CHECK(ours.points(0).back().y == doctest::Approx(-0.3 * std::sin(settled)).epsilon(0.01));
  CHECK(vrm.tip().y == doctest::Approx(-0.3 * std::sin(settled)).epsilon(0.01));
  CHECK(lowest < -0.1);  // it swung past where it settles
  CHECK(error < 0.1 * -lowest);
  joint.drag_force = 1.0f;
  CHECK_THROWS_WITH_AS(deform::vrm_spring_settings(joint, 0.3f), doctest::Contains("dragForce"), deform::Error);
  joint.drag_force = 0.4f;
  CHECK_THROWS_WITH_AS(deform::vrm_spring_settings(joint, 0.0f), doctest::Contains("length"), deform::Error);
  joint.stiffness = 0.0f;
  CHECK_THROWS_WITH_AS(deform::vrm_spring_settings(joint, 0.3f), doctest::Contains("stiffness"), deform::Error);
}

namespace {

// The colliders, in the root's frame: a sphere under the first chain and a slanted capsule under the second.
const glm::vec3 crowd_sphere(0.27f, -0.24f, 0.06f);
constexpr float crowd_sphere_radius = 0.15f;
const glm::vec3 crowd_capsule_start(-0.32f, -0.17f, -0.06f), crowd_capsule_end(-0.27f, -0.12f, 0.12f);
constexpr float crowd_capsule_radius = 0.1f;

// A crowd for SpringCrowdJob: a root with two chains of five hanging from it (so that gravity lays them on the
// colliders under them), a sphere and a slanted capsule; instance i moves at its own phase and amplitude about its own
// axis (crowd_pose), and some have their own frequency and damping. No coordinate plane holds the chains (each bone's
// offset has x, y and z parts), the colliders or the motion, so that the lanes' quaternions (the sub-steps' bends
// and the bend in lanes after a whole step) have all four parts at once: motion in one plane leaves each either
// (w, 0, 0, z) or, folded back, (0, x, y, 0), where a wrong sign on a w·x or z·x term changes no bit.
// `crowded`: the second chain also has 9 far spheres, more colliders than SpringCrowdJob's lanes take, so that it
// runs one instance at a time beside the first chain in lanes.
struct SpringCrowd {
  deform::Skeleton skeleton;
  std::vector<deform::SpringChains> instances;
};

SpringCrowd spring_crowd(std::size_t count, std::uint32_t seed, bool crowded = false) {
  std::vector<deform::Bone> bones;
  bones.push_back({"root", -1, {1, 6}, glm::vec3(0.0f), glm::vec3(0.0f), {}});
  for (int s = 0; s < 2; ++s) {
    for (int k = 0; k < 5; ++k) {
      const auto id = std::int32_t(1 + s * 5 + k);
      bones.push_back({"strand" + std::to_string(s) + "_" + std::to_string(k),
                       k == 0 ? 0 : id - 1,
                       k + 1 < 5 ? std::vector<std::int32_t>{id + 1} : std::vector<std::int32_t>{},
                       k == 0   ? (s == 0 ? glm::vec3(0.1f, 0.0f, 0.03f) : glm::vec3(-0.1f, 0.0f, -0.03f))
                       : s == 0 ? glm::vec3(0.05f, -0.012f, 0.032f)
                                : glm::vec3(-0.045f, 0.015f, 0.04f),
                       glm::vec3(0.0f),
                       {}});
    }
  }
  SpringCrowd crowd{deform::Skeleton(bones), {}};
  std::vector<deform::SpringChainSpec> chains;
  for (int s = 0; s < 2; ++s) {
    deform::SpringChainSpec chain;
    chain.name = "strand" + std::to_string(s);
    for (int k = 0; k < 5; ++k) chain.bones.push_back(1 + s * 5 + k);
    chain.frequency = 2.0f;
    chain.damping_ratio = 0.2f;
    chain.gravity = glm::vec3(0.0f, -9.81f, 0.0f);
    chain.radius = 0.02f;
    chain.colliders = {0, 1};
    chains.push_back(chain);
  }
  std::vector<deform::SpringCollider> colliders = {{0, crowd_sphere, crowd_sphere, crowd_sphere_radius},
                                                   {0, crowd_capsule_start, crowd_capsule_end, crowd_capsule_radius}};
  if (crowded) {
    for (std::uint32_t n = 0; n < 9; ++n) {
      const auto far = float(50 + n);
      colliders.push_back({0, glm::vec3(far, far, 0.0f), glm::vec3(far, far, 0.0f), 0.05f});
      chains[1].colliders.push_back(std::uint32_t(colliders.size() - 1));
    }
  }
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> uniform(0.5f, 4.0f);
  for (std::size_t i = 0; i < count; ++i) {
    crowd.instances.emplace_back(crowd.skeleton, chains, colliders);
    if (i % 3 == 1) {
      deform::SpringChainSpec tuned = chains[1];
      tuned.frequency = uniform(random);
      tuned.damping_ratio = uniform(random) * 0.2f;
      crowd.instances.back().set_settings(1, tuned);
    }
  }
  return crowd;
}

// Instance i's animated pose at time t: the root bobbing along a slanted line and swinging about an axis of its own
// (x, y and z parts, none zero, other for each i mod 15), each strand's bones curling about a slanted axis of the
// strand's, at the instance's own phase; every bone's world matrix by forward kinematics from its bind offset (the
// crowd's bones have no bind rotation). The rate by central differences.
void crowd_pose(const deform::Skeleton& skeleton, std::size_t i, double t, std::span<glm::mat4> world,
                std::span<glm::mat4> rate) {
  const double phase = 0.71 * double(i), amplitude = 0.3 + 0.05 * double(i % 7);
  const glm::dvec3 axis = glm::normalize(glm::dvec3(0.4 + 0.15 * double(i % 5), 0.8 - 0.3 * double(i % 3), 1.0));
  const glm::dvec3 curl_axes[2] = {glm::normalize(glm::dvec3(0.3, 0.5, -0.8)),
                                   glm::normalize(glm::dvec3(-0.6, 0.4, 0.7))};
  const std::span<const deform::Bone> bones = skeleton.bones();
  const auto posed = [&](double time, std::vector<glm::dmat4>& out) {
    out.resize(bones.size());
    for (std::size_t b = 0; b < bones.size(); ++b) {
      if (bones[b].parent < 0) {
        const double bob = 0.1 * std::sin(2 * pi * 1.3 * time + phase);
        out[b] = glm::translate(glm::dmat4(1.0), glm::dvec3(0.03, 1.0, -0.04) * bob);
        out[b] = glm::rotate(out[b], amplitude * std::sin(2 * pi * 0.9 * time + phase), axis);
        continue;
      }
      const double curl = 0.1 * std::sin(2 * pi * 1.7 * time + phase + 0.6 * double(b));
      const glm::dmat4 placed =
          glm::translate(out[std::size_t(bones[b].parent)], glm::dvec3(bones[b].bind_translation));
      out[b] = glm::rotate(placed, curl, curl_axes[b < 6 ? 0 : 1]);
    }
  };
  std::vector<glm::dmat4> now, before, after;
  posed(t, now);
  posed(t - 1e-6, before);
  posed(t + 1e-6, after);
  for (std::size_t b = 0; b < world.size(); ++b) {
    world[b] = glm::mat4(now[b]);
    if (!rate.empty()) rate[b] = glm::mat4((after[b] - before[b]) / 2e-6);
  }
}

bool same_bits(std::span<const glm::mat4> a, std::span<const glm::mat4> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

}  // namespace

TEST_CASE("SpringCrowdJob: the same bits as each instance's run(), any group and range split, colliders hit") {
  constexpr std::size_t count = 37;  // not a multiple of any group
  const SpringCrowd reference_crowd = spring_crowd(count, 7);
  const std::size_t bones = reference_crowd.skeleton.bone_count();
  for (const std::size_t group : {std::size_t(1), std::size_t(3), std::size_t(8)}) {
    for (const std::size_t split : {std::size_t(1), std::size_t(2), std::size_t(5)}) {
      CAPTURE(group);
      CAPTURE(split);
      // Group 8 on 5 ranges: the second chain with more colliders than the lanes take (one instance at a time).
      const bool crowded = group == 8 && split == 5;
      SpringCrowd alone = spring_crowd(count, 7, crowded), together = spring_crowd(count, 7, crowded);
      std::vector<glm::mat4> world(bones * count), rate(world.size()), palette(world.size());
      std::vector<glm::mat4> world_alone(world.size()), palette_alone(world.size());
      std::mt19937 random(11);
      std::uniform_real_distribution<double> jitter(0.9, 1.1);
      double t = 0.0;
      float closest = 1e9f, closest_capsule = 1e9f;  // the tails' least distances to the sphere's and capsule's core
      for (int frame = 0; frame < 90; ++frame) {
        // Frame times jittered so that leftovers differ; a pause (dt 0) now and then; rates on some frames only;
        // some instances reset or restarted, so that their kept states differ in age within a group. On split 1, and
        // every other frame on split 2 (the portable copy), whole sub-steps (1/60 s of 1/240 s): no leftover is owed,
        // so the lanes also bend the pose (end_run()'s corrections, Chain::bent); with a leftover end_run() bends it.
        const bool whole = split == 1 || (split == 2 && frame % 2 == 0);
        const float frame_dt = whole ? float(1.0 / 60.0) : float(jitter(random) / 60.0);
        const float dt = frame == 0 ? 0.0f : frame % 37 == 0 ? 0.0f : frame_dt;
        t += double(dt);
        const bool rates = frame % 4 != 3;
        for (std::size_t i = 0; i < count; ++i) {
          if ((frame == 40 && i % 5 == 2) || (frame == 80 && i % 4 == 0)) {
            alone.instances[i].reset();
            together.instances[i].reset();
          }
          if (frame == 60 && i % 6 == 1) {
            REQUIRE(alone.instances[i].restart(0));
            REQUIRE(together.instances[i].restart(0));
          }
          const std::span<glm::mat4> w = std::span<glm::mat4>(world).subspan(i * bones, bones);
          crowd_pose(alone.skeleton, i, frame == 74 && i % 2 == 0 ? t + 3.0 : t, w,
                     std::span<glm::mat4>(rate).subspan(i * bones, bones));
        }
        world_alone = world;
        for (std::size_t i = 0; i < count; ++i) {
          const auto part = [&](std::vector<glm::mat4>& v) {
            return std::span<glm::mat4>(v).subspan(i * bones, bones);
          };
          REQUIRE(alone.instances[i].run(dt, part(world_alone),
                                         rates ? std::span<const glm::mat4>(part(rate)) : std::span<const glm::mat4>(),
                                         part(palette_alone)));
        }
        deform::SpringCrowdJob job;
        job.instances = together.instances;
        job.dt = dt;
        job.world = world;
        if (rates) job.world_rate = rate;
        job.palette = palette;
        job.group = group;
        // The lanes' portable copy on one split, the widest here on the others (the same bits either way).
        job.isa = split == 2 ? deform::Isa::portable : deform::Isa::automatic;
        REQUIRE(job.validate());
        for (std::size_t part = 0; part < split; ++part)
          REQUIRE(job.run(count * part / split, count * (part + 1) / split));
        REQUIRE(same_bits(world, world_alone));
        REQUIRE(same_bits(palette, palette_alone));
        for (std::size_t i = 0; i < count; ++i) {
          for (std::size_t c = 0; c < 2; ++c) {
            const auto a = alone.instances[i].points(c), b = together.instances[i].points(c);
            REQUIRE(std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
            const glm::mat4& root = world[i * bones];
            const glm::vec3 sphere(root * glm::vec4(crowd_sphere, 1.0f));
            const glm::vec3 from(root * glm::vec4(crowd_capsule_start, 1.0f)),
                to(root * glm::vec4(crowd_capsule_end, 1.0f));
            for (const glm::vec3& p : b) {
              closest = std::min(closest, glm::length(p - sphere));
              const float along =
                  std::clamp(glm::dot(p - from, to - from) / glm::dot(to - from, to - from), 0.0f, 1.0f);
              closest_capsule = std::min(closest_capsule, glm::length(p - (from + (to - from) * along)));
            }
          }
        }
      }
      // The chains come to the sphere (radius 0.15 plus the tails' 0.02) and to the capsule (0.1 plus 0.02) and are
      // kept about out of them (the length may pull a tail back in by a little): both colliders were in play.
      CHECK(closest < 0.171f);
      CHECK(closest > 0.15f);
      CHECK(closest_capsule < 0.121f);
      CHECK(closest_capsule > 0.1f);
    }
  }
}

TEST_CASE("SpringCrowdJob: refuses bad sizes, dt, group, range and an instance laid out unlike the first") {
  SpringCrowd crowd = spring_crowd(4, 3);
  const std::size_t bones = crowd.skeleton.bone_count();
  std::vector<glm::mat4> world(bones * 4), palette(world.size());
  for (std::size_t i = 0; i < 4; ++i)
    crowd_pose(crowd.skeleton, i, 0.0, std::span<glm::mat4>(world).subspan(i * bones, bones), {});
  deform::SpringCrowdJob job;
  job.instances = crowd.instances;
  job.dt = 1.0f / 60.0f;
  job.world = world;
  job.palette = palette;
  REQUIRE(job.validate());
  const std::vector<glm::mat4> before = world;
  const auto refused = [&](deform::SpringCrowdJob bad, const char* why) {
    CAPTURE(why);
    CHECK_FALSE(bad.validate());
    CHECK(std::string(bad.validate().reason()).find(why) != std::string::npos);
    CHECK_FALSE(bad.run());
    CHECK(same_bits(world, before));
  };
  deform::SpringCrowdJob bad = job;
  bad.dt = -1.0f;
  refused(bad, "dt");
  bad.dt = std::nanf("");
  refused(bad, "dt");
  bad = job;
  bad.world = std::span<glm::mat4>(world).first(world.size() - 1);
  refused(bad, "world");
  bad = job;
  const std::vector<glm::mat4> short_rate(3);
  bad.world_rate = short_rate;
  refused(bad, "world_rate");
  bad = job;
  bad.palette = std::span<glm::mat4>(palette).first(bones);
  refused(bad, "palette");
  bad = job;
  bad.group = 0;
  refused(bad, "group");
  bad.group = deform::SpringCrowdJob::max_group + 1;
  refused(bad, "group");
  bad = job;
  bad.isa = deform::Isa(200);  // no such instruction set
  refused(bad, "instruction set");
  for (const deform::Isa isa : {deform::Isa::avx2, deform::Isa::avx512, deform::Isa::neon, deform::Isa::simd128}) {
    bad.isa = isa;
    if (!deform::isa_available(isa)) refused(bad, "instruction set");
  }
  CHECK_FALSE(job.run(3, 2));
  CHECK_FALSE(job.run(0, 5));
  // An instance with one chain fewer.
  std::vector<deform::SpringChains> mixed = crowd.instances;
  deform::SpringChainSpec one = crowd.instances[0].spec(0);
  mixed[2] = deform::SpringChains(crowd.skeleton, {one},
                                  {crowd.instances[0].colliders().begin(), crowd.instances[0].colliders().end()});
  bad = job;
  bad.instances = mixed;
  refused(bad, "laid out");
  CHECK(bad.run(0, 2));  // the range before it is fine
  CHECK_FALSE(bad.run(1, 3));
  // No instances: nothing to do, and matrices for none refused.
  deform::SpringCrowdJob empty;
  CHECK(empty.validate());
  CHECK(empty.run());
  empty.world = world;
  CHECK_FALSE(empty.validate());
  CHECK(job.run());  // the first run starts at rest on the pose
  CHECK(job.run());  // then gravity bends the chains
  CHECK_FALSE(same_bits(world, before));
}
