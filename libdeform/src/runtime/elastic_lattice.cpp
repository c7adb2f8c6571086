// Damped harmonic oscillators over a flat array of points: the closed-form step, the seed's Verlet, the state.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/prefetch.hpp"
#include "finite.hpp"
namespace deform {
namespace {

void require(bool ok, const char* field, const char* what) {
  if (!ok) throw Error::invalid_argument(field, what);
}

}  // namespace

bool is_valid(const ElasticParams& params) noexcept {
  return finite(params.stiffness) && finite(params.damping_ratio) && finite(params.mass) && params.stiffness > 0.0f &&
         params.mass > 0.0f && params.damping_ratio >= 0.0f;
}

double angular_frequency(const ElasticParams& params) noexcept {
  return std::sqrt(double(params.stiffness) / double(params.mass));
}

double damping_coefficient(const ElasticParams& params) noexcept {
  return 2.0 * double(params.damping_ratio) * std::sqrt(double(params.stiffness) * double(params.mass));
}

DampingRegime damping_regime(const ElasticParams& params) noexcept {
  const double zeta = params.damping_ratio;
  if (std::abs(zeta - 1.0) <= 1e-6) return DampingRegime::critical;
  return zeta < 1.0 ? DampingRegime::under : DampingRegime::over;
}

double verlet_kd(const ElasticParams& params, double frame_dt) noexcept {
  return 1.0 - std::exp(-damping_coefficient(params) / double(params.mass) * frame_dt);
}

double verlet_max_step(const ElasticParams& params, double kd) noexcept {
  return std::sqrt(2.0 * (2.0 - kd)) / angular_frequency(params);
}

OscillatorStep oscillator_step(const ElasticParams& params, double t) noexcept {
  // y(t) = e^(-a t) [(C + a S) y0 + S v0],  v(t) = e^(-a t) [-ω² S y0 + (C - a S) v0], with a = ζω and
  // (C, S) = (cos st, sin st / s) under-damped, (1, t) critical, (cosh st, sinh st / s) over-damped, s = ω√|1 - ζ²|.
  const double omega = angular_frequency(params);
  const double zeta = params.damping_ratio;
  const double a = zeta * omega;
  double eC = 0.0;  // e^(-a t) · C
  double eS = 0.0;  // e^(-a t) · S
  switch (damping_regime(params)) {
    case DampingRegime::under: {
      const double s = omega * std::sqrt(1.0 - zeta * zeta);
      const double e = std::exp(-a * t);
      eC = e * std::cos(s * t);
      eS = e * std::sin(s * t) / s;
      break;
    }
    case DampingRegime::critical: {
      const double e = std::exp(-omega * t);
      eC = e;
      eS = e * t;
      break;
    }
    case DampingRegime::over: {
      const double s = omega * std::sqrt(zeta * zeta - 1.0);
      const double st = s * t;
      if (st < 20.0) {  // expm1 keeps sinh(st)/s accurate when s·t is small (ζ near 1)
        const double e = std::exp(-a * t);
        eC = e * std::cosh(st);
        eS = e * 0.5 * (std::expm1(st) - std::expm1(-st)) / s;
      } else {  // both exponents are <= 0 here (s < a), so nothing overflows
        const double slow = std::exp((s - a) * t);
        const double fast = std::exp(-(s + a) * t);
        eC = 0.5 * (slow + fast);
        eS = 0.5 * (slow - fast) / s;
      }
      break;
    }
  }
  OscillatorStep m;
  m.position_from_offset = eC + a * eS;
  m.position_from_velocity = eS;
  m.velocity_from_offset = -omega * omega * eS;
  m.velocity_from_velocity = eC - a * eS;
  return m;
}

ForcedStep forced_step(const ElasticParams& params, double t) noexcept {
  // Particular solutions of y'' + 2ζω y' + ω² y = f(s): for f = 1, y_p = 1/ω²; for the ramp f = s/t,
  // y_p = (s - 2ζ/ω) / (t ω²). Starting from y = v = 0, the forced part is y_p plus the homogeneous flow of -y_p(0),
  // -y_p'(0). The start's share is the constant's response minus the ramp's.
  ForcedStep f;
  const double omega = angular_frequency(params);
  if (!(t > 0.0)) return f;
  if (omega * t < 1e-4) {  // Taylor: y ≈ ∫(t - s) f(s) ds, v ≈ ∫ f(s) ds
    f.position_from_start = t * t / 3.0;
    f.position_from_end = t * t / 6.0;
    f.velocity_from_start = 0.5 * t;
    f.velocity_from_end = 0.5 * t;
    return f;
  }
  const OscillatorStep m = oscillator_step(params, t);
  const double w2 = omega * omega;
  const double c = 2.0 * double(params.damping_ratio) / omega;
  const double constant_y = (1.0 - m.position_from_offset) / w2;
  const double constant_v = -m.velocity_from_offset / w2;
  const double ramp_y = (t - m.position_from_velocity - c * (1.0 - m.position_from_offset)) / (t * w2);
  const double ramp_v = (1.0 - m.velocity_from_velocity + c * m.velocity_from_offset) / (t * w2);
  f.position_from_start = constant_y - ramp_y;
  f.position_from_end = ramp_y;
  f.velocity_from_start = constant_v - ramp_v;
  f.velocity_from_end = ramp_v;
  return f;
}

HermiteAccelerations hermite_accelerations(glm::vec3 p0, glm::vec3 v0, glm::vec3 p1, glm::vec3 v1, float h) noexcept {
  // p(s) = h00 p0 + h10 h v0 + h01 p1 + h11 h v1 with the cubic Hermite basis; p''(0) and p''(h):
  const glm::vec3 chord = (p1 - p0) * (6.0f / (h * h));
  HermiteAccelerations a;
  a.start = chord - (4.0f * v0 + 2.0f * v1) / h;
  a.end = -chord + (2.0f * v0 + 4.0f * v1) / h;
  return a;
}

double settling_time(const ElasticParams& params, double tolerance) noexcept {
  if (!is_valid(params) || !(tolerance > 0.0 && tolerance < 1.0)) return std::numeric_limits<double>::quiet_NaN();
  const double omega = angular_frequency(params);
  const double zeta = params.damping_ratio;
  if (damping_regime(params) == DampingRegime::under) {
    if (zeta == 0.0) return std::numeric_limits<double>::infinity();
    return std::log(1.0 / (tolerance * std::sqrt(1.0 - zeta * zeta))) / (zeta * omega);
  }
  // Critical or over-damped from rest offset 1: y(t) falls monotonically from 1 to 0.
  double lo = 0.0;
  double hi = 1.0 / omega;
  while (oscillator_step(params, hi).position_from_offset > tolerance) {
    lo = hi;
    hi *= 2.0;
  }
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (oscillator_step(params, mid).position_from_offset > tolerance ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

void require_valid_settings(const ElasticSettings& settings) {
  const ElasticParams& p = settings.oscillator;
  require(finite(p.stiffness) && p.stiffness > 0.0f, "stiffness", "must be finite and > 0");
  require(finite(p.mass) && p.mass > 0.0f, "mass", "must be finite and > 0");
  require(finite(p.damping_ratio) && p.damping_ratio >= 0.0f, "damping_ratio", "must be finite and >= 0");
  require(finite(settings.verlet_kd) && settings.verlet_kd >= 0.0f && settings.verlet_kd <= 1.0f, "verlet_kd",
          "must be in [0, 1]");
  const NeighbourSprings& s = settings.springs;
  require(finite(s.stiffness) && s.stiffness >= 0.0f, "springs.stiffness", "must be finite and >= 0");
  require(finite(s.damping) && s.damping >= 0.0f, "springs.damping", "must be finite and >= 0");
  require(finite(s.substep) && s.substep > 0.0f && s.substep <= 1.0f, "springs.substep", "must be in (0, 1] seconds");
}

ElasticLattice::ElasticLattice(std::span<const glm::vec3> rest, const ElasticSettings& settings, glm::ivec3 grid)
    : grid_(grid) {
  require_valid_settings(settings);
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (!finite(rest[i])) throw Error::invalid_argument("point " + std::to_string(i), "rest position is not finite");
  }
  const bool no_grid = grid == glm::ivec3(0);
  if (!no_grid && (grid.x < 1 || grid.y < 1 || grid.z < 1 ||
                   std::size_t(grid.x) * std::size_t(grid.y) * std::size_t(grid.z) != rest.size())) {
    throw Error::invalid_argument("grid", "grid dimensions do not match the point count");
  }
  positions_.assign(rest.begin(), rest.end());
  previous_ = positions_;
  rest_ = positions_;
  velocities_.assign(rest.size(), glm::vec3(0.0f));
  sub_positions_ = positions_;
  sub_velocities_ = velocities_;
  forces_.assign(rest.size(), glm::vec3(0.0f));
  held_accel_.assign(rest.size(), glm::vec3(0.0f));
  set_settings(settings);
}

void ElasticLattice::set_settings(const ElasticSettings& settings) {
  require_valid_settings(settings);
  if (settings.integrator != settings_.integrator) previous_ = positions_;  // Verlet restarts from rest velocity
  settings_ = settings;
  springs_ = grid_ == glm::ivec3(0) ? std::vector<Spring>{} : grid_springs(grid_, settings.springs);
  step_cache_dt_ = -1.0;
  sub_cache_dt_ = -1.0;
  sub_positions_ = positions_;  // the sub-step clock restarts from the reported state
  sub_velocities_ = velocities_;
  owed_ = 0.0;
}

Status ElasticLattice::set_pinned(std::span<const std::uint8_t> pinned) {
  if (!pinned.empty() && pinned.size() != size()) return Status::failure("pinned is neither empty nor one per point");
  pinned_.assign(pinned.begin(), pinned.end());
  return {};
}

Status ElasticLattice::reset(std::span<const glm::vec3> rest) {
  if (rest.size() != size()) return Status::failure("rest does not have one entry per point");
  std::copy(rest.begin(), rest.end(), positions_.begin());
  std::copy(rest.begin(), rest.end(), previous_.begin());
  std::copy(rest.begin(), rest.end(), rest_.begin());
  std::copy(rest.begin(), rest.end(), sub_positions_.begin());
  std::fill(velocities_.begin(), velocities_.end(), glm::vec3(0.0f));
  std::fill(sub_velocities_.begin(), sub_velocities_.end(), glm::vec3(0.0f));
  owed_ = 0.0;
  return {};
}

Status ElasticLattice::step(float dt, std::span<const glm::vec3> rest) { return step(dt, rest, {}, {}); }

Status ElasticLattice::step(float dt, std::span<const glm::vec3> rest, std::span<const glm::vec3> accel_start,
                            std::span<const glm::vec3> accel_end) {
  if (!(dt >= 0.0f) || !finite(dt)) return Status::failure("dt is negative or not finite");
  if (rest.size() != size()) return Status::failure("rest does not have one entry per point");
  const bool forced = !accel_start.empty() || !accel_end.empty();
  if (forced && (accel_start.size() != size() || accel_end.size() != size()))
    return Status::failure("accelerations do not have one entry per point");
  if (settings_.integrator == Integrator::verlet &&
      !(double(dt) < verlet_max_step(settings_.oscillator, double(settings_.verlet_kd))))
    return Status::failure("dt is beyond the Verlet integrator's stable step (verlet_max_step)");
  std::copy(rest.begin(), rest.end(), rest_.begin());
  const glm::vec3* start = forced ? accel_start.data() : nullptr;
  const glm::vec3* end = forced ? accel_end.data() : nullptr;
  if (dt > 0.0f) {
    if (settings_.integrator == Integrator::verlet) {
      step_verlet(dt, end);
    } else if (!springs_.empty()) {
      step_with_springs(dt, start, end);
    } else {
      step_exact(dt, start, end);
    }
  }
  if (!pinned_.empty()) {
    // The Verlet history and the sub-step state only where the integrator reads them: set_settings() restarts them
    // from positions_ and velocities_ when it starts reading them (a crowd's frame then leaves those lines alone).
    const bool verlet = settings_.integrator == Integrator::verlet;
    const bool substepping = !verlet && !springs_.empty();
    for (std::size_t i = 0; i < size(); ++i) {
      if (!pinned_[i]) continue;
      positions_[i] = rest_[i];
      velocities_[i] = glm::vec3(0.0f);
      if (verlet) previous_[i] = rest_[i];
      if (substepping) sub_positions_[i] = rest_[i], sub_velocities_[i] = glm::vec3(0.0f);
    }
  }
  return {};
}

Status ElasticLattice::add_velocity(std::span<const glm::vec3> delta) {
  if (delta.size() != size()) return Status::failure("delta does not have one entry per point");
  for (std::size_t i = 0; i < size(); ++i) {
    if (!pinned_.empty() && pinned_[i]) continue;
    velocities_[i] += delta[i];
    sub_velocities_[i] += delta[i];
    previous_[i] -= delta[i] * last_dt_;  // Verlet's velocity is p - p_old over the last step
  }
  return {};
}

const OscillatorStep& ElasticLattice::cached_step(double dt, OscillatorStep& cache, double& cache_dt) const {
  if (dt != cache_dt) {  // a fixed frame rate computes the map once
    cache = oscillator_step(settings_.oscillator, dt);
    cache_dt = dt;
  }
  return cache;
}

void ElasticLattice::step_exact(double dt, const glm::vec3* accel_start, const glm::vec3* accel_end) {
  const double cached_dt = step_cache_dt_;
  const OscillatorStep& m = cached_step(dt, step_cache_, step_cache_dt_);
  if (cached_dt != step_cache_dt_) forced_cache_ = forced_step(settings_.oscillator, dt);
  const float py = float(m.position_from_offset), pv = float(m.position_from_velocity);
  const float vy = float(m.velocity_from_offset), vv = float(m.velocity_from_velocity);
  const std::size_t n = size();
  glm::vec3* p = positions_.data();
  glm::vec3* v = velocities_.data();
  const glm::vec3* r = rest_.data();
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 y = p[i] - r[i];
    const glm::vec3 u = v[i];
    p[i] = r[i] + py * y + pv * u;
    v[i] = vy * y + vv * u;
  }
  if (accel_start == nullptr) return;
  const ForcedStep& f = forced_cache_;
  const float ps = float(f.position_from_start), pe = float(f.position_from_end);
  const float vs = float(f.velocity_from_start), ve = float(f.velocity_from_end);
  for (std::size_t i = 0; i < n; ++i) {
    p[i] += ps * accel_start[i] + pe * accel_end[i];
    v[i] += vs * accel_start[i] + ve * accel_end[i];
  }
}

void ElasticLattice::step_verlet(float dt, const glm::vec3* accel_end) {
  // The seed (§8.4.2): unit-time Verlet with the implicit velocity p - p_old scaled by (1 - Kd) every frame.
  const float k_over_m = settings_.oscillator.stiffness / settings_.oscillator.mass;
  const float keep = 1.0f - settings_.verlet_kd;
  for (std::size_t i = 0; i < size(); ++i) {
    const glm::vec3 p = positions_[i];
    const glm::vec3 a = -k_over_m * (p - rest_[i]) + (accel_end != nullptr ? accel_end[i] : glm::vec3(0.0f));
    positions_[i] = p + (p - previous_[i]) * keep + a * (dt * dt);
    previous_[i] = p;
    velocities_[i] = (positions_[i] - p) / dt;
  }
  last_dt_ = dt;
}

}  // namespace deform

namespace deform {

void ElasticLattice::prefetch() const noexcept {
  prefetch_span(positions_);
  prefetch_span(velocities_);
  prefetch_span(rest_);
  prefetch_span(pinned_);
  if (settings_.integrator == Integrator::verlet) prefetch_span(previous_);
  if (!springs_.empty()) {
    prefetch_span(springs_);
    prefetch_span(sub_positions_);
    prefetch_span(sub_velocities_);
    prefetch_span(forces_);
    prefetch_span(held_accel_);
  }
}

}  // namespace deform
