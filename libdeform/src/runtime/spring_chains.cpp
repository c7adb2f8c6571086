// Spring chains: tails as damped oscillators in fixed sub-steps, their bones' lengths kept, colliders, and the bent
// pose written back into the world matrices.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <numbers>
#include <string>

#include "deform/runtime/elastic.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/portable.hpp"
#include "deform/runtime/prefetch.hpp"
#include "deform/runtime/spring_chain.hpp"
#include "finite.hpp"
#include "simd/spring_lanes_kernel.hpp"

namespace deform {
namespace {

glm::vec3 transform_point(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

float matrix_scale(const glm::mat4& m) { return std::cbrt(std::abs(glm::determinant(glm::mat3(m)))); }

// q / |q| by one square root and one division (glm::normalize divides each component: a sub-step's chain spent more
// time in divisions than in anything else).
DEFORM_ALWAYS_INLINE inline glm::quat unit(const glm::quat& q) noexcept {
  const float inverse = 1.0f / std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return glm::quat(q.w * inverse, q.x * inverse, q.y * inverse, q.z * inverse);
}

// The shortest rotation taking the direction of a to that of b, given norms = |a| |b|; identity when either is zero.
// Opposite directions turn half a turn about an axis perpendicular to a. Inlined: it is on each link's critical path,
// and as a call its vectors went through the stack both ways (the chain's sub-step took 1.4x as long).
DEFORM_ALWAYS_INLINE inline glm::quat shortest_arc(glm::vec3 a, glm::vec3 b, float norms) noexcept {
  if (!(norms > 0.0f)) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  const float w = norms + glm::dot(a, b);
  if (w <= 1e-6f * norms) {
    const glm::vec3 axis = std::abs(a.x) > std::abs(a.z) ? glm::vec3(-a.y, a.x, 0.0f) : glm::vec3(0.0f, -a.z, a.y);
    return unit(glm::quat(0.0f, axis.x, axis.y, axis.z));
  }
  const glm::vec3 c = glm::cross(a, b);
  return unit(glm::quat(w, c.x, c.y, c.z));
}

glm::quat shortest_arc(glm::vec3 a, glm::vec3 b) noexcept {
  return shortest_arc(a, b, std::sqrt(glm::dot(a, a) * glm::dot(b, b)));
}

void require(bool ok, const std::string& element, const char* what) {
  if (!ok) throw Error::invalid_argument(element, what);
}

constexpr int lane_count = detail::spring_lanes;
static_assert(std::size_t(lane_count) == SpringCrowdJob::max_group);
constexpr int state_rows = detail::spring_state_rows;
constexpr int end_rows = detail::spring_end_rows;
constexpr std::size_t max_lane_links = detail::spring_max_links;
constexpr std::size_t max_lane_colliders = detail::spring_max_colliders;

// The lane kernel's copy for `isa` (accepted by isa_available): automatic the widest here. All give the same bits.
void lanes_kernel(Isa isa, const detail::SpringLanesArgs& args) noexcept {
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::automatic) isa = isa_best();
  if (isa == Isa::avx2 || isa == Isa::avx512) return detail::spring_lanes_avx2(args);
#else
  (void)isa;
#endif
  detail::spring_lanes_portable(args);
}

}  // namespace

void require_valid_chain_settings(const SpringChainSpec& chain) {
  const std::string element = chain.name.empty() ? std::string("<spring chain>") : "spring chain '" + chain.name + "'";
  // Bounds far beyond any character, so that no product of them overflows a float.
  require(chain.frequency > 0.0f && chain.frequency <= 1000.0f, element, "frequency must be in (0, 1000] Hz");
  require(chain.damping_ratio >= 0.0f && chain.damping_ratio <= 1000.0f, element, "damping_ratio must be in [0, 1000]");
  require(finite(chain.gravity) && glm::length(chain.gravity) <= 1e6f, element,
          "gravity must be finite and at most 1e6 m/s²");
  require(chain.units_per_metre > 0.0f && chain.units_per_metre <= 1e6f, element,
          "units_per_metre must be in (0, 1e6]");
  require(chain.radius >= 0.0f && chain.radius <= 1e6f, element, "radius must be in [0, 1e6]");
  require(finite(chain.tip), element, "tip must be finite");
}

SpringChainSpec vrm_spring_settings(const VrmSpringJoint& joint, float bone_length, float frame_rate) {
  const std::string element = "<VRM spring joint>";
  require(std::isfinite(joint.stiffness) && joint.stiffness > 0.0f, element, "stiffness must be finite and > 0");
  require(joint.drag_force >= 0.0f && joint.drag_force < 1.0f, element, "dragForce must be in [0, 1)");
  require(std::isfinite(joint.gravity_power) && joint.gravity_power >= 0.0f, element,
          "gravityPower must be finite and >= 0");
  require(finite(joint.gravity_dir), element, "gravityDir must be finite");
  require(std::isfinite(joint.hit_radius) && joint.hit_radius >= 0.0f, element, "hitRadius must be finite and >= 0");
  require(std::isfinite(bone_length) && bone_length > 0.0f, element, "the bone length must be finite and > 0");
  require(std::isfinite(frame_rate) && frame_rate > 0.0f, element, "the frame rate must be finite and > 0");
  const double rate = frame_rate;
  const double omega = std::sqrt(double(joint.stiffness) * rate / double(bone_length));
  SpringChainSpec spec;
  spec.frequency = float(omega / (2.0 * std::numbers::pi));
  spec.damping_ratio = float(-std::log1p(-double(joint.drag_force)) * rate / (2.0 * omega));
  const float length = glm::length(joint.gravity_dir);
  spec.gravity =
      length > 0.0f ? joint.gravity_dir / length * float(double(joint.gravity_power) * rate) : glm::vec3(0.0f);
  spec.units_per_metre = 1.0f;
  spec.radius = joint.hit_radius;
  return spec;
}

SpringChains::SpringChains(const Skeleton& skeleton, std::vector<SpringChainSpec> chains,
                           std::vector<SpringCollider> colliders, float substep)
    : colliders_(std::move(colliders)), substep_(substep) {
  require(std::isfinite(substep) && substep > 0.0f && substep <= 1.0f, "<spring chains>",
          "substep must be in (0, 1] seconds");
  const std::size_t bones = skeleton.bone_count();
  const std::span<const Bone> bone_list = skeleton.bones();
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const SpringCollider& collider = colliders_[c];
    const std::string element = "collider " + std::to_string(c);
    require(collider.bone >= 0 && std::size_t(collider.bone) < bones, element, "bone is out of range");
    require(finite(collider.start) && finite(collider.end), element, "ends must be finite");
    require(collider.radius > 0.0f && collider.radius <= 1e6f, element, "radius must be in (0, 1e6]");
  }
  inverse_bind_.assign(skeleton.inverse_bind_world().begin(), skeleton.inverse_bind_world().end());
  std::vector<std::int32_t> joint_of(bones, -1);
  std::size_t joints = 0;
  for (std::size_t c = 0; c < chains.size(); ++c) {
    SpringChainSpec& spec = chains[c];
    require_valid_chain_settings(spec);
    const std::string element = "spring chain '" + spec.name + "'";
    for (std::size_t other = 0; other < c; ++other)
      require(chains[other].name != spec.name, element, "name is used by another chain");
    require(!spec.bones.empty(), element, "has no bones");
    for (std::size_t i = 0; i < spec.bones.size(); ++i) {
      const std::int32_t b = spec.bones[i];
      require(b >= 0 && std::size_t(b) < bones, element, "a bone is out of range");
      require(joint_of[std::size_t(b)] < 0, element, "a bone is in two chains");
      require(i == 0 || bone_list[std::size_t(b)].parent == spec.bones[i - 1], element,
              "bones are not a parent path (each bone the parent of the next)");
      joint_of[std::size_t(b)] = std::int32_t(joints + i);
    }
    for (std::uint32_t collider : spec.colliders)
      require(collider < colliders_.size(), element, "a collider index is out of range");
    Chain chain;
    chain.first = joints;
    chain.count = spec.bones.size();
    const auto last = std::size_t(spec.bones.back());
    chain.tip = spec.tip;
    if (chain.tip == glm::vec3(0.0f)) {
      const glm::mat4& bind = skeleton.bind_world()[last];
      std::int32_t child = -1;
      for (std::size_t b = 0; b < bones && child < 0; ++b)
        if (bone_list[b].parent == std::int32_t(last)) child = std::int32_t(b);
      if (child >= 0) {
        chain.tip = transform_point(inverse_bind_[last], glm::vec3(skeleton.bind_world()[std::size_t(child)][3]));
      } else if (const std::int32_t parent = bone_list[last].parent; parent >= 0) {
        const glm::vec3 offset = glm::vec3(bind[3]) - glm::vec3(skeleton.bind_world()[std::size_t(parent)][3]);
        chain.tip = glm::inverse(glm::mat3(bind)) * offset;
      }
      require(glm::dot(chain.tip, chain.tip) > 0.0f, element, "the last bone has no tip to guess: give one");
    }
    chain.root = spec.bones.front();
    chain.bind_scale = matrix_scale(skeleton.bind_world()[std::size_t(chain.root)]);
    chain.spec = std::move(spec);
    chain.fixed = oscillator(chain, substep_);
    joints += chain.count;
    chains_.push_back(std::move(chain));
  }
  // Who moves each bone: its own joint, else its parent's (the order visits parents first).
  governed_.assign(bones, -1);
  for (const std::int32_t b : skeleton.order()) {
    const std::int32_t parent = bone_list[std::size_t(b)].parent;
    governed_[std::size_t(b)] = joint_of[std::size_t(b)] >= 0 ? joint_of[std::size_t(b)]
                                : parent >= 0                 ? governed_[std::size_t(parent)]
                                                              : -1;
  }
  for (const Chain& chain : chains_) {
    const std::int32_t parent = bone_list[std::size_t(chain.spec.bones.front())].parent;
    require(parent < 0 || governed_[std::size_t(parent)] < 0, "spring chain '" + chain.spec.name + "'",
            "lies below another chain's bone (chains do not nest)");
  }
  // The points: per chain its first head, then each bone's tail (the next bone's head, the last bone's tip).
  for (const Chain& chain : chains_) {
    for (std::size_t i = 0; i < chain.count; ++i) {
      point_bone_.push_back(chain.spec.bones[i]);
      point_local_.push_back(glm::vec3(0.0f));
    }
    point_bone_.push_back(chain.spec.bones.back());
    point_local_.push_back(chain.tip);
  }
  // Then the colliders' ends, so that they move between frames as the chains' points do.
  collider_points_ = point_bone_.size();
  for (const SpringCollider& collider : colliders_) {
    point_bone_.insert(point_bone_.end(), 2, collider.bone);
    point_local_.push_back(collider.start);
    point_local_.push_back(collider.end);
  }
  const std::size_t points = point_bone_.size();
  for (auto* v : {&start_points_, &start_velocities_, &end_points_, &end_velocities_, &sample_points_, &drawn_})
    v->assign(points, glm::vec3(0.0f));
  for (auto* v : {&positions_, &velocities_, &rests_, &report_positions_, &report_velocities_, &report_rests_})
    v->assign(joints, glm::vec3(0.0f));
  corrections_.assign(joints, glm::mat4(1.0f));
  heads_.assign(chains_.size(), glm::vec3(0.0f));
  report_heads_ = heads_;
  collider_start_radius_.assign(colliders_.size(), 0.0f);
  collider_end_radius_ = collider_start_radius_;
  sample_colliders_.assign(colliders_.size(), Placed{});
}

void SpringChains::set_settings(std::size_t chain, const SpringChainSpec& settings) {
  if (chain >= chains_.size())
    throw Error::invalid_argument("spring chain " + std::to_string(chain), "spring chain index out of range");
  Chain& target = chains_[chain];
  SpringChainSpec checked = settings;
  checked.name = target.spec.name;
  checked.tip = target.spec.tip;
  require_valid_chain_settings(checked);
  target.spec.frequency = settings.frequency;
  target.spec.damping_ratio = settings.damping_ratio;
  target.spec.gravity = settings.gravity;
  target.spec.units_per_metre = settings.units_per_metre;
  target.spec.radius = settings.radius;
  target.fixed = oscillator(target, substep_);
}

std::span<const glm::vec3> SpringChains::points(std::size_t chain) const noexcept {
  const Chain& c = chains_[chain];
  return std::span<const glm::vec3>(drawn_).subspan(c.first + chain, c.count + 1);
}

SpringChains::Oscillator SpringChains::oscillator(const Chain& chain, double h) const noexcept {
  ElasticParams params;  // unit mass: only ω and ζ matter
  const double omega = 2.0 * std::numbers::pi * double(chain.spec.frequency);
  params.stiffness = float(omega * omega);
  params.damping_ratio = chain.spec.damping_ratio;
  const OscillatorStep m = oscillator_step(params, h);
  const ForcedStep f = forced_step(params, h);
  Oscillator o;
  o.py = float(m.position_from_offset);
  o.pv = float(m.position_from_velocity);
  o.vy = float(m.velocity_from_offset);
  o.vv = float(m.velocity_from_velocity);
  o.pg = float(f.position_from_start + f.position_from_end);
  o.vg = float(f.velocity_from_start + f.velocity_from_end);
  return o;
}

void SpringChains::place_at_rest(Chain& chain) noexcept {
  const std::size_t point0 = chain.first + std::size_t(&chain - chains_.data());
  for (std::size_t i = 0; i < chain.count; ++i) {
    positions_[chain.first + i] = rests_[chain.first + i] = end_points_[point0 + i + 1];
    velocities_[chain.first + i] = end_velocities_[point0 + i + 1];
  }
  heads_[std::size_t(&chain - chains_.data())] = end_points_[point0];
  chain.restart = false;
}

void SpringChains::sample_points(double tau, double dt) {
  // The cubic Hermite through the step's start and end (positions, velocities), at tau in [0, dt].
  float w[4];
  detail::spring_hermite_weights(tau, dt, w);
  for (std::size_t k = 0; k < sample_points_.size(); ++k) {
    const glm::vec3 p0 = start_points_[k], v0 = start_velocities_[k], p1 = end_points_[k], v1 = end_velocities_[k];
    sample_points_[k] = w[0] * p0 + w[1] * v0 + w[2] * p1 + w[3] * v1;
  }
}

void SpringChains::sample_colliders(float blend) {
  // The ends ride with the points (sample_points); the radius, which only the bone's scale changes, linearly.
  for (std::size_t c = 0; c < colliders_.size(); ++c) {
    const float start = collider_start_radius_[c], end = collider_end_radius_[c];
    const glm::vec3 from = sample_points_[collider_points_ + 2 * c], to = sample_points_[collider_points_ + 2 * c + 1];
    const float length2 = glm::dot(to - from, to - from);
    sample_colliders_[c] = {from, to - from, length2 > 0.0f ? 1.0f / length2 : 0.0f, start + (end - start) * blend};
  }
}

void SpringChains::substep(const Chain& chain, const Oscillator& m, float h, glm::vec3* positions,
                           glm::vec3* velocities, glm::vec3* rests, glm::vec3* heads) const noexcept {
  // Root to tip: each tail's rest is its head (the parent's simulated tail) plus its animated bone vector turned by
  // the rotation the chain above has been bent by; the rest moves linearly over the sub-step, which the oscillator
  // step follows exactly; then the colliders and the bone's length.
  const std::size_t index = std::size_t(&chain - chains_.data());
  const std::size_t point0 = chain.first + index;
  glm::vec3 head = sample_points_[point0];
  // The first head's velocity over the sub-step, as the rests' (linear over it): from its positions only, which a
  // frame's cubic gives to O(h⁴). The cubic's own derivative carries the caller's rate, whose error (a forward
  // difference over a lead of a millisecond is off by half the lead times the acceleration) differs between a
  // frame's ends and its inside: sub-steps inside frames and sub-steps on frames would part by it.
  glm::vec3 head_velocity = (head - heads[index]) * (1.0f / h);
  heads[index] = head;
  glm::quat bend(1.0f, 0.0f, 0.0f, 0.0f);
  const glm::vec3 gravity = chain.spec.gravity * (chain.spec.units_per_metre * chain.scale);
  const float radius = chain.spec.radius * chain.scale;
  const float inverse_h = 1.0f / h;
  for (std::size_t i = 0; i < chain.count; ++i) {
    const std::size_t j = chain.first + i;
    // The length from the animated bone before it is turned: the same to rounding, and off the chain's critical path
    // (each link waits on the bend above it; the sub-step was bound by that chain of square roots and divisions).
    const glm::vec3 animated = sample_points_[point0 + i + 1] - sample_points_[point0 + i];
    const float length = glm::length(animated);
    const glm::vec3 bone = bend * animated;
    const glm::vec3 rest = head + bone;
    const glm::vec3 rest_velocity = (rest - rests[j]) * inverse_h;
    const glm::vec3 y = positions[j] - rests[j];
    const glm::vec3 u = velocities[j] - rest_velocity;
    glm::vec3 p = rest + m.py * y + m.pv * u + m.pg * gravity;
    glm::vec3 v = rest_velocity + m.vy * y + m.vv * u + m.vg * gravity;
    // Out of the colliders, then back to the bone's length; the length may lead back in, so a few rounds (a tail
    // caught between a collider and its length settles on the circle where both hold).
    const auto keep_length = [&] {
      const glm::vec3 from_head = p - head;
      const float distance = glm::length(from_head);
      const glm::vec3 along = distance > 1e-12f * length ? from_head * (1.0f / distance)
                              : length > 0.0f            ? bone * (1.0f / length)
                                                         : bone;
      p = head + along * length;
      v -= glm::dot(v - head_velocity, along) * along;
    };
    keep_length();
    for (int round = 0; round < 4; ++round) {
      bool pushed = false;
      for (const std::uint32_t c : chain.spec.colliders) {
        // The capsule's nearest point; most tails are outside every capsule, decided without a square root.
        const Placed& collider = sample_colliders_[c];
        const float t = std::clamp(glm::dot(p - collider.start, collider.axis) * collider.inverse_length2, 0.0f, 1.0f);
        const glm::vec3 nearest = collider.start + collider.axis * t;
        const glm::vec3 out = p - nearest;
        const float reach = collider.radius + radius;
        const float distance2 = glm::dot(out, out);
        if (distance2 >= reach * reach) continue;
        const float distance = std::sqrt(distance2);
        const glm::vec3 normal =
            distance > 1e-12f * reach ? out * (1.0f / distance) : glm::normalize(rest - nearest + 1e-30f);
        p = nearest + normal * reach;
        const float inward = glm::dot(v, normal);
        if (inward < 0.0f) v -= inward * normal;
        pushed = true;
      }
      if (!pushed) break;
      keep_length();
    }
    positions[j] = p;
    velocities[j] = v;
    rests[j] = rest;
    bend = shortest_arc(bone, p - head, length * length) * bend;  // keep_length left |p - head| = length
    head = p;
    head_velocity = v;
  }
}

bool SpringChains::same_layout(const SpringChains& other) const noexcept {
  if (other.substep_ != substep_ || other.chains_.size() != chains_.size() ||
      other.colliders_.size() != colliders_.size() || other.governed_.size() != governed_.size() ||
      other.point_bone_.size() != point_bone_.size())
    return false;
  for (std::size_t c = 0; c < chains_.size(); ++c)
    if (other.chains_[c].count != chains_[c].count || other.chains_[c].spec.colliders != chains_[c].spec.colliders)
      return false;
  return true;
}

void SpringChains::advance(double dt) noexcept {
  SpringChains* self = this;
  advance_together(&self, 1, dt);
}

void SpringChains::advance_together(SpringChains* const* group, std::size_t count, double dt, Isa isa) noexcept {
  // Whole sub-steps from the kept state's time (owed_ before this step's start) to the last one within the step,
  // then the leftover from a copy: the kept state only ever moves by the fixed sub-step. The group shares owed_,
  // the sub-step and the chains' shapes (same_layout), so one count of sub-steps serves all. Chains do not act on one
  // another (each reads only the animated points, the colliders and its own state), so a group runs chain after chain,
  // each through all the step's sub-steps: the chain's state and its animated points' ends are put in lanes once a
  // step, stay there over its sub-steps and are written back at the end — the members' arithmetic untouched.
  const SpringChains& first = *group[0];
  const double h = first.substep_;
  double available = first.owed_ + dt;
  constexpr double max_substepped = 1.0;  // a longer stall takes its excess in one sub-step
  // The lengths of the whole sub-steps: a stall's excess first, then `steps` of h (counted first so that rounding in
  // `available` cannot drop or add one).
  const double stall = available > max_substepped ? available - max_substepped : 0.0;
  if (stall > 0.0) available = max_substepped;
  const auto steps = std::size_t(std::floor(available / h + 1e-9));
  // The kept state's age after the step; when no leftover is owed the reported state is the kept one, and the lanes
  // also give end_run()'s bend (Chain::bent).
  const double owed_after = std::max(0.0, available - double(steps) * h);
  const bool bend_in_lanes = !(owed_after > 1e-12);
  const auto lanes_for = [&](const Chain& chain) {
    return count > 1 && chain.count <= max_lane_links && chain.spec.colliders.size() <= max_lane_colliders;
  };
  bool any_alone = false;  // a chain that runs one member at a time (count 1, or beyond the lanes' sizes)
  for (const Chain& chain : first.chains_) any_alone = any_alone || !lanes_for(chain);
  if (any_alone) {
    double kept = -first.owed_;  // the kept state's time relative to this step's start
    const auto whole = [&](double length) {
      kept += length;
      for (std::size_t g = 0; g < count; ++g) {
        group[g]->sample_points(kept, dt);
        group[g]->sample_colliders(dt > 0.0 ? float(std::clamp(kept / dt, 0.0, 1.0)) : 1.0f);
      }
      for (std::size_t c = 0; c < first.chains_.size(); ++c) {
        if (lanes_for(first.chains_[c])) continue;
        for (std::size_t g = 0; g < count; ++g) {
          SpringChains& s = *group[g];
          const Chain& chain = s.chains_[c];
          s.substep(chain, length == h ? chain.fixed : s.oscillator(chain, length), float(length), s.positions_.data(),
                    s.velocities_.data(), s.rests_.data(), s.heads_.data());
        }
      }
    };
    if (stall > 0.0) whole(stall);
    for (std::size_t n = 0; n < steps; ++n) whole(h);
  }
  for (std::size_t c = 0; c < first.chains_.size(); ++c) {
    if (!lanes_for(first.chains_[c])) continue;
    const Chain& shape = first.chains_[c];
    const std::size_t point0 = shape.first + c;
    const std::vector<std::uint32_t>& used = shape.spec.colliders;
    // In lanes for the step (lanes past `count` repeat the first member and are not written back): the animated
    // points' ends (the chain's, then its colliders' two each), the kept state, the first head at the last sub-step.
    alignas(32) float ends[(max_lane_links + 1 + 2 * max_lane_colliders) * end_rows * lane_count];
    alignas(32) float state[max_lane_links * state_rows * lane_count];
    alignas(32) float radii[max_lane_colliders * 2 * lane_count];  // per collider: its radius at the start, at the end
    alignas(32) float heads[3 * lane_count];
    alignas(32) float gravity[3 * lane_count], radius[lane_count], maps[6 * lane_count], stall_maps[6 * lane_count];
    alignas(32) float corrections[max_lane_links * 12 * lane_count];  // end_run()'s bend: mat3 and translation
    const std::size_t chain_points = shape.count + 1;
    for (int k = 0; k < lane_count; ++k) {
      const SpringChains& s = *group[std::size_t(k) < count ? std::size_t(k) : 0];
      const Chain& chain = s.chains_[c];
      // Plain stores of each float (a copy through a small array on the stack cost as much as the sub-steps).
      const auto put = [&](float* at, const glm::vec3& v) {
        at[0] = v.x, at[lane_count] = v.y, at[2 * lane_count] = v.z;
      };
      const auto put_ends = [&](std::size_t row, std::size_t point) {
        float* at = ends + row * end_rows * lane_count + k;
        put(at, s.start_points_[point]);
        put(at + 3 * lane_count, s.start_velocities_[point]);
        put(at + 6 * lane_count, s.end_points_[point]);
        put(at + 9 * lane_count, s.end_velocities_[point]);
      };
      for (std::size_t i = 0; i < chain_points; ++i) put_ends(i, point0 + i);
      for (std::size_t n = 0; n < used.size(); ++n) {
        put_ends(chain_points + 2 * n, s.collider_points_ + 2 * used[n]);
        put_ends(chain_points + 2 * n + 1, s.collider_points_ + 2 * used[n] + 1);
        radii[2 * n * lane_count + k] = s.collider_start_radius_[used[n]];
        radii[(2 * n + 1) * lane_count + k] = s.collider_end_radius_[used[n]];
      }
      for (std::size_t i = 0; i < shape.count; ++i) {
        float* at = state + i * state_rows * lane_count + k;
        put(at, s.positions_[shape.first + i]);
        put(at + 3 * lane_count, s.velocities_[shape.first + i]);
        put(at + 6 * lane_count, s.rests_[shape.first + i]);
      }
      heads[k] = s.heads_[c].x, heads[lane_count + k] = s.heads_[c].y, heads[2 * lane_count + k] = s.heads_[c].z;
      // substep()'s gravity and radius, the same over the step; the maps of a whole sub-step and of a stall's.
      const glm::vec3 g = chain.spec.gravity * (chain.spec.units_per_metre * chain.scale);
      gravity[k] = g.x, gravity[lane_count + k] = g.y, gravity[2 * lane_count + k] = g.z;
      radius[k] = chain.spec.radius * chain.scale;
      const auto put_maps = [&](float* rows, const Oscillator& m) {
        rows[k] = m.py, rows[lane_count + k] = m.pv, rows[2 * lane_count + k] = m.vy;
        rows[3 * lane_count + k] = m.vv, rows[4 * lane_count + k] = m.pg, rows[5 * lane_count + k] = m.vg;
      };
      put_maps(maps, chain.fixed);
      if (stall > 0.0) put_maps(stall_maps, stall == h ? chain.fixed : s.oscillator(chain, stall));
    }
    detail::SpringLanesArgs args{};
    args.links = shape.count;
    args.colliders = used.size();
    args.ends = ends;
    args.radii = radii;
    args.state = state;
    args.heads = heads;
    args.gravity = gravity;
    args.radius = radius;
    args.maps = maps;
    args.stall_maps = stall_maps;
    args.owed = first.owed_;
    args.dt = dt;
    args.h = h;
    args.stall = stall;
    args.steps = steps;
    args.corrections = bend_in_lanes ? corrections : nullptr;
    lanes_kernel(isa, args);
    for (std::size_t g = 0; g < count; ++g) {
      SpringChains& s = *group[g];
      const auto k = int(g);
      for (std::size_t i = 0; i < shape.count; ++i) {
        const float* at = state + i * state_rows * lane_count + k;
        s.positions_[shape.first + i] = glm::vec3(at[0], at[lane_count], at[2 * lane_count]);
        s.velocities_[shape.first + i] = glm::vec3(at[3 * lane_count], at[4 * lane_count], at[5 * lane_count]);
        s.rests_[shape.first + i] = glm::vec3(at[6 * lane_count], at[7 * lane_count], at[8 * lane_count]);
      }
      s.heads_[c] = glm::vec3(heads[k], heads[lane_count + k], heads[2 * lane_count + k]);
      if (!bend_in_lanes) continue;
      for (std::size_t i = 0; i < shape.count; ++i) {
        const float* at = corrections + i * 12 * lane_count + k;
        glm::mat4& correction = s.corrections_[shape.first + i];
        correction[0] = glm::vec4(at[0], at[lane_count], at[2 * lane_count], 0.0f);
        correction[1] = glm::vec4(at[3 * lane_count], at[4 * lane_count], at[5 * lane_count], 0.0f);
        correction[2] = glm::vec4(at[6 * lane_count], at[7 * lane_count], at[8 * lane_count], 0.0f);
        correction[3] = glm::vec4(at[9 * lane_count], at[10 * lane_count], at[11 * lane_count], 1.0f);
      }
      s.chains_[c].bent = true;
    }
  }
  for (std::size_t g = 0; g < count; ++g) {
    SpringChains& s = *group[g];
    s.owed_ = owed_after;
    // With no leftover the reported state is the kept one (reported_kept_: nothing copied); else a copy advanced by it.
    s.reported_kept_ = !(s.owed_ > 1e-12);
    if (!s.reported_kept_) {
      s.report_positions_ = s.positions_;
      s.report_velocities_ = s.velocities_;
      s.report_rests_ = s.rests_;
      s.report_heads_ = s.heads_;
      s.sample_points(dt, dt);
      s.sample_colliders(1.0f);
      for (const Chain& chain : s.chains_) {
        s.substep(chain, s.oscillator(chain, s.owed_), float(s.owed_), s.report_positions_.data(),
                  s.report_velocities_.data(), s.report_rests_.data(), s.report_heads_.data());
      }
    }
  }
}

Status SpringChains::check(float dt, std::size_t world, std::size_t world_rate, std::size_t palette) const noexcept {
  if (!(dt >= 0.0f) || !std::isfinite(dt)) return Status::failure("dt is negative or not finite");
  const std::size_t bones = governed_.size();
  if (world != bones) return Status::failure("world does not have one entry per bone");
  if (world_rate != 0 && world_rate != bones) return Status::failure("world_rate is neither empty nor one per bone");
  if (palette != 0 && palette != bones) return Status::failure("palette is neither empty nor one per bone");
  return {};
}

Status SpringChains::run(float dt, std::span<glm::mat4> world, std::span<const glm::mat4> world_rate,
                         std::span<glm::mat4> palette) {
  if (Status status = check(dt, world.size(), world_rate.size(), palette.size()); !status) return status;
  if (chains_.empty()) return {};
  if (begin_run(dt, world, world_rate)) advance(double(dt));
  end_run(world, palette);
  return {};
}

bool SpringChains::begin_run(float dt, std::span<const glm::mat4> world,
                             std::span<const glm::mat4> world_rate) noexcept {
  // Hints for the state the advance reads and writes next (cold in a crowd by now), issued before the pose is read.
  for (const auto* points : {&start_points_, &start_velocities_, &positions_, &velocities_, &rests_})
    prefetch_span(*points);
  prefetch_span(corrections_);
  // The animated points and colliders at the end of the step.
  for (std::size_t k = 0; k < point_bone_.size(); ++k) {
    const auto b = std::size_t(point_bone_[k]);
    end_points_[k] = transform_point(world[b], point_local_[k]);
    if (!world_rate.empty()) {
      end_velocities_[k] = glm::vec3(world_rate[b] * glm::vec4(point_local_[k], 1.0f));
    } else {  // moving linearly over the step
      end_velocities_[k] = started_ && dt > 0.0f ? (end_points_[k] - start_points_[k]) / dt : glm::vec3(0.0f);
      start_velocities_[k] = end_velocities_[k];
    }
  }
  for (std::size_t c = 0; c < colliders_.size(); ++c)
    collider_end_radius_[c] = colliders_[c].radius * matrix_scale(world[std::size_t(colliders_[c].bone)]);
  for (Chain& chain : chains_) chain.scale = matrix_scale(world[std::size_t(chain.root)]) / chain.bind_scale;
  // A pose that changed while no time passed is a jump (a cut, a teleport): the chains start again on it, at rest.
  if (started_ && dt == 0.0f) started_ = std::equal(end_points_.begin(), end_points_.end(), start_points_.begin());
  if (!started_) {
    start_points_ = end_points_;
    start_velocities_ = end_velocities_;
    collider_start_radius_ = collider_end_radius_;
    for (Chain& chain : chains_) place_at_rest(chain);
    reported_kept_ = true;
    owed_ = 0.0;
    started_ = true;
  } else {
    for (Chain& chain : chains_) {
      if (!chain.restart) continue;
      const std::size_t point0 = chain.first + std::size_t(&chain - chains_.data());
      for (std::size_t k = point0; k <= point0 + chain.count; ++k) {
        start_points_[k] = end_points_[k];
        start_velocities_[k] = end_velocities_[k];
      }
      place_at_rest(chain);
      if (reported_kept_) continue;
      for (std::size_t j = chain.first; j < chain.first + chain.count; ++j) {
        report_positions_[j] = positions_[j];
        report_velocities_[j] = velocities_[j];
        report_rests_[j] = rests_[j];
      }
    }
    return dt > 0.0f;
  }
  return false;
}

void SpringChains::end_run(std::span<glm::mat4> world, std::span<glm::mat4> palette) noexcept {
  // The bent pose: per joint the rigid map taking its animated bone onto its simulated one.
  const std::vector<glm::vec3>& report_positions = reported_kept_ ? positions_ : report_positions_;
  for (Chain& chain : chains_) {
    const std::size_t point0 = chain.first + std::size_t(&chain - chains_.data());
    glm::vec3 head = end_points_[point0];
    drawn_[point0] = head;
    if (chain.bent) {  // SpringCrowdJob's lanes computed the corrections below, bit for bit
      for (std::size_t i = 0; i < chain.count; ++i) drawn_[point0 + i + 1] = report_positions[chain.first + i];
      chain.bent = false;
      continue;
    }
    glm::quat bend(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::size_t i = 0; i < chain.count; ++i) {
      const std::size_t j = chain.first + i;
      const glm::vec3 animated_head = end_points_[point0 + i];
      const glm::vec3 bone = bend * (end_points_[point0 + i + 1] - animated_head);
      bend = shortest_arc(bone, report_positions[j] - head) * bend;
      glm::mat4 correction = glm::mat4_cast(bend);
      correction[3] = glm::vec4(head - glm::mat3(correction) * animated_head, 1.0f);
      corrections_[j] = correction;
      head = report_positions[j];
      drawn_[point0 + i + 1] = head;
    }
  }
  for (std::size_t b = 0; b < governed_.size(); ++b) {
    const std::int32_t joint = governed_[b];
    if (joint < 0) continue;
    world[b] = corrections_[std::size_t(joint)] * world[b];
    if (!palette.empty()) palette[b] = world[b] * inverse_bind_[b];
  }
  // The end becomes the next step's start; begin_run() rewrites every end value before reading one: swapped, not
  // copied.
  start_points_.swap(end_points_);
  start_velocities_.swap(end_velocities_);
  collider_start_radius_.swap(collider_end_radius_);
}

Status SpringCrowdJob::check(std::size_t begin, std::size_t end) const noexcept {
  const SpringCrowdJob& job = *this;
  if (job.group < 1 || job.group > SpringCrowdJob::max_group) return Status::failure("group is not in [1, 8]");
  if (!isa_available(job.isa)) return Status::failure("instruction set not available");
  if (job.instances.empty())
    return (job.world.empty() && job.world_rate.empty() && job.palette.empty())
               ? Status()
               : Status::failure("world, world_rate or palette given for no instances");
  const SpringChains& first = job.instances[0];
  const std::size_t bones = first.governed_.size();
  if (job.world.size() != bones * job.instances.size())
    return Status::failure("world does not have one entry per bone per instance");
  if (!job.world_rate.empty() && job.world_rate.size() != job.world.size())
    return Status::failure("world_rate is neither empty nor one per bone per instance");
  if (!job.palette.empty() && job.palette.size() != job.world.size())
    return Status::failure("palette is neither empty nor one per bone per instance");
  if (Status status = first.check(job.dt, bones, 0, 0); !status) return status;
  for (std::size_t i = begin; i < end; ++i)
    if (!first.same_layout(job.instances[i]))
      return Status::failure("an instance's chains are laid out unlike the first's");
  return {};
}

Status SpringCrowdJob::validate() const noexcept { return check(0, instances.size()); }

Status SpringCrowdJob::run() const noexcept { return run(0, instances.size()); }

Status SpringCrowdJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (begin > end || end > instances.size()) return Status::failure("range out of bounds");
  if (Status status = check(begin, end); !status) return status;
  if (begin == end || instances[0].chains_.empty()) return {};
  const std::size_t bones = instances[0].governed_.size();
  const auto span_of = [&](auto matrices, std::size_t i) {
    return matrices.empty() ? matrices : matrices.subspan(i * bones, bones);
  };
  for (std::size_t from = begin; from < end; from += group) {
    const std::size_t to = std::min(end, from + group);
    SpringChains* advancing[max_group];
    std::size_t count = 0;
    for (std::size_t i = from; i < to; ++i)
      if (instances[i].begin_run(dt, span_of(world, i), span_of(world_rate, i))) advancing[count++] = &instances[i];
    // Together the instances whose kept state is as old (the usual case: all of them); the others in later rounds.
    while (count > 0) {
      SpringChains* together[max_group];
      std::size_t together_count = 0, left = 0;
      const double owed = advancing[0]->owed_;
      for (std::size_t k = 0; k < count; ++k) {
        if (advancing[k]->owed_ == owed) {
          together[together_count++] = advancing[k];
        } else {
          advancing[left++] = advancing[k];
        }
      }
      SpringChains::advance_together(together, together_count, double(dt), isa);
      count = left;
    }
    for (std::size_t i = from; i < to; ++i) instances[i].end_run(span_of(world, i), span_of(palette, i));
  }
  return {};
}

}  // namespace deform

namespace deform {

void SpringChains::prefetch() const noexcept {
  prefetch_span(chains_);
  prefetch_span(colliders_);
  prefetch_span(point_bone_);
  prefetch_span(point_local_);
  prefetch_span(governed_);
  prefetch_span(inverse_bind_);
  for (const auto* points :
       {&start_points_, &start_velocities_, &end_points_, &end_velocities_, &sample_points_, &positions_, &velocities_,
        &rests_, &report_positions_, &report_velocities_, &report_rests_, &heads_, &drawn_})
    prefetch_span(*points);
  prefetch_span(collider_start_radius_);
  prefetch_span(collider_end_radius_);
  prefetch_span(sample_colliders_);
  prefetch_span(corrections_);
}

}  // namespace deform
