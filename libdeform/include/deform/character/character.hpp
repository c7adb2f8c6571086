#pragma once
// Character: the facade over the SDK — a rigged mesh, its skin, its elastic lattices — behind a few calls:
//
//   deform::Character hero = deform::make_builtin_character();  // extras: the built-in model and its rig
//   hero.reach(hero.skeleton().find("hand_l"), {1.6f, 1.5f, 0.3f});   // IK, then stretch for the rest
//   every frame: hero.update(dt); draw hero.positions(), hero.normals(), hero.control_points(i)
//   hero.release();                                         // the stretch springs back, a damped oscillation
//
// reach(effector, target): the chain (rig reach root, or the effector's Rig::reach_chains root, or the parent of the
// topmost lattice above the effector — that lattice's bone itself when its parent is the skeleton's root, so a leg
// reaches from the hip joint) turns toward the target by CCD within the DOF limits; what distance remains is covered
// by stretching the chain's
// lattices along their bones (shares in proportion to their lengths; IK and stretch are solved together, so a bent
// chain that straightens as it grows is accounted for). The stretch is a spring target: update() lets the lattices
// spring toward it, so the effector arrives — within 1% of that remaining distance once settled — with the
// overshoot and settling of the lattices' damping. release() sets the targets back to zero. What the lattices show
// goes through their StretchShape (rig.lattices[l].shape, or deformers().set_shape): a soft floor on their length
// (default 70%) and volume compensation (default full), so a stretched arm thins and the spring-back bulges.
//
// A frame: pose (set_pose, e.g. from a SamplingJob) → IK (reach, on the chain alone) → update(dt): forward kinematics
// once (LocalToWorldJob: world matrices and skinning palette), the spring chains bending the pose, the lattices'
// springs' step, skinning, the lattices' carried points and fields → normals() on demand. Nothing on that path
// allocates; everything it needs is sized at construction. Characters are movable values (a std::vector of them is
// fine).
//
// Normals (NormalsMode): transported by default — each point's bind-pose normal (angle-weighted, from the bind
// positions) goes through the skinning (cofactor of the blended matrix) and the lattices (cofactor of their map's
// Jacobian) in update(), and normals() copies it to the point's render vertices; or recomputed from the deformed
// positions by normals() (VertexNormalsJob). Transported normals are exact for a point skinned rigidly and moved
// by one lattice with full weight, and approximate where skin or selection weights blend (docs/performance.md,
// "Vertex normals", states the error on the built-in character).
//
// Morph targets (Model::morph_targets, blend shapes): each character holds one weight per target (the targets'
// default weights at construction), set by index, by name or from a clip's morph channels at a time
// (set_morph_weights(clip, t): the engine's path, sample_morph_weights). update() runs MorphJob on the bind positions
// (and, transporting normals, the bind normals) into per-character arrays sized at construction, then skins those:
// morph in bind space, then skin, as glTF and three.js do. With no targets, or every weight 0, the job is skipped and
// the frame costs what it did without morphs. The lattices deform the morphed, skinned points as any others.
//
// A crowd: instance() makes another character of the same model and rig that shares the immutable bind data
// (mesh, skeleton, weights, normals binding, bind normals) and owns only its per-frame state (pose, springs,
// positions, normals). Characters are independent: an engine's job system updates a contiguous range of them per
// thread (no hidden threads; bench/crowd_bench.cpp). Distant ones show levels of detail (set_levels, set_level:
// fewer bones per point, deformers off, deformed every Nth update, a simplified mesh's points only; docs/skinning.md,
// "Levels of detail").
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "deform/character/export.hpp"
#include "deform/offline/bone_lod.hpp"
#include "deform/offline/rig.hpp"
#include "deform/offline/delta_mush.hpp"
#include "deform/offline/direct_delta_mush.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/morph.hpp"
#include "deform/runtime/pose_driver.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/runtime/skinning.hpp"
#include "deform/runtime/spring_chain.hpp"
namespace deform {

// What reach() decided.
struct ReachResult {
  Status status;          // refused (bad effector or target, a chain longer than max_chain_bones): nothing changed
  float residual = 0.0f;  // |target - effector| after IK alone, before stretching (model units)
  float stretch = 0.0f;   // total stretch asked of the chain's lattices (model units)
  float distance = 0.0f;  // |target - effector| once the stretch has settled
  int iterations = 0;     // IK + stretch rounds
};

class DEFORM_CHARACTER_API Character {
 public:
  // Binds the rig's lattices to the model (see DeformerHierarchy) and puts it in its bind pose. Throws
  // deform::Error when the rig does not fit the model. Allocates everything the per-frame path needs, reach()
  // included (its chain storage and IK scratch are sized for the skeleton's deepest chain).
  Character(Model model, const Rig& rig);
  // No lattices: skinning and IK only.
  explicit Character(Model model);
  // Movable: nothing in a Character points into itself (its jobs are made per call), so a move is member-wise, keeps
  // the storage reserved for the per-frame path and allocates nothing; an engine keeps its characters in a
  // std::vector. A moved-from Character may only be assigned to or destroyed. Not copyable: a copied vector keeps
  // its elements but not its reserved capacity, which reach() relies on.
  Character(Character&&) noexcept = default;
  Character& operator=(Character&&) noexcept = default;
  Character(const Character&) = delete;
  Character& operator=(const Character&) = delete;
  ~Character() = default;

  // Another character of the same model and rig, sharing this one's immutable bind data (model(), the normals
  // binding and bind normals: not copied) with its own per-frame state: bind pose, springs at rest, no reach, default
  // morph weights, `settings` whole, the normals mode, max stretch, Delta Mush and Direct Delta Mush (their bindings
  // shared), the lattices' current elastic settings, shapes and motion, and the spring chains' settings copied.
  // Allocates that state only (about 142 KB for the built-in character; docs/performance.md, "2026-11-24, late").
  Character instance() const;

  const Model& model() const noexcept { return bind_->model; }
  const Skeleton& skeleton() const noexcept { return bind_->model.skeleton; }
  // The rig as it stands now: its lattices' specs as the hierarchy holds them (set_shape, set_motion, set_elastic
  // change them there) and its spring chains' as springs() holds them, with the rig's reach chains, max_stretch and
  // model. Each spec is held once, where it is used; this assembles a copy (allocates), e.g. to save the tuned rig.
  Rig rig() const;
  DeformerHierarchy& deformers() noexcept { return hierarchy_; }
  const DeformerHierarchy& deformers() const noexcept { return hierarchy_; }

  // The held pose (every bone's local rotation and translation), clamped into the DOF limits. Cancels nothing: a
  // stretch in progress goes on. Refuses, changing nothing, a pose of the wrong size, not finite or with a zero
  // rotation. No allocation; O(bones).
  Status set_pose(const Pose& pose);
  // The held pose and where it is heading: `later` is the same motion `lead` seconds later (the animation sampled at
  // t + lead; a millisecond is plenty), both clamped alike. update() takes every bone's velocity from the two, and
  // the lattices' inertia (LatticeMotion) and the spring chains follow the motion between frames along cubics
  // through those velocities: the same curve at any frame rate. With set_pose(pose) alone the bones move linearly
  // between frames (docs/elasticity.md, "Secondary motion", says what that costs). reach() keeps the reached joints
  // still relative to their parents in `later`. Refuses, changing nothing, what set_pose refuses for either pose and
  // a lead that is not finite and > 0. No allocation.
  Status set_pose(const Pose& pose, const Pose& later, float lead);
  const Pose& pose() const noexcept { return pose_; }

  // Morph-target weights, one per Model::morph_targets entry (empty without targets), as update() applies them.
  // A new character (and an instance()) starts from the targets' default weights. The setters refuse, changing
  // nothing, an index out of range ("morph target out of range"), a name no target has ("no morph target of that
  // name") and a weight that is not finite; a name sets every target of that name (glTF meshes may repeat one).
  // Take effect at the next update(). No allocation: O(1), O(targets) by name or span.
  std::size_t morph_target_count() const noexcept { return morph_weights_.size(); }
  std::span<const float> morph_weights() const noexcept { return morph_weights_; }
  Status set_morph_weight(std::size_t target, float weight) noexcept;
  Status set_morph_weight(std::string_view name, float weight) noexcept;
  // All of them at once: as many weights as targets.
  Status set_morph_weights(std::span<const float> weights) noexcept;
  // The clip's morph channels at `seconds` (sample_morph_weights: the clip's local time): the targets the clip
  // animates take its weights, the others keep theirs. Refuses, changing nothing, what sample_morph_weights refuses
  // (a time not finite, a channel's target out of range). O(channels · log keys), no allocation.
  Status set_morph_weights(const Animation& clip, float seconds) noexcept;
  // Every weight back to its target's default.
  void reset_morph_weights() noexcept;
  // The morphed bind-pose positions the last deforming update() skinned, one per point: the bind positions when no
  // weight was set (no targets, or all 0). A caller that deforms elsewhere (deform_on_cpu = false) morphs itself —
  // MorphJob over model().morph_targets with morph_weights() — as update() then does not.
  std::span<const glm::vec3> morphed_bind_positions() const noexcept {
    return morphed_ ? std::span<const glm::vec3>(morphed_positions_)
                    : std::span<const glm::vec3>(model().mesh.positions);
  }

  // Delta Mush (runtime/delta_mush.hpp), an optional smoothing stage after the lattices, off by default: update()
  // then mushes the skinned, stretched points in place, so that a bent joint and the stretched rubber stay smooth
  // while the surface keeps its detail. set_delta_mush binds it for this model (bind_delta_mush: allocates and throws
  // as it does, so call it at set-up; iterations 0 turns the stage off, as clear_delta_mush does) and takes effect at
  // the next update(). While it is on, normals() recomputes the normals from the mushed points (VertexNormalsJob),
  // whatever normals_mode() says. It runs only when update() deforms completely (deform_on_cpu and lattice_fields
  // true; else the caller, who finishes the deformation, mushes after it: DeltaMushJob with delta_mush()). Instances
  // share the binding. Off, the frame is what it was without the stage, to the bit.
  void set_delta_mush(const DeltaMushSettings& settings);
  void clear_delta_mush() noexcept;
  // The binding in use, or null when the stage is off.
  const DeltaMushBinding* delta_mush() const noexcept { return mush_.get(); }

  // Direct Delta Mush (runtime/direct_delta_mush.hpp) as the skinning, off by default: while it is bound, update()
  // skins with DirectDeltaMushJob over palette() in place of settings.skinning (which it overrides, LBS or DQS alike,
  // and which takes effect again once it is cleared); morph targets, the lattices and the Delta Mush stage then run
  // after it as they do after LBS. The morphed bind points go in as the job's input points (each morph offset turned
  // with its point). Transported normals (normals_mode()) turn by each point's DDM rotation, the rotation of its
  // smoothed neighbourhood, so they follow the surface the job makes, not the bones' blended matrix whose cofactor
  // would disagree with the smoothed positions near joints; recomputed normals are recomputed, as always.
  // set_direct_delta_mush binds it for this model's mesh and weights (bind_direct_delta_mush: allocates, costs a
  // sparse factorisation and solves, and throws deform::Error as the binder does, changing nothing: call it at
  // set-up) and takes effect at the next update(). It runs only when update() deforms (deform_on_cpu; else the caller
  // skins, with direct_delta_mush() and palette()). Instances share the binding. Off, the frame is what it was without
  // it, to the bit. No allocation per frame: the job needs no scratch. settings.variant = reduced skins with
  // DirectDeltaMushReducedJob instead (4 floats an influence, the bones' rotations blended: the DQS palette of
  // palette() computed each frame) and keeps only the reduced binding: direct_delta_mush() is then null and
  // direct_delta_mush_reduced() the binding; the rest of the above holds alike.
  void set_direct_delta_mush(const DirectDeltaMushSettings& settings);
  void clear_direct_delta_mush() noexcept;
  // The binding in use, or null when Direct Delta Mush is off.
  const DirectDeltaMushBinding* direct_delta_mush() const noexcept { return direct_mush_.get(); }
  // The reduced binding in use (settings.variant = reduced), or null.
  const DirectDeltaMushReducedBinding* direct_delta_mush_reduced() const noexcept { return reduced_mush_.get(); }

  // Pose-space correctives (runtime/pose_driver.hpp): a driver's shapes are morph targets of the model, shape s the
  // target `targets[s]`; each update() then sets those targets' weights from the pose (PoseDriverJob on pose()'s
  // rotations) before the morph step, overriding what the setters above gave them. The rig's corrective groups
  // (Rig::correctives) come as drivers already, their shapes appended to the model's morph targets. add_pose_driver
  // adds one; it refuses, changing nothing, a driver PoseDriverJob::validate refuses for this skeleton or targets
  // not one per shape and in range. Instances share the drivers. No allocation per frame.
  Status add_pose_driver(const PoseDriverBinding& driver, std::span<const std::uint32_t> targets);
  void clear_pose_drivers() noexcept;
  std::size_t pose_driver_count() const noexcept { return drivers_.size(); }
  const PoseDriverBinding& pose_driver(std::size_t i) const noexcept { return *drivers_[i].binding; }
  // The morph target each of driver i's shapes sets (i < pose_driver_count()).
  std::span<const std::uint32_t> pose_driver_targets(std::size_t i) const noexcept { return drivers_[i].targets; }

  // The spring chains of the rig (Rig::spring_chains): tune them, draw their points, reset them after a teleport.
  SpringChains& springs() noexcept { return springs_; }
  const SpringChains& springs() const noexcept { return springs_; }

  // The solvers and limits reach() can use (Settings::reach_solver, Settings::reach_limits, described there).
  enum class ReachSolver : std::uint8_t { ccd, two_bone };
  enum class JointLimits : std::uint8_t { euler, swing_twist };

  // The knobs that need no check when set: plain values, read by the next update() or reach(), copied whole by
  // instance(). Settings with an invariant to keep have setters instead (set_max_stretch, set_normals_mode,
  // set_delta_mush, set_direct_delta_mush).
  struct Settings {
    // LBS or DQS; a bound Direct Delta Mush (set_direct_delta_mush) takes precedence over it.
    SkinningMethod skinning = SkinningMethod::lbs;
    // true (the default): update() deforms completely. false: update() leaves out the lattices' Bézier fields
    // (DeformerHierarchy::apply_carried instead of apply) for a caller that evaluates them elsewhere, e.g. on a GPU,
    // from deformers().binding(l), bound_weights(l) and displacements(l); positions() and normals() are then those of
    // the skinned, carried surface, and adding the fields to positions() gives what true gives.
    bool lattice_fields = true;
    // true (the default): update() deforms on the CPU (skinning, then the lattices as lattice_fields says). false:
    // update() only poses — forward kinematics, the spring chains, the lattices' springs and DeformerHierarchy::update
    // — for a caller that deforms elsewhere, e.g. the whole deformation on a GPU: deform::GpuSkinning from palette()
    // and bind_normals(), then deform::GpuLatticeFields::apply_into from deformers() (docs/gpu.md). positions() and
    // normals() then keep what the last deforming update() gave (the bind pose before any); bone_position() and
    // control_points() follow the pose as always. Takes effect at the next update().
    bool deform_on_cpu = true;
    IkSettings ik;  // max_iterations and escape_stalls are used; the tolerance is set per reach
    // A pole for reach() (IkJob::pole), used when `use_reach_pole`: a model-space point the chain's middle bends toward
    // (a knee or elbow hint), applied without losing the target.
    glm::vec3 reach_pole{0.0f};
    bool use_reach_pole = false;
    // The solver reach() uses: CCD over the rig's chain (the default), or the closed-form two-bone solve of the limb
    // that ends at the effector — its parent and grandparent joints, e.g. upper arm and forearm (TwoBoneIkJob, with
    // reach_soften and the pole) — for a limb that should bend like one; it takes Euler limits only (with swing_twist
    // reach_limits, reach() refuses). Takes effect at the next reach().
    ReachSolver reach_solver = ReachSolver::ccd;
    // two_bone: how softly the limb approaches full extension, [0, 1] (TwoBoneIkJob::soften); out of range, reach()
    // refuses. What it leaves short the lattices stretch to cover, like any residual (to within a few percent of it:
    // the stretched limb is softened again).
    float reach_soften = 0.0f;
    // How reach() limits the chain's joints: by the skeleton's Euler limits (the default), or by swing-twist limits
    // derived from them (swing_twist_from_euler: a twist range about each bone's axis and a swing cone around it, which
    // may leave the Euler box; the reached pose is kept as solved). Takes effect at the next reach().
    JointLimits reach_limits = JointLimits::euler;
    // Levels with an update_interval > 1 (LevelOptions): false (the default), update() moves positions() a share of
    // the way to the last deformed points on every update (36 bytes a point); true, the renderer does it, drawing
    // from + share · (to − from) of interpolation() in its vertex shader, and an update between deformed ones does no
    // per-point work at all (O(1)). The frames shown are the same, to float rounding. While such an interpolation
    // runs, positions() gives its `to`, the last deformed points (what picking and bounds then see, at most one
    // interval ahead of the frame drawn). A Settings flag rather than a LevelOptions field: it is the renderer's
    // choice, the same for every level it draws, and it may change between any two updates (the interpolation in
    // progress is then finished on the other side, without a jump).
    bool renderer_interpolates = false;
  };
  Settings settings;
  // The bones of the last reach's chain, root first, effector last (empty before any).
  std::span<const std::int32_t> reach_chain() const noexcept { return chain_.bones; }
  // Joint k's swing-twist limits in the last reach's chain (reach_limits swing_twist), else null.
  const SwingTwistLimits* reach_swing_twist(std::size_t joint) const noexcept {
    return joint < chain_.swing_twist.size() && chain_.swing_twist[joint].active ? &chain_.swing_twist[joint] : nullptr;
  }
  // The largest stretch reach() asks of a lattice, in multiples of its length (the rig's max_stretch, [0, 1000]).
  // Refuses, changing nothing, a value outside that range. Takes effect at the next reach().
  Status set_max_stretch(float max_stretch) noexcept;

  // Reaches for `target` (model space) with `effector`'s head: IK on the held pose, then the stretch target of the
  // chain's lattices. Refuses (result.status), changing nothing, an effector out of range or the root, a target not
  // finite or beyond ±1e18 on an axis (squared distances to it would overflow: the result would not be finite), a
  // chain longer than max_chain_bones. No allocation: the chain is rebuilt in storage reserved at
  // construction when the effector changes. Cost: up to 17 CCD solves of the chain (microseconds), no full FK.
  // Called again each frame while the body moves (after each set_pose), it re-solves on the new pose: a reach held so
  // (the same effector, not released, a target within a tenth of the chain's length of the last) is solved without
  // the stall escape's random restarts, so it follows its target smoothly. A reach that starts, and a release, move the
  // limb at once: the next update() takes that as a jump, not as motion — the lattices and spring chains on the limb
  // start again from the new pose.
  ReachResult reach(std::int32_t effector, glm::vec3 target);
  // Lets go: every stretch target back to zero; the pose reached stays.
  void release();

  // --- levels of detail (docs/skinning.md, "Levels of detail") ---
  // How a level runs, besides its skin (BoneLodLevel): whether its deformers run, and how often it updates.
  struct LevelOptions {
    // true: the lattices, the spring chains, Delta Mush and (at level 0 only) Direct Delta Mush run as set. false: the
    // level skins the animated pose alone (settings.skinning); the deformers' state waits and starts again from the
    // pose (restart) when a level with them is next shown.
    bool deformers = true;
    // The level deforms on every Nth update() (1 to 64): update() sums the dt of the updates between, so the springs
    // take the longer step, and positions() moves each update a share of the way to the last deformed points, reaching
    // them after N updates: piecewise linear, N updates behind, no pop. Normals follow the deformed updates only.
    // Used while the character deforms on the CPU (settings.deform_on_cpu), else every update poses. With
    // Settings::renderer_interpolates the renderer does that interpolation (interpolation()), and positions() gives
    // the last deformed points.
    std::uint32_t update_interval = 1;
    // The mesh points the level deforms, as the full mesh's point ids (any order, each once; copied by set_levels);
    // empty: all of them. A level drawn with a simplified mesh lists that mesh's points: simplify_model's
    // SimplifiedModel::source_point (deform/simplify/simplify.hpp, docs/skinning.md "Levels of detail"). Its skin is
    // gathered for those points at set_levels, so that skinning, the interpolation, the switch's blend and the normals
    // run over them alone. positions() and normals() keep the full mesh's numbering and size: the level writes its
    // points and the render vertices of those points only, and the others keep stale values (what an earlier level
    // or a switch's frame at the outgoing level left there; don't draw them): the renderer draws the simplified mesh's
    // triangles with their indices mapped to the full mesh's render vertices (SimplifiedModel::source_vertex) and
    // points (source_point). With `deformers` such a level runs the spring chains alone: they move bones, which its
    // points follow; the lattices and the mushes work on the whole mesh and wait (they start again from the pose at
    // the next level that runs them, as after a cut). It transports its normals whatever normals_mode() says
    // (recomputing them from the full mesh's triangles would read stale points): normals() gives each of its render
    // vertices its point's skinned bind-pose normal.
    std::span<const std::uint32_t> points = {};
  };
  // Binds levels: level l skins with lod.levels[l].weights (the full skeleton's bone ids) and runs as options[l] says;
  // level 0 should be the whole character (build_bone_lod's level 0). A switch (set_level) blends: its first update
  // deforms the frame at both levels (that update costs both) and positions() then goes from the outgoing level's
  // points to the new level's in `blend_frames` deformed updates (0: at once), by an offset per point that shrinks
  // linearly. With point subsets (LevelOptions::points) the blend runs over the new level's points: a point the
  // outgoing level deformed too blends by its offset as above; a point new to the level (not drawn before) starts at
  // its new place, at once and when the level interpolates. Throws deform::Error (kind argument, element "level N")
  // for a level count that differs from options' or is 0, a skin that SkinningJob refuses for this model (its reason),
  // an update_interval outside [1, 64], a point id out of range or listed twice; and for blend_frames over 1000
  // (element "blend_frames"). Allocates the levels (shared with instance()) and a per-point blend and interpolation
  // buffer (and one per point of the largest subset); the character starts at level 0. Call at set-up, not per frame.
  void set_levels(const BoneLod& lod, std::span<const LevelOptions> options, std::uint32_t blend_frames = 8);
  // The level the next update() shows (0 without levels), and how many there are (1 without levels).
  std::size_t level() const noexcept { return level_; }
  std::size_t level_count() const noexcept;
  // Shows `level` from the next update() on (see set_levels for the blend). Refuses, changing nothing, a level out of
  // range. No allocation, O(1): call it per frame with what pick_level gives.
  Status set_level(std::size_t level) noexcept;
  // Whether the next update() deforms: true without levels or off the CPU; false while an update_interval level is
  // between its deformed updates (that update only moves positions() on, or with Settings::renderer_interpolates
  // only the share, reading no pose: a crowd loop may skip sampling the clip and set_pose for it). No allocation,
  // O(1).
  bool next_update_deforms() const noexcept;
  // What a level costs per deformed update, for a caller that budgets a crowd.
  struct LevelCost {
    std::size_t points = 0;      // points skinned (the level's subset, LevelOptions::points)
    std::size_t influences = 0;  // Σ over points of their influences
    std::size_t bones = 0;       // bones the skin uses (the kept bones; forward kinematics still runs over all)
    bool deformers = true;
    std::uint32_t update_interval = 1;
  };
  // Level 0 without levels; a level out of range gives a zero cost.
  LevelCost level_cost(std::size_t level) const noexcept;

  // Advances the springs by dt seconds and deforms the held pose: FK once (twice with a lead), the spring chains,
  // the lattices' springs, skinning, lattices (see the top of this file). Refuses, changing nothing, a dt that is
  // negative or not finite. The later stages cannot refuse for a pose set by set_pose or reach; should one, update
  // reports its reason, never success. No allocation; O(bones + points + bound points · lattice cost). With levels
  // (set_levels), at the level set_level asked for: its skin, its deformers, its update interval and a switch's blend.
  Status update(float dt);

  // Cache hints for the state the next update() and normals() read and write (deform/runtime/prefetch.hpp): no
  // effect on any result. update() issues them itself as it starts; a crowd's loop may call it on the next
  // character while this one updates, so that its state is on its way before its update() starts. No allocation.
  void prefetch() const noexcept;
  // A cache hint for the character's own record (the object, whose members prefetch() reads to find its arrays), with
  // no load: a crowd loop calls it two characters ahead of the one it updates and prefetch() one ahead, so that
  // neither waits on memory (crowd/builtin_1000 in bench/crowd_bench.cpp). No effect on any result.
  void prefetch_record() const noexcept;

  // Deformed positions, one per mesh point (OBJ `v`), as of the last update(): the frame shown, or, while the renderer
  // interpolates (Settings::renderer_interpolates), the last deformed points, interpolation().to. Valid until the next
  // update(): under renderer_interpolates a deformed update swaps buffers, so the span's data moves.
  std::span<const glm::vec3> positions() const noexcept { return lerp_ ? target_ : positions_; }
  // The frame shown as the renderer draws it: point p at from[p] + share · (to[p] − from[p]), one per mesh point (the
  // level's points; the others as positions() says). While a level with an update_interval of N > 1 interpolates on
  // the renderer (Settings::renderer_interpolates), `to` is the last deformed points (positions()), `from` the frame
  // shown before that deformed update, and share goes k / N over the N updates from it (k = 1 at the deformed update;
  // a switch or set_level cutting an interval short starts the next one from the frame shown then). Otherwise from =
  // to = positions() and share 0, so that a renderer can always draw through it. A version names a buffer's content
  // (equal versions, equal points; each is at least 1): a renderer that keeps its two buffers tagged with them uploads
  // only what it lacks — after a whole interval the new `from` is the old `to` (its version too), so once per
  // interval only the new `to`. Valid until the next update(). No allocation, O(1).
  struct Interpolation {
    std::span<const glm::vec3> from;
    std::span<const glm::vec3> to;
    float share = 0.0f;
    std::uint64_t from_version = 0;
    std::uint64_t to_version = 0;
  };
  Interpolation interpolation() const noexcept {
    if (!lerp_) return {positions_, positions_, 0.0f, positions_version_, positions_version_};
    return {positions_, target_, float(lerp_span_ - approach_left_) / float(lerp_span_), positions_version_,
            target_version_};
  }
  // How normals() gets its normals (see the top of this file).
  enum class NormalsMode : std::uint8_t {
    transported,  // the default: carried through skinning and lattices in update(); normals() gathers (O(vertices))
    recomputed,   // recomputed from positions() by normals() (VertexNormalsJob: O(triangles), exact)
  };
  NormalsMode normals_mode() const noexcept { return normals_mode_; }
  // Takes effect at the next update() (recomputed: at the next normals()). Switching to recomputed the first time
  // allocates its scratch (one entry per point and corner): call it at set-up, not per frame.
  void set_normals_mode(NormalsMode mode);

  // Deformed normals, one per render vertex, as of the last update(): transported (gathered on the first call after
  // update(): one move per render vertex that is not its point's own slot, so a mesh laid out by
  // order_vertices_by_point, as the built-in character is, pays only for its seam copies) or recomputed from
  // positions() on the first call after update() (VertexNormalsJob over a binding made at construction:
  // O(triangles)), by normals_mode(). The span stays valid for the character's
  // life, but what it shows is the last update()'s normals only once normals() has been called after that update():
  // transported normals are gathered in the same array (one per point first, then in place per render vertex).
  std::span<const glm::vec3> normals();
  // The skinning palette of the last update() (T_W · T_B⁻¹ per bone, the spring chains' bending included): what
  // SkinningJob::matrices gets, for a caller that skins elsewhere (deform_on_cpu = false). Identity before any.
  std::span<const glm::mat4> palette() const noexcept { return palette_; }
  // The bind-pose unit normals the transported mode skins, one per mesh point (angle-weighted over the bind
  // positions): a GPU skinning that should give normals() gathers them per render vertex (Mesh::vertex_point).
  std::span<const glm::vec3> bind_normals() const noexcept { return bind_->point_normals; }
  // Whether the last update() ran the lattices (their springs and DeformerHierarchy::update): true without levels,
  // false when it showed a level without deformers or with a point subset (LevelOptions), whose lattices wait. The
  // frame then has no lattice in it, and deformers()'s state (active(), displacements()) is an earlier update's: a
  // caller that adds the lattices itself (deform_on_cpu = false) adds none.
  bool lattices_ran() const noexcept { return runs_lattices(shown_); }
  // A lattice's control points in world space (for drawing), i-fastest.
  std::span<const glm::vec3> control_points(std::size_t lattice) const { return hierarchy_.control_points(lattice); }
  // World head of a bone including what the lattices above it carry it by.
  glm::vec3 bone_position(std::int32_t bone) const;
  // The stretch the lattices have now, summed over those reach() stretches (model units); 0 when not reaching.
  float stretch() const;
  // The effector of the last reach (-1 before any).
  std::int32_t effector() const noexcept { return effector_; }

 private:
  // A lattice reach() stretches.
  struct Stretched {
    std::size_t lattice = 0;
    std::int32_t child = -1;  // the chain bone right below the lattice's bone
    glm::vec3 axis{0.0f};     // stretch per unit, in the lattice bone's frame
  };

  // What instances share: read-only after construction.
  struct BindData {
    Model model;
    VertexNormalsBinding vertex_normals;
    std::vector<glm::vec3> point_normals;  // bind-pose unit normals, one per point (angle-weighted)
    std::vector<EulerLimits> limits;       // each bone's DOF limits prepared for set_pose's clamp
    // Transported normals in place (points no more than render vertices): update() puts the per-point normals in
    // the first point_count() entries of normals_ and normals() gathers them there into render-vertex order, so an
    // instance holds and writes no separate per-point array (34 KB less per built-in character).
    bool normals_in_place = false;
    InPlaceGather normals_gather;
  };
  Character(std::shared_ptr<const BindData> bind, const Rig& rig, const DeformerHierarchy& hierarchy);
  void allocate_frame_state();
  void forget_held_specs() noexcept;
  void clamp_pose(Pose& pose) const noexcept;
  // update()'s LBS or DQS (settings.skinning) of the (morphed) bind points, and their normals when transporting.
  // Into `out_positions` and `out_normals` (transporting), one per skin entry.
  SkinningJob skinning_job(std::span<const glm::vec3> rest_positions, std::span<const glm::vec3> rest_normals,
                           bool transport, const SkinWeights& weights, std::span<glm::vec3> out_positions,
                           std::span<glm::vec3> out_normals) noexcept;
  Status skin(std::span<const glm::vec3> rest_positions, std::span<const glm::vec3> rest_normals, bool transport,
              const SkinWeights& weights, std::span<glm::vec3> out_positions,
              std::span<glm::vec3> out_normals) noexcept;
  // A subset level's skinning (deform_frame): its points into positions_, its normals into level_normals_.
  Status skin_subset(std::size_t level) noexcept;
  // Where update() transports the per-point normals: normals_'s first entries, or point_normals_.
  std::span<glm::vec3> point_normals() noexcept;
  // reach()'s steps (character.cpp): refuse a bad effector or target, the chain, its lattices, the first solve, the
  // stretch rounds, the reached pose held.
  struct ReachSolve;
  Status refuse_reach(std::int32_t effector, glm::vec3 target) const noexcept;
  std::int32_t reach_chain_root(std::int32_t effector) const noexcept;
  Status prepare_reach_chain(std::int32_t effector);
  void find_chain_lattices(std::int32_t effector);
  Status start_reach_solve(ReachSolve& solve, glm::vec3 target, float reach_length, bool continuing);
  glm::vec3 stretch_growth() noexcept;
  float stretch_to_target(ReachSolve& solve, glm::vec3 target, ReachResult& result);
  void hold_reach(std::int32_t effector, float lambda, bool continuing, ReachResult& result);

  std::shared_ptr<const BindData> bind_;
  Rig rig_;  // the rig without its lattices and spring chains, which hierarchy_ and springs_ hold (rig())
  DeformerHierarchy hierarchy_;
  SpringChains springs_;
  Pose pose_;
  Pose later_;  // set_pose(pose, later, lead): the pose lead_ seconds later (lead_ 0: none)
  float lead_ = 0.0f;
  std::vector<glm::mat4> world_;
  std::vector<glm::mat4> world_later_;  // ... its world matrices and the bones' rates d(world)/dt
  std::vector<glm::mat4> world_rate_;
  std::vector<glm::mat4> palette_;
  std::vector<DualQuat> dual_quats_;
  std::vector<glm::mat3> scales_;
  std::vector<glm::vec3> positions_;
  std::vector<glm::vec3> point_normals_;  // transported: one per point, as of update() (empty when in place)
  std::vector<glm::vec3> normals_;  // one per render vertex (in place: per point until normals(), and a scratch entry)
  std::vector<glm::vec4> normals_scratch_;  // VertexNormalsJob::scratch (allocated for the recomputed mode only)
  // Morph targets: one weight per target; the morphed bind positions and normals, one per point (allocated only when
  // the model has targets); whether the last deforming update() morphed (a weight was not 0).
  std::vector<float> morph_weights_;
  std::vector<glm::vec3> morphed_positions_;
  std::vector<glm::vec3> morphed_normals_;
  bool morphed_ = false;
  NormalsMode normals_mode_ = NormalsMode::transported;
  bool transported_current_ = false;  // the last update() transported point_normals_
  bool normals_current_ = false;
  std::int32_t effector_ = -1;
  bool reaching_ = false;               // a reach is held (reach() since the last release())
  glm::vec3 reach_target_{0.0f};        // the last reach's target
  std::int32_t jumped_root_ = -1;       // the root of a limb a reach snapped or let go since the last update(), or -1
  std::vector<std::size_t> stretched_;  // lattices of the last reach (capacity: every lattice)
  // reach()'s working storage, sized at construction: the chain (rebuilt when the effector changes), the pose being
  // solved, the IK scratch and the joints' model-space matrices for the deepest chain, the chain's lattices.
  IkChain chain_;
  std::int32_t chain_effector_ = -1;
  JointLimits chain_limits_ = JointLimits::euler;  // the kind chain_ was built with
  ReachSolver chain_solver_ = ReachSolver::ccd;    // the solver chain_ was built for
  Pose work_;
  std::vector<std::byte> ik_scratch_;
  std::vector<glm::mat4> chain_world_;
  std::vector<Stretched> chain_lattices_;
  // Delta Mush: the binding (shared by instances; null when off) and the job's scratch.
  std::shared_ptr<const DeltaMushBinding> mush_;
  std::vector<glm::vec4> mush_scratch_;
  // Direct Delta Mush: the binding (shared by instances; null when off). Its job needs no scratch.
  std::shared_ptr<const DirectDeltaMushBinding> direct_mush_;
  // Levels of detail (set_levels): shared by instances; null without levels.
  // A level's point subset (LevelOptions::points), bound: all empty for a level of all points.
  struct LevelPoints {
    std::vector<std::uint32_t> points;      // the full mesh's point ids, ascending
    bool contiguous = false;                // they are a range of ids (points renumbered, order_points_first)
    std::vector<std::uint8_t> member;       // per mesh point: 1 when the level deforms it
    std::vector<glm::vec3> rest_positions;  // per subset point: its bind position and bind normal
    std::vector<glm::vec3> rest_normals;
    std::vector<std::uint32_t> vertices;  // the render vertices of those points, and each one's subset index
    std::vector<std::uint32_t> vertex_slot;
    // Subset point i is render vertex i's (points renumbered first, vertices ordered by point, order_points_first):
    // the skinning writes the normals into normals_ itself and normals() copies them to the seams' vertices alone.
    // Else they go through level_normals_.
    bool normals_in_place = false;
  };
  struct LevelData {
    std::vector<SkinWeights> weights;  // per level: one per mesh point, or one per subset point
    std::vector<LevelCost> costs;
    std::vector<LevelPoints> subsets;
    std::size_t largest_subset = 0;            // points, of any subset level
    std::size_t largest_scattered_subset = 0;  // points, of a subset level whose normals are not in place
    std::uint32_t blend_frames = 0;
  };
  // Whether `level` runs the lattices (and the mushes): its deformers on and every point deformed.
  bool runs_lattices(std::size_t level) const noexcept {
    return !levels_ || (levels_->costs[level].deformers && levels_->subsets[level].points.empty());
  }
  bool level_has(std::size_t level, std::size_t point) const noexcept {
    return levels_->subsets[level].points.empty() || levels_->subsets[level].member[point] != 0;
  }
  void allocate_level_state();
  std::shared_ptr<const LevelData> levels_;
  std::size_t level_ = 0;            // the level asked for (set_level)
  std::size_t shown_ = 0;            // the level the last deformed update showed
  std::uint32_t tick_ = 0;           // updates at an update_interval > 1 since its last deformed one
  float pending_dt_ = 0.0f;          // their dt, summed
  std::uint32_t blend_left_ = 0;     // deformed updates the switch's offset still shrinks over
  std::vector<glm::vec3> blend_;     // the switch's offset per point (outgoing - new)
  std::vector<glm::vec3> target_;    // update_interval > 1: the last deformed points, the frame shown moving to them
  std::uint32_t approach_left_ = 0;  // updates until the frame shown reaches target_
  // Settings::renderer_interpolates: an interpolation on the renderer runs (positions_ holds its `from`, target_ its
  // `to`, the share is (lerp_span_ - approach_left_) / lerp_span_); the versions of positions_'s and target_'s content
  // (interpolation()), from a counter per character.
  bool lerp_ = false;
  std::uint32_t lerp_span_ = 0;
  std::uint64_t positions_version_ = 1;
  std::uint64_t target_version_ = 1;
  std::uint64_t version_counter_ = 1;
  template <class F>
  void for_each_point(std::size_t level, F&& f) const;
  void settle_interpolation(std::size_t level) noexcept;
  // A subset level's skinned points and normals, one per subset point (sized by the largest subset; the normals only
  // for a level whose normals are not in place), and its rest points and normals gathered from the morphed ones (only
  // with morph targets); the subset level whose normals normals() copies to its render vertices (-1: none, the last
  // update's normals are the whole mesh's).
  std::vector<glm::vec3> level_positions_;
  std::vector<glm::vec3> level_normals_;
  std::vector<glm::vec3> level_rest_;
  std::int32_t subset_normals_ = -1;
  Status deform_frame(float dt, std::size_t level);
  std::shared_ptr<const DirectDeltaMushReducedBinding> reduced_mush_;  // set_direct_delta_mush's reduced variant
  // Pose-space correctives: each driver (shared), the morph target of each of its shapes, its weights' room.
  struct Driven {
    std::shared_ptr<const PoseDriverBinding> binding;
    std::vector<std::uint32_t> targets;
    std::vector<float> weights;
  };
  std::vector<Driven> drivers_;
};

// The limbs reach() stretches, for a caller that reaches with "the nearest limb" (a click beside the character):
// every lattice's bone that has no lattice on a bone below it and a lattice on a bone above it (the end of a chain of
// lattices, which reach() stretches the lattices above: hand_l, hand_r, foot_l and foot_r with builtin_full_rig; the
// lattice on the effector itself does not stretch), plus the rig's reach effector and its reach_chains' effectors;
// ascending ids. Allocates the result.
DEFORM_CHARACTER_API std::vector<std::int32_t> reach_effectors(const Character& character);
// Of reach_effectors(), the one whose head (bone_position: as deformed now) is nearest `target`; ties go to the lower
// id. -1 when there is none or the target is not finite. No allocation; O(lattices² · depth + depth).
DEFORM_CHARACTER_API std::int32_t nearest_reach_effector(const Character& character, glm::vec3 target);

// Choosing a level is the caller's (Character::set_level); these help from a camera. The height `extent` (model units)
// at `distance` from a perspective camera of vertical field of view `vertical_fov` (radians, in (0, pi)) covers this
// fraction of the viewport's height (2 · atan(extent / 2 / distance) / vertical_fov, 1 or more when it fills it); 0
// for an argument not finite or not positive. No allocation.
DEFORM_CHARACTER_API float screen_height(float extent, float distance, float vertical_fov) noexcept;
// The level for a screen height: the number of `thresholds` (decreasing fractions of the viewport's height, one per
// level after 0: level l while the height is below thresholds[l - 1]) that `height` is below; thresholds not
// decreasing are taken as they come (the first that the height is not below ends the count). No allocation.
DEFORM_CHARACTER_API std::size_t pick_level(std::span<const float> thresholds, float height) noexcept;

// `clip` with the character's pose drivers baked in, for a file that plays without libdeform (a skinned glTF export,
// docs/gltf-export.md "Pose-space correctives"): each morph target a driver sets gets a linear weight track with a key
// every 1 / frames_per_second seconds from 0 and one at the duration: the weight update() sets when the character
// holds the clip's pose at that time (sampled from the bind pose, joint limits applied as set_pose applies them). A
// channel the clip had for such a target is replaced; the rest of the clip is unchanged. Between keys the weights are
// linear, where the driver is not: more keys follow it more closely. Throws deform::Error (argument) for a rate not
// finite or outside (0, 1000], or a clip the skeleton refuses. Allocates: offline.
DEFORM_CHARACTER_API Animation with_driven_weights(const Character& character, const Animation& clip,
                                                   float frames_per_second);

}  // namespace deform
