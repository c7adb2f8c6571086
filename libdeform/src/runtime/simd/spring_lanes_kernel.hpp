#pragma once
// Internal: the per-instruction-set entry points of SpringCrowdJob's lane kernel (spring_lanes_kernel.inl; see
// spring_chain.hpp and SpringChains::advance_together).
#include <algorithm>
#include <cstddef>

namespace deform::detail {

inline constexpr int spring_lanes = 8;          // SpringCrowdJob::max_group: one member a lane
inline constexpr int spring_collider_rows = 8;  // a collider in lanes: start xyz, axis xyz, 1 / |axis|², radius
inline constexpr int spring_state_rows = 9;     // a joint's kept state in lanes: position xyz, velocity xyz, rest xyz
inline constexpr int spring_end_rows = 12;      // an animated point's ends: start position, velocity, end position,
                                                // velocity (xyz each)
inline constexpr std::size_t spring_max_links = 32;     // the lanes' sizes (on the stack): a longer chain, or one
inline constexpr std::size_t spring_max_colliders = 8;  // with more colliders, runs one member at a time (substep())

// One chain of up to spring_lanes members over all of a step's whole sub-steps, its arrays row after row of
// spring_lanes floats. Lanes past the group's members repeat the first member.
struct SpringLanesArgs {
  std::size_t links;        // the chain's bones, at most spring_max_links
  std::size_t colliders;    // the chain's colliders, at most spring_max_colliders
  const float* ends;        // (links + 1) chain points, then each collider's two ends: spring_end_rows rows each
  const float* radii;       // per collider: its radius at the step's start, then at its end
  float* state;             // in/out: per joint spring_state_rows rows (SpringChains' positions_, velocities_, rests_)
  float* heads;             // in/out: 3 rows, the first head at the last sub-step (SpringChains' heads_)
  const float* gravity;     // 3 rows: the chain's gravity in model units (substep()'s)
  const float* radius;      // 1 row: the tails' collision radius (substep()'s)
  const float* maps;        // 6 rows: a whole sub-step's maps (py, pv, vy, vv, pg, vg: SpringChains::Oscillator)
  const float* stall_maps;  // 6 rows: the stall's sub-step's maps, read only when stall > 0
  double owed;              // the kept state's age at the step's start (SpringChains' owed_)
  double dt;                // the step, > 0
  double h;                 // the sub-step
  double stall;             // > 0: first a sub-step of this length (a stall's excess)
  std::size_t steps;        // then this many of h
  float* corrections;       // out, when not null: after the sub-steps, end_run()'s bend from the ends' end positions
                            // to the kept positions, 12 rows a joint (mat3 columns 0, 1, 2, then the translation)
};

// sample_points()' cubic Hermite at tau in [0, dt] as four weights: of the start position, the start velocity, the
// end position and the end velocity. One function for the scalar and the lane sampling, so that both round alike
// (static: each copy's translation unit its own, never another instruction set's).
static inline void spring_hermite_weights(double tau, double dt, float weights[4]) noexcept {
  const double s = dt > 0.0 ? std::clamp(tau / dt, 0.0, 1.0) : 1.0;
  const auto s2 = float(s * s), s3 = float(s * s * s), sf = float(s), h = float(dt);
  const float h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + sf, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
  weights[0] = h00, weights[1] = h10 * h, weights[2] = h01, weights[3] = h11 * h;
}

// One copy per instruction set, each compiled with its own flags: spring_lanes_portable.cpp (the baseline, SSE2 on
// x86-64) and spring_lanes_avx2.cpp (x86-64; one 8-lane register). No copy fuses a multiply and an add
// (-ffp-contract=off), so every copy gives the same bits as substep().
void spring_lanes_portable(const SpringLanesArgs& args) noexcept;
#if defined(DEFORM_X86_KERNELS)
void spring_lanes_avx2(const SpringLanesArgs& args) noexcept;
#endif

}  // namespace deform::detail
