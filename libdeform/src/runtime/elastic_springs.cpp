// Neighbour springs between lattice control points (thesis §8.2.3 topology on the lattice grid) and the fixed
// sub-step integration they need.
#include <cmath>

#include "deform/runtime/elastic.hpp"
namespace deform {

std::vector<Spring> grid_springs(glm::ivec3 dims, const NeighbourSprings& springs) {
  std::vector<Spring> out;
  if (!springs.any() || dims.x < 1 || dims.y < 1 || dims.z < 1) return out;
  const auto index = [&](int i, int j, int k) { return std::uint32_t(i + dims.x * (j + dims.y * k)); };
  const auto inside = [&](int i, int j, int k) {
    return i >= 0 && j >= 0 && k >= 0 && i < dims.x && j < dims.y && k < dims.z;
  };
  // Each spring once: only offsets that are lexicographically positive.
  for (int di = -2; di <= 2; ++di) {
    for (int dj = -2; dj <= 2; ++dj) {
      for (int dk = -2; dk <= 2; ++dk) {
        const glm::ivec3 d(di, dj, dk);
        if (di < 0 || (di == 0 && (dj < 0 || (dj == 0 && dk <= 0)))) continue;
        const glm::ivec3 m = glm::abs(d);
        const int ones = (m.x == 1) + (m.y == 1) + (m.z == 1);
        const int twos = (m.x == 2) + (m.y == 2) + (m.z == 2);
        const bool structural = ones == 1 && twos == 0;
        const bool shear = ones >= 2 && twos == 0;
        const bool bend = ones == 0 && twos == 1;
        if (!((structural && springs.structural) || (shear && springs.shear) || (bend && springs.bend))) continue;
        for (int i = 0; i < dims.x; ++i) {
          for (int j = 0; j < dims.y; ++j) {
            for (int k = 0; k < dims.z; ++k) {
              if (inside(i + di, j + dj, k + dk)) out.push_back({index(i, j, k), index(i + di, j + dj, k + dk)});
            }
          }
        }
      }
    }
  }
  return out;
}

void ElasticLattice::substep(double h, std::span<glm::vec3> positions, std::span<glm::vec3> velocities) {
  // Spring forces from the current state, held constant over the sub-step; the anchor oscillator is then exact with
  // that constant force, whose effect is to shift the point's equilibrium by F / k.
  const NeighbourSprings& s = settings_.springs;
  std::fill(forces_.begin(), forces_.end(), glm::vec3(0.0f));
  for (const Spring& spring : springs_) {
    const glm::vec3 d = positions[spring.a] - positions[spring.b];
    const float length = glm::length(d);
    if (!(length > 1e-12f)) continue;
    const glm::vec3 dir = d / length;
    const float rest_length = glm::length(rest_[spring.a] - rest_[spring.b]);
    const float relative_speed = glm::dot(velocities[spring.a] - velocities[spring.b], dir);
    const glm::vec3 f = -(s.stiffness * (length - rest_length) + s.damping * relative_speed) * dir;
    forces_[spring.a] += f;
    forces_[spring.b] -= f;
  }
  const float mass = settings_.oscillator.mass;
  for (std::size_t i = 0; i < positions.size(); ++i) forces_[i] += mass * held_accel_[i];
  const OscillatorStep m =
      h == double(s.substep) ? cached_step(h, sub_cache_, sub_cache_dt_) : oscillator_step(settings_.oscillator, h);
  const float py = float(m.position_from_offset), pv = float(m.position_from_velocity);
  const float vy = float(m.velocity_from_offset), vv = float(m.velocity_from_velocity);
  const float inv_k = 1.0f / settings_.oscillator.stiffness;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const glm::vec3 equilibrium = rest_[i] + forces_[i] * inv_k;
    const glm::vec3 y = positions[i] - equilibrium;
    const glm::vec3 u = velocities[i];
    positions[i] = equilibrium + py * y + pv * u;
    velocities[i] = vy * y + vv * u;
  }
  if (!pinned_.empty()) {
    for (std::size_t i = 0; i < positions.size(); ++i) {
      if (pinned_[i]) positions[i] = rest_[i], velocities[i] = glm::vec3(0.0f);
    }
  }
}

void ElasticLattice::step_with_springs(double dt, const glm::vec3* accel_start, const glm::vec3* accel_end) {
  // Whole sub-steps advance the kept state; the reported state is that one advanced by the leftover time, so the
  // output is at exactly the caller's time while the kept state only ever moves by the fixed sub-step. An outside
  // acceleration is held at its mean over this call (first order, like the springs themselves).
  for (std::size_t i = 0; i < held_accel_.size(); ++i)
    held_accel_[i] = accel_start != nullptr ? 0.5f * (accel_start[i] + accel_end[i]) : glm::vec3(0.0f);
  const double h = settings_.springs.substep;
  double available = owed_ + dt;
  // A step longer than one second (a stall) takes its excess in one sub-step, so the cost per call stays bounded; the
  // anchor part is exact at any length, so that sub-step stays bounded too.
  constexpr double max_substepped = 1.0;
  if (available > max_substepped) {
    substep(available - max_substepped, sub_positions_, sub_velocities_);
    available = max_substepped;
  }
  while (available >= h) {
    substep(h, sub_positions_, sub_velocities_);
    available -= h;
  }
  owed_ = available;
  std::copy(sub_positions_.begin(), sub_positions_.end(), positions_.begin());
  std::copy(sub_velocities_.begin(), sub_velocities_.end(), velocities_.begin());
  if (owed_ > 0.0) substep(owed_, positions_, velocities_);
}

}  // namespace deform
