#pragma once
// Spring chains: secondary motion for tails, hair, ears, cloth strips and bellies — bones that trail behind the
// animated pose, overshoot and settle, pulled by gravity and kept out of the body by colliders. docs/elasticity.md,
// "Spring chains".
//
// Each bone of a chain ends in a tail (the next bone's head; the last bone's `tip`) that is a damped oscillator in
// world space: pulled toward where the animated pose puts it — relative to the chain as simulated so far, so a bend
// near the root carries the rest of the chain — with a natural frequency in Hz and a damping ratio, pushed by
// gravity, then kept at its bone's length from its head and out of the colliders. The chain's first head stays
// where the animation puts it. The simulated chain then rotates each chain bone (shortest arc from its animated
// direction to its simulated one, no twist added) and carries every bone below it rigidly.
//
// The same at any frame rate: the state advances in fixed sub-steps (`substep`, 1/240 s by default) whatever the
// caller's frame time, each sub-step the exact flow of the oscillators toward a rest moving linearly over it; the
// caller's frame only decides where the animated pose is sampled, and between frames the animated points move along
// the cubic through their positions and velocities (world_rate given) or linearly (not given). Output is reported
// at exactly the caller's time (the kept state advanced by the leftover time, not committed).
// The same at any scale: frequency and damping ratio have no length in them; gravity (m/s²) and the tails' collision
// radius are scaled by the scale of the chain's first bone relative to the bind pose, and colliders are placed by
// their bones' matrices, scale included — a character scaled by 0.01 or 100 moves the same way, scaled.
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <span>
#include <string>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// A sphere (start == end) or a capsule (the segment start–end swept by the radius) moving with a bone.
struct SpringCollider {
  std::int32_t bone = -1;  // moves with this bone's animated world matrix
  glm::vec3 start{0.0f};   // bone-local (bind units): a sphere's centre, a capsule's first end
  glm::vec3 end{0.0f};     // bone-local: a capsule's second end
  float radius = 0.0f;     // bone-local units, in (0, 1e6]
  bool operator==(const SpringCollider&) const = default;
};

// One chain of spring bones.
struct SpringChainSpec {
  std::string name;                      // unique among the chains
  std::vector<std::int32_t> bones;       // root first, each bone the parent of the next; at least one
  glm::vec3 tip{0.0f};                   // the last bone's tail in its local frame; zero: its first child's bind head,
                                         // else its own offset from its parent continued
  float frequency = 2.0f;                // Hz, in (0, 1000]: each tail's natural frequency toward the animated pose
  float damping_ratio = 0.3f;            // in [0, 1000]: < 1 overshoots and settles, 1 returns without overshoot
  glm::vec3 gravity{0.0f};               // m/s², model space, e.g. {0, -9.81, 0} for a +Y-up model; at most 1e6 long
  float units_per_metre = 1.0f;          // model units in a metre (100 for centimetres), in (0, 1e6]
  float radius = 0.0f;                   // each tail's collision radius, model units at bind scale, in [0, 1e6]
  std::vector<std::uint32_t> colliders;  // indices into the colliders the chains share
  bool operator==(const SpringChainSpec&) const = default;
};

// Throws deform::Error ("<spring chain>" or the chain's name, naming the field) when a setting is not finite or out
// of its range. The bones and colliders are checked against a skeleton by SpringChains' constructor.
DEFORM_RUNTIME_API void require_valid_chain_settings(const SpringChainSpec& chain);

// A joint's parameters in VRMC_springBone (VRM 1.0), as a .vrm file gives them. VRM moves a tail every frame by
//   next = tail + (tail - previous)·(1 - dragForce) + restDirection·stiffness·Δt + gravityDir·gravityPower·Δt,
// then back to the bone's length: per-frame factors, so its motion changes with the frame rate.
struct VrmSpringJoint {
  float stiffness = 1.0f;                    // stiffness, >= 0
  float drag_force = 0.4f;                   // dragForce, in [0, 1)
  float gravity_power = 0.0f;                // gravityPower, >= 0
  glm::vec3 gravity_dir{0.0f, -1.0f, 0.0f};  // gravityDir
  float hit_radius = 0.0f;                   // hitRadius, metres, >= 0
};

// The chain settings (frequency, damping ratio, gravity, radius; units_per_metre 1: VRM is in metres) that move as
// VRM moves a joint of `bone_length` metres when VRM runs at `frame_rate` frames per second — where the model was
// tuned, usually 60. Linearised about the rest direction (docs/elasticity.md, "From VRM"): the stiffness term turns
// the tail by stiffness·Δt/L per frame, so ω² = stiffness·rate/L; (1 - dragForce) of the velocity kept per frame
// is a damping of -ln(1 - dragForce)·rate per second, so ζ = -ln(1 - dragForce)·rate/(2ω); gravityPower·Δt per
// frame is an acceleration gravityPower·rate. Throws deform::Error naming the parameter when one is out of its range
// (a stiffness of 0 has no frequency: refused).
DEFORM_RUNTIME_API SpringChainSpec vrm_spring_settings(const VrmSpringJoint& joint, float bone_length,
                                                       float frame_rate = 60.0f);

// The spring chains of one skeleton and their state. Construction allocates; run() does not.
class DEFORM_RUNTIME_API SpringChains {
 public:
  static constexpr float default_substep = 1.0f / 240.0f;

  SpringChains() = default;
  // Throws deform::Error naming the chain or collider for a bone out of range, a chain whose bones are not a parent
  // path, a bone in two chains, a chain below another chain's bone (chains do not nest), a leaf root with no tip to
  // guess, a collider index out of range, a setting out of range (require_valid_chain_settings) or a substep outside
  // (0, 1] s.
  SpringChains(const Skeleton& skeleton, std::vector<SpringChainSpec> chains, std::vector<SpringCollider> colliders,
               float substep = default_substep);

  // Advances the chains by dt seconds and bends the pose: `world` holds the animated world matrices at the end of
  // the step (LocalToWorldJob's, one per bone) and receives the simulated ones for every chain bone and bone below
  // one; `palette`, when not empty, is rewritten for those bones (world · inverse bind). `world_rate`, when not
  // empty, is d(world)/dt per bone at the end of the step (see DeformerHierarchy::step). The first run after
  // construction or reset(), and a run with dt = 0 whose pose moved the chains (a cut, a teleport), start the chains
  // on the animated pose, at rest. Refuses, changing nothing, a dt that is
  // negative or not finite, or spans of the wrong size. No allocation, no exceptions; O(sub-steps × (tails +
  // tail-collider pairs) + bones).
  Status run(float dt, std::span<glm::mat4> world, std::span<const glm::mat4> world_rate = {},
             std::span<glm::mat4> palette = {});
  // The next run() starts on the animated pose, at rest (after a teleport, say).
  void reset() noexcept { started_ = false; }
  // The next run() starts this chain again on its animated pose, at rest; the others go on (a limb that jumped: a
  // reach that starts or ends). Refuses a chain index out of range. No allocation.
  Status restart(std::size_t chain) noexcept {
    if (chain >= chains_.size()) return Status::failure("spring chain index out of range");
    chains_[chain].restart = true;
    return {};
  }

  // Cache hints for the state the next run() reads and writes (deform/runtime/prefetch.hpp): no effect on it.
  void prefetch() const noexcept;

  std::size_t chain_count() const noexcept { return chains_.size(); }
  // Read accessors taking a chain index never throw: they require chain < chain_count(), as
  // std::vector::operator[] does (the sanitizer build checks it, with _GLIBCXX_ASSERTIONS).
  const SpringChainSpec& spec(std::size_t chain) const noexcept { return chains_[chain].spec; }
  std::span<const SpringCollider> colliders() const noexcept { return colliders_; }
  float substep() const noexcept { return substep_; }
  // Changes a chain's frequency, damping, gravity, units and radius (its bones, tip and colliders stay), keeping the
  // state. Throws deform::Error when invalid or the index is out of range.
  void set_settings(std::size_t chain, const SpringChainSpec& settings);
  // As of the last run(): the chain's first head and its tails, world space (bones + 1 points, for drawing).
  std::span<const glm::vec3> points(std::size_t chain) const noexcept;

 private:
  struct Oscillator {                      // one sub-step's maps (double-computed, stored as float)
    float py = 1, pv = 0, vy = 0, vv = 1;  // oscillator_step
    float pg = 0, vg = 0;                  // forced_step for a constant acceleration
  };
  struct Chain {
    SpringChainSpec spec;
    Oscillator fixed;         // the maps of one whole sub-step
    std::size_t first = 0;    // its first joint in the flat arrays (one per bone); its points start at first + index
    std::size_t count = 0;    // bones
    std::int32_t root = 0;    // spec.bones.front(), kept here: begin_run() reads it per run
    glm::vec3 tip{0.0f};      // the last bone's tail, bone-local
    float bind_scale = 1.0f;  // the first bone's scale in the bind pose
    float scale = 1.0f;       // ... and as of the last run
    bool restart = false;     // restart(): at rest on the animated pose at the next run
    bool bent = false;        // advance_together() wrote this step's corrections_ in lanes: end_run() takes them
  };
  struct Placed {  // a collider in world space
    glm::vec3 start{0.0f};
    glm::vec3 axis{0.0f};          // end - start
    float inverse_length2 = 0.0f;  // 1 / |axis|², 0 for a sphere (start = end)
    float radius = 0.0f;
  };
  friend struct SpringCrowdJob;
  Oscillator oscillator(const Chain& chain, double h) const noexcept;
  void sample_points(double tau, double dt);
  void sample_colliders(float blend);
  void substep(const Chain& chain, const Oscillator& m, float h, glm::vec3* positions, glm::vec3* velocities,
               glm::vec3* rests, glm::vec3* heads) const noexcept;
  // advance() for `count` members of one layout (same_layout) whose kept state is as old (owed_), their sub-steps in
  // lanes (links_lanes in spring_chains.cpp): each chain's links wait on one another, the members do not. Chain by
  // chain, its state and animated points put in lanes once for all the step's sub-steps and written back after them.
  // The same bits as one by one.
  static void advance_together(SpringChains* const* group, std::size_t count, double dt,
                               Isa isa = Isa::automatic) noexcept;
  void advance(double dt) noexcept;
  bool same_layout(const SpringChains& other) const noexcept;
  Status check(float dt, std::size_t world, std::size_t world_rate, std::size_t palette) const noexcept;
  // run() in three parts: the animated pose read (true when the chains are to advance by dt), the advance, and the
  // bent pose written.
  bool begin_run(float dt, std::span<const glm::mat4> world, std::span<const glm::mat4> world_rate) noexcept;
  void end_run(std::span<glm::mat4> world, std::span<glm::mat4> palette) noexcept;
  void place_at_rest(Chain& chain) noexcept;  // the chain's tails on end_points_, moving with them

  std::vector<Chain> chains_;
  std::vector<SpringCollider> colliders_;
  float substep_ = default_substep;
  std::vector<std::int32_t> point_bone_;  // per point (chains' first heads and tails, then colliders' ends):
                                          // the bone whose matrix places it
  std::vector<glm::vec3> point_local_;    // ... and where in that bone's frame
  std::vector<std::int32_t> governed_;    // per bone: the joint that moves it, or -1
  std::vector<glm::mat4> inverse_bind_;   // per bone
  // Animated points at the last run (start of this step) and now, with velocities; the sample at a sub-step.
  std::vector<glm::vec3> start_points_, start_velocities_, end_points_, end_velocities_;
  std::vector<glm::vec3> sample_points_;
  std::size_t collider_points_ = 0;  // the first collider end among the points
  // Colliders' radii in world space at the start and end of the step; colliders at a sub-step.
  std::vector<float> collider_start_radius_, collider_end_radius_;
  std::vector<Placed> sample_colliders_;
  // Per joint: the kept state (positions, velocities, rest at the last sub-step), the reported one, corrections.
  std::vector<glm::vec3> positions_, velocities_, rests_;
  std::vector<glm::vec3> report_positions_, report_velocities_, report_rests_;
  bool reported_kept_ = true;  // the reported state is the kept one (no leftover owed): report_* not written
  // Per chain: its animated first head at the kept state's last sub-step, and in the reported state.
  std::vector<glm::vec3> heads_, report_heads_;
  std::vector<glm::vec3> drawn_;  // per point: the reported chain (first head, tails)
  std::vector<glm::mat4> corrections_;
  double owed_ = 0.0;
  bool started_ = false;
};

// Many characters' spring chains stepped together: each instance's run(dt, its world, its rate, its palette), the
// instances' bone matrices laid out one instance after another in caller-owned flat arrays. A chain's links wait on
// one another (each link's rest turns with the bend above it: square roots and divisions in a row), so one
// character's sub-step is bound by that latency; the job runs up to `group` instances' sub-steps together in
// structure-of-arrays lanes (one lane per instance, vector code), each lane the scalar code's operations in its
// order. A group goes chain by chain (chains do not act on one another): the chain's state and animated points are
// put in lanes once a step, all the step's sub-steps run there, and the state is written back to each instance, which
// owns it between runs (reset(), restart(), set_settings() and the instance's own run() go on working). When the step
// leaves no leftover (the reported state is the kept one), the lanes also compute end_run()'s bend (each joint's
// shortest arc and correction), which each instance then applies to its bones. A chain of more than 32 bones or 8
// colliders runs one instance at a time. Each instance computes exactly what its own run() would: the same bits for
// any group size, range split or thread count. Group 8 fills the lanes; smaller groups leave lanes idle (group 1 runs
// each instance alone).
//
// Every instance must have the chains of instances[0] laid out alike (the same chain count, bones per chain, collider
// count and each chain's colliders, the same skeleton size and sub-step; settings such as frequency may differ):
// the usual crowd of one character's copies.
struct DEFORM_RUNTIME_API SpringCrowdJob {
  static constexpr std::size_t max_group = 8;

  std::span<SpringChains> instances;
  float dt = 0.0f;                        // seconds, >= 0 and finite, for every instance
  std::span<glm::mat4> world;             // in/out: bones × instances, instance i's at [i × bones, (i + 1) × bones)
  std::span<const glm::mat4> world_rate;  // empty, or as world
  std::span<glm::mat4> palette;           // out: empty, or as world
  std::size_t group = 8;                  // instances stepped together, in [1, max_group]
  Isa isa = Isa::automatic;  // the lanes' kernel copy (isa.hpp): portable, or avx2 (which avx512 also runs); every
                             // copy gives the same bits (none fuses a multiply and an add)

  // Why run() would refuse: a dt negative or not finite, a group out of range, an isa not available here
  // (isa_available), an instance laid out unlike the first,
  // or world, world_rate or palette not one matrix per bone per instance (the last two may be empty). O(instances ×
  // chains).
  Status validate() const noexcept;
  // validate(), then each instance's run(). On failure changes nothing. No allocation: the lanes of one chain for a
  // group live on the calling thread's stack, about 48 KB, which a job system's fibers must have to spare.
  Status run() const noexcept;
  // The instances [begin, end), for ranges on threads (ThreadPool::parallel_for): refuses a range out of bounds, and
  // what validate() refuses of those instances (the sizes, the layout of each against instances[0]).
  Status run(std::size_t begin, std::size_t end) const noexcept;
  std::size_t count() const noexcept { return instances.size(); }

 private:
  Status check(std::size_t begin, std::size_t end) const noexcept;
};

}  // namespace deform
