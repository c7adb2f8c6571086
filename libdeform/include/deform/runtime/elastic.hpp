#pragma once
// Elasticity: lattice control points as damped harmonic oscillators (thesis §4.4, §8.4.2), optional neighbour springs.
//
// Each point of an ElasticLattice is a mass m pulled toward its rest position r by a spring k and slowed by a damper b
// acting on its velocity relative to the rest (eq. 12: m·y'' = -k·y - b·y', y = p - r). The rest is the caller's: it
// is where the point would be without elasticity (a lattice's stretched or bone-carried grid), given anew each step.
// Damping is set as the ratio ζ = b / (2·√(k·m)): ζ < 1 oscillates (under-damped), ζ = 1 returns fastest without
// overshoot (critical), ζ > 1 creeps back (over-damped) — the sign of b² - 4km of §4.4.
//
// Two integrators:
//  - Integrator::exact (default): the closed-form solution of eq. 12 over each step. Frame-rate independent (any
//    sequence of steps summing to T gives the state at T, up to float rounding) and unconditionally stable.
//  - Integrator::verlet: the thesis' position Verlet with a constant per-frame damping Kd,
//    p += (p - p_old)·(1 - Kd) + a·dt². Kept for fidelity; its motion changes with the frame rate (Kd is per frame,
//    not per second) and it diverges for dt > 2/ω. docs/elasticity.md derives both.
// With neighbour springs on, the state advances in fixed sub-steps (see NeighbourSprings).
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
namespace deform {

// One oscillator: stiffness, damping ratio, mass. Units: with positions in metres and time in seconds, k is N/m and
// m kg; only ω = √(k/m) and ζ matter to the motion.
struct ElasticParams {
  float stiffness = 150.0f;    // k > 0
  float damping_ratio = 0.2f;  // ζ >= 0: < 1 under-, 1 critically, > 1 over-damped
  float mass = 1.0f;           // m > 0 (the thesis uses unit mass)
  bool operator==(const ElasticParams&) const = default;
};

enum class DampingRegime { under, critical, over };

// True when every field is finite and k > 0, m > 0, ζ >= 0.
DEFORM_RUNTIME_API bool is_valid(const ElasticParams& params) noexcept;
// ω = √(k/m), rad/s.
DEFORM_RUNTIME_API double angular_frequency(const ElasticParams& params) noexcept;
// b = 2·ζ·√(k·m), the damper of eq. 11 (force per unit velocity).
DEFORM_RUNTIME_API double damping_coefficient(const ElasticParams& params) noexcept;
// The regime; |ζ - 1| <= 1e-6 counts as critical.
DEFORM_RUNTIME_API DampingRegime damping_regime(const ElasticParams& params) noexcept;
// The seed's Kd that matches ζ at one frame step: the velocity lost per frame, Kd = 1 - exp(-(b/m)·frame_dt).
// Valid only at that frame step: the same Kd at another frame rate is another damping (hence frame-rate dependence).
DEFORM_RUNTIME_API double verlet_kd(const ElasticParams& params, double frame_dt) noexcept;
// The longest step the seed's Verlet integrator stays stable at: x' = x + (1 - Kd)(x - x_old) - (ωh)²x is stable for
// ωh < √(2(2 - Kd)) (2/ω undamped, √2/ω at Kd = 1). ElasticLattice::step refuses a longer Verlet step instead of
// diverging; the exact integrator has no bound.
DEFORM_RUNTIME_API double verlet_max_step(const ElasticParams& params, double kd) noexcept;
// Time for a point released at rest-offset A with zero velocity to stay within `tolerance`·A for good (0 < tolerance
// < 1). Under-damped: the envelope bound ln(1/(tolerance·√(1-ζ²)))/(ζω) (infinite when ζ = 0); critical and over:
// the exact crossing of the monotonic response, found by bisection.
DEFORM_RUNTIME_API double settling_time(const ElasticParams& params, double tolerance = 0.02) noexcept;

// The exact solution of eq. 12 over a time t as a 2×2 map of (offset y, velocity v):
//   y(t) = position_from_offset·y0 + position_from_velocity·v0,
//   v(t) = velocity_from_offset·y0 + velocity_from_velocity·v0.
// Computed in double for all three regimes (one expression with cos/sin or cosh/sinh, no cancellation near ζ = 1,
// no overflow for large t). Cost: a few exp/sin calls; per point the step is then 4 multiply-adds per axis.
struct OscillatorStep {
  double position_from_offset = 1.0;
  double position_from_velocity = 0.0;
  double velocity_from_offset = 0.0;
  double velocity_from_velocity = 1.0;
};
DEFORM_RUNTIME_API OscillatorStep oscillator_step(const ElasticParams& params, double t) noexcept;

// What an acceleration f acting on the point adds over a time t, when f changes linearly from f0 at the start to f1
// at the end (m·y'' = -k·y - b·y' + m·f): exactly, with the homogeneous part from oscillator_step,
//   y(t) += position_from_start·f0 + position_from_end·f1,   v(t) += velocity_from_start·f0 + velocity_from_end·f1.
// Such an f is gravity (constant) or, for points whose rest rides on a moving frame, minus the rest's acceleration
// (inertia): a rest moving along a cubic between two frames has an acceleration linear in time, so a step over a
// piecewise-cubic rest is exact. Computed in double; for ω·t < 1e-4 from the Taylor series (no cancellation).
struct ForcedStep {
  double position_from_start = 0.0;
  double position_from_end = 0.0;
  double velocity_from_start = 0.0;
  double velocity_from_end = 0.0;
};
DEFORM_RUNTIME_API ForcedStep forced_step(const ElasticParams& params, double t) noexcept;

// The accelerations at the start and the end of a step of length h of a point moving along the cubic (Hermite)
// through position p0 with velocity v0 at the start and p1, v1 at the end: the cubic's second derivative, linear in
// time between these two values. With v0 = v1 = (p1 - p0) / h both are 0 (a point moving linearly).
struct HermiteAccelerations {
  glm::vec3 start{0.0f};
  glm::vec3 end{0.0f};
};
DEFORM_RUNTIME_API HermiteAccelerations hermite_accelerations(glm::vec3 p0, glm::vec3 v0, glm::vec3 p1, glm::vec3 v1,
                                                              float h) noexcept;

enum class Integrator { exact, verlet };

// Springs between control points of a grid (thesis §8.2.3, fig. 38): structural (axis neighbours), shear (face and
// body diagonals), bend (two apart along an axis). Each pulls its two points toward the distance their rests have
// now, so the springs add wobble while the points move and never shift where they settle.
// With springs on, the state advances in fixed sub-steps of `substep` seconds (leftover time kept for the next call,
// the positions reported for the exact end of the step): each sub-step integrates the anchor oscillator exactly with
// the spring forces held constant, so only the neighbour springs bound the sub-step (stable for
// substep < 2·√(m / (springs per point · stiffness)) roughly; docs/elasticity.md).
struct NeighbourSprings {
  bool structural = false;
  bool shear = false;
  bool bend = false;
  float stiffness = 50.0f;        // per spring, force per unit of length change, >= 0
  float damping = 1.0f;           // per spring, force per unit of relative speed along it, >= 0
  float substep = 1.0f / 240.0f;  // seconds, > 0
  bool any() const noexcept { return structural || shear || bend; }
  bool operator==(const NeighbourSprings&) const = default;
};

// A spring between two points, by index.
struct Spring {
  std::uint32_t a = 0;
  std::uint32_t b = 0;
};

// The springs of a dims.x × dims.y × dims.z grid of points indexed i + dims.x·(j + dims.y·k) (i fastest, as
// lattice.hpp orders control points), of the kinds `springs` switches on. Empty when no kind is on or a dimension
// is < 1.
DEFORM_RUNTIME_API std::vector<Spring> grid_springs(glm::ivec3 dims, const NeighbourSprings& springs);

// Everything that sets how an ElasticLattice moves.
struct ElasticSettings {
  ElasticParams oscillator;
  Integrator integrator = Integrator::exact;
  float verlet_kd = 0.05f;   // Integrator::verlet only: the seed's per-frame damping in [0, 1]
  NeighbourSprings springs;  // off by default; Integrator::exact only
  bool operator==(const ElasticSettings&) const = default;
};

// The elastic state of a set of points (a lattice's control points): positions, velocities, rests. Construction and
// configuration allocate; step() does not.
class DEFORM_RUNTIME_API ElasticLattice {
 public:
  ElasticLattice() = default;
  // Points start at `rest` with zero velocity. `grid` (points per axis, product = rest.size()) places them for the
  // neighbour springs; {0,0,0} means no grid (springs then ignored). Throws deform::Error when the settings are not
  // valid (see require_valid_settings), a rest position is not finite, or `grid` does not match rest.size().
  explicit ElasticLattice(std::span<const glm::vec3> rest, const ElasticSettings& settings = {},
                          glm::ivec3 grid = glm::ivec3(0));

  // Changes the settings keeping the state. Throws deform::Error when they are not valid.
  void set_settings(const ElasticSettings& settings);
  const ElasticSettings& settings() const noexcept { return settings_; }

  // Pinned points sit on their rest every step (a lattice face that must not move). `pinned` has size() entries,
  // non-zero = pinned. An empty span unpins all. Refuses a size mismatch, changing nothing. Allocates on the first
  // call (configuration, not per frame).
  Status set_pinned(std::span<const std::uint8_t> pinned);

  // Advances the state by dt seconds toward `rest` (size() entries; the rest in effect for the whole step: a rest
  // that moves is sampled once per step). dt = 0 only re-anchors pinned points. Refuses, changing nothing, a dt that
  // is negative or not finite, or a `rest` of the wrong size. Cost O(points (+ springs · sub-steps)), no allocation.
  Status step(float dt, std::span<const glm::vec3> rest);
  // The same step with every point also pushed by an acceleration (the caller's frame, units/s², size() entries
  // each) that changes linearly over the step from accel_start to accel_end: gravity, or minus the rest's own
  // acceleration for points that ride on an accelerating frame (inertia; see DeformerHierarchy). Exact with the exact
  // integrator (forced_step); with neighbour springs the mean of the two is held over the step's sub-steps, and
  // Verlet adds accel_end to its acceleration (both first order in the step). Refuses, changing nothing, what step()
  // refuses and accelerations of the wrong size.
  Status step(float dt, std::span<const glm::vec3> rest, std::span<const glm::vec3> accel_start,
              std::span<const glm::vec3> accel_end);
  // Adds `delta` (size() entries) to the points' velocities, pinned points excepted: an impulse, such as the change
  // of velocity of a rest that moves linearly within each step and turns at the step's start. Refuses, changing
  // nothing, a size mismatch. No allocation.
  Status add_velocity(std::span<const glm::vec3> delta);

  // Puts every point on `rest` with zero velocity (size() entries; refused, changing nothing, otherwise). No
  // allocation.
  Status reset(std::span<const glm::vec3> rest);

  // Cache hints for the state the next step() reads and writes (deform/runtime/prefetch.hpp): no effect on it.
  void prefetch() const noexcept;

  std::size_t size() const noexcept { return positions_.size(); }
  std::span<const glm::vec3> positions() const noexcept { return positions_; }
  std::span<const glm::vec3> velocities() const noexcept { return velocities_; }
  std::span<const glm::vec3> rest() const noexcept { return rest_; }
  std::span<const Spring> springs() const noexcept { return springs_; }

 private:
  void step_exact(double dt, const glm::vec3* accel_start, const glm::vec3* accel_end);
  void step_verlet(float dt, const glm::vec3* accel_end);
  void step_with_springs(double dt, const glm::vec3* accel_start, const glm::vec3* accel_end);
  void substep(double h, std::span<glm::vec3> positions, std::span<glm::vec3> velocities);
  const OscillatorStep& cached_step(double dt, OscillatorStep& cache, double& cache_dt) const;

  ElasticSettings settings_;
  glm::ivec3 grid_{0};
  std::vector<glm::vec3> positions_;
  std::vector<glm::vec3> velocities_;
  std::vector<glm::vec3> rest_;
  std::vector<glm::vec3> previous_;   // Verlet: last step's positions
  std::vector<std::uint8_t> pinned_;  // empty = none pinned
  std::vector<Spring> springs_;
  // Sub-stepping: the state at the last whole sub-step, time owed to it, scratch for forces and the reported state.
  std::vector<glm::vec3> sub_positions_;
  std::vector<glm::vec3> sub_velocities_;
  std::vector<glm::vec3> forces_;
  std::vector<glm::vec3> held_accel_;  // sub-stepping: the acceleration held over this call's sub-steps
  double owed_ = 0.0;
  float last_dt_ = 0.0f;  // Verlet: the last step, which turns a change of velocity into one of p_old
  OscillatorStep step_cache_;
  ForcedStep forced_cache_;
  double step_cache_dt_ = -1.0;
  OscillatorStep sub_cache_;
  double sub_cache_dt_ = -1.0;
};

// Throws deform::Error ("<settings>", naming the field) when a parameter is not finite or out of its range.
DEFORM_RUNTIME_API void require_valid_settings(const ElasticSettings& settings);

}  // namespace deform
