#pragma once
// The deformer hierarchy (thesis §9.4.1, fig. 53/54): elastic Bézier lattices bound to bones, whose stretch carries
// everything below them. docs/elasticity.md.
//
// Each lattice lives in its bone's bind frame with its U axis along the bone: u = 0 at the bone's head, u = 1 at the
// head of the bone's first child (for a leaf, at the farthest bound point), V and W fitted around the bound points.
// Its control points are an ElasticLattice simulated in that frame, so the rest moves with the bone and only the
// stretch (set_stretch_target) drives the springs. A stretch of s moves control point P_ijk by s·(i/l) along U; the
// first face (i = 0) is pinned and the last face (i = l) moves rigidly (its mean displacement), so
//  - a point the lattice selects is moved by  weight · D(u, v, w), where D is the lattice's displacement field
//    (Σ ΔP_ijk B_i B_j B_k, carried into world space by the bone's current matrix) and weight the point's selection
//    weight (its skin weight on the bone's subtree, or 1 for an explicit list);
//  - a selected point beyond the far face (u >= 1, the hand below a forearm) is translated by weight · δ, δ the far
//    face's displacement: exactly D at u = 1, so there is no seam at the border; points before the near face (u <= 0)
//    do not move, exactly D at u = 0 = 0.
// What update() shows of the springs' state is shaped like rubber (StretchShape): a length floor and volume
// compensation, both memoryless functions of the state, so the motion stays as frame-rate independent as the springs.
// Displacements of several lattices add up, applied after skinning (positions skinned with the unstretched pose), so
// skin blending at the joints is kept. A lattice on a mid-chain bone thus carries the bones and points below it —
// the hand follows a stretched forearm — and so does any lattice below it.
#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <string>
#include <optional>
#include <string_view>
#include <memory>
#include <vector>

#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// How a lattice chooses the points it moves.
enum class VertexSelection : std::uint8_t {
  subtree_weight,  // points whose summed skin weight on the bone and its descendants exceeds weight_threshold
  list,            // an explicit list of points (thesis fig. 52), each moved fully
};

// How a stretched lattice keeps its body, like rubber. Both act per slice of control points across the bone (the
// points with one index i along U), on the slices' mean displacement along the bone:
//  - a length floor: each segment between two slices shows the length ratio soft_length_floor(r, min_length_fraction)
//    of its spring state's r (identity for r >= floor + knee, then bending smoothly toward the floor, never
//    below it), so an under-damped release bulges back to at least that fraction instead of collapsing;
//  - volume compensation: each slice's rest points are scaled about the bone's line (its head, along U) by the
//    factor s^(-volume/2), s the slice's shown length ratio (the mean of its segments'), so the cross-section scales
//    by s^-volume: a stretched limb thins like a hose and a squashed one bulges. volume = 1 keeps the volume of a
//    lattice stretched uniformly exactly (an affine map of determinant s · s^-1); 0 is the plain stretch.
// The lattice's first face still does not move along the bone and the points beyond its far face are still carried
// by the far face's move along the bone; with volume > 0 its first and last faces scale across the bone too, so
// points just outside the lattice, not scaled, meet a scaled border: a step of |1 - s^(-volume/2)| times their
// distance from the bone's line, softened where the selection weights blend.
struct StretchShape {
  float min_length_fraction = 0.7f;  // in [0, 1); 0 = no floor
  float volume = 1.0f;               // in [0, 1]
  bool operator==(const StretchShape&) const = default;
};

// The shown length ratio of a segment whose springs give `ratio` (its length over its rest length), for a floor
// `min_fraction` in [0, 1): ratio itself when min_fraction is 0 or ratio >= min_fraction + knee, else
// min_fraction + knee · exp((ratio - min_fraction - knee) / knee), with knee = (1 - min_fraction) / 3 — continuous
// with its first derivative, increasing, never below min_fraction. A ratio of 1 or more is never changed.
DEFORM_RUNTIME_API float soft_length_floor(float ratio, float min_fraction) noexcept;

// Throws deform::Error ("<stretch shape>", naming the field) when a field is not finite or out of its range.
DEFORM_RUNTIME_API void require_valid_shape(const StretchShape& shape);

// What a lattice's bone is, for the default secondary motion of a rig (default_lattice_motion).
enum class BodyPart : std::uint8_t {
  upper_limb,  // upper arm, thigh: the flesh between two joints
  lower_limb,  // forearm, shin
  hand,        // a limb's end that carries nothing below it
  foot,
  torso,        // spine, chest, belly, hips
  head,         // head, neck
  appendage,    // tail, ears, hair, a ponytail as lattices: free to swing
  unspecified,  // not said (set up by hand, a rig file from before parts): LatticeMotion's defaults at inertia 1
};

// How a lattice's control points follow their bone's motion: secondary motion (docs/elasticity.md, "Secondary
// motion"). With both at 0 (the default, as in the thesis) the springs live in the bone's frame and only a stretch
// excites them. With inertia λ > 0 every control point also feels λ times minus its rest's acceleration in the world:
// it lags behind when the bone starts to move or turns, overshoots when it stops, and settles with the lattice's
// springs and damping (the forcing is the rest's world acceleration taken into the bone's frame; the offset's own
// Coriolis and centrifugal terms, second order in it, are left out). Gravity pulls every control point (a belly
// sags, then bounces). Both are measured in the bone's own frame, so a character scaled by any factor moves the same
// way, scaled.
// What the motion moves is flesh on a bone of a fixed length: the forcing (inertia and gravity) is taken per slice of
// control points across the bone (the points with one index i along U; an affine forcing's slice mean is its value at
// the slice's centre), and
//  - across the bone it moves each slice as a whole: the lattice shears and bends, it does not swell (a translation
//    of slices keeps the volume exactly);
//  - along the bone it drives one more oscillator per slice (the lattice's springs), whose offset z is shown as
//    b·tanh(z / b), b = along_bound · length(): a slice moves along the bone by less than b, so the limb keeps its
//    length within along_bound (the StretchShape's volume compensation then keeps its volume);
//  - a lattice that carries points beyond its far face (the joint and the limb below) moves that face by far_share
//    of its motion: at 0 the joint stays where the bone puts it and only the flesh between the joints jiggles, so a
//    limb keeps its length from joint to joint; at 1 the limb below lags with the far face. A lattice that carries
//    nothing (a hand, a foot, a tail's tip) moves its far face fully.
// Both parts are linear in the forcing and stepped exactly; the bound is a memoryless function of the state, so the
// motion is as frame-rate independent as the springs (docs/elasticity.md).
struct LatticeMotion {
  float inertia = 0.0f;          // λ in [0, 1]: 0 the bone carries the points rigidly, 1 they are free masses
  glm::vec3 gravity{0.0f};       // m/s², model space, e.g. {0, -9.81, 0} for a +Y-up model; at most 1e6 long
  float units_per_metre = 1.0f;  // model units in a metre (100 for a model in centimetres), in (0, 1e6]
  float along_bound = 0.02f;     // in [0, 1]: the most a slice moves along the bone, as a fraction of the length
  float far_share = 1.0f;        // in [0, 1]: how much of the motion a far face that carries points takes
  BodyPart part = BodyPart::unspecified;  // what the bone is: whose tuned inertia scaled_inertia scales
  bool active() const noexcept { return inertia != 0.0f || gravity != glm::vec3(0.0f); }
  bool operator==(const LatticeMotion&) const = default;
};

// Throws deform::Error ("<lattice motion>", naming the field) when a field is not finite or out of its range.
DEFORM_RUNTIME_API void require_valid_motion(const LatticeMotion& motion);

// The tuned secondary motion of a lattice on such a part (inertia, along_bound, far_share, the part; no gravity):
// flesh that wobbles between joints that stay put, hands that lag a little, feet that stay planted, appendages that
// swing — on the built-in walk and run, and on an imported clip with default_rig, each limb keeps its length within
// 2% and each lattice its volume within 3% (docs/elasticity.md, "Measured"). The built-in rigs and default_rig use
// it. An unspecified part gets LatticeMotion's defaults at inertia 1 (a free mass, bounded along the bone).
DEFORM_RUNTIME_API LatticeMotion default_lattice_motion(BodyPart part) noexcept;

// The tuned inertia of a lattice on `part` (default_lattice_motion(part).inertia) times `scale`: the one knob the
// viewer's slider, `deform simulate --inertia` and the C and Python global setters turn. 1 gives every part its
// tuned inertia, 0 a rigid body, between them every part in proportion, so each keeps its character (a limb's
// flesh wobbling less than a belly). An unspecified part's tuned inertia is 1, so for such a lattice the scale is its
// inertia, as the knob set it before lattices had parts. Throws deform::Error ("<lattice motion>") when `scale` is
// not in [0, 1].
DEFORM_RUNTIME_API float scaled_inertia(BodyPart part, float scale);

// A part's name as rig files write it ("upper_limb", ..., "appendage", "unspecified"), and the part of a name
// (std::nullopt for none).
DEFORM_RUNTIME_API std::string_view body_part_name(BodyPart part) noexcept;
DEFORM_RUNTIME_API std::optional<BodyPart> body_part_named(std::string_view name) noexcept;

// The set-up of one lattice (what a rig file stores, docs/formats.md).
struct LatticeSpec {
  std::string name;        // unique within a hierarchy
  std::int32_t bone = -1;  // the bone it is bound to
  glm::ivec3 degree{3};    // Bézier degree along U (the bone), V, W; 1 .. max_bezier_degree
  VertexSelection selection = VertexSelection::subtree_weight;
  float weight_threshold = 0.0f;        // subtree_weight: in [0, 1)
  std::vector<std::uint32_t> vertices;  // list: point indices, ascending, unique
  float margin = 0.05f;                 // sideways padding of the fitted box, fraction of its width, in [0, 1]
  ElasticSettings elastic;              // how its control points spring
  bool carry_descendants = true;        // points beyond the far face follow it (fig. 54); false = fig. 53
  StretchShape shape;                   // length floor and volume compensation
  LatticeMotion motion;                 // inertia and gravity (secondary motion)
  bool operator==(const LatticeSpec&) const = default;
};

// One lattice of a hierarchy as bind_hierarchy (deform::offline, offline/hierarchy_binding.hpp) fits and binds it to
// a mesh: what the per-frame path reads.
struct BoundLattice {
  LatticeSpec spec;
  BezierLattice rest{LatticeFrame{}};         // the rest lattice in its bone's bind frame (U along the bone)
  glm::vec3 axis{0.0f, 1.0f, 0.0f};           // unit U in the bone's frame
  float length = 0.0f;                        // |U|, model units
  LatticeBinding binding;                     // the points the Bézier field moves
  std::vector<float> lane_weights;            // their selection weights, per binding lane (0 in padding lanes)
  std::vector<std::uint32_t> carried_points;  // points beyond the far face, carried by it
  std::vector<float> carried_weights;         // their selection weights
};

class DEFORM_RUNTIME_API DeformerHierarchy {
 public:
  DeformerHierarchy() = default;
  // Takes the lattices bind_hierarchy (deform::offline) fitted and bound, for a mesh of `point_count` points and
  // `skeleton`, whose bone parents and bind matrices it copies (it keeps no reference: a hierarchy is movable).
  // Links each lattice to its parent lattice, sets up its springs (first face pinned) and puts it at rest. Throws
  // deform::Error when a lattice's bone is out of range or its binding does not fit its rest lattice or the points.
  // Allocates; O(lattices × control points + bones).
  DeformerHierarchy(const Skeleton& skeleton, std::vector<BoundLattice> lattices, std::size_t point_count);

  std::size_t lattice_count() const noexcept { return lattices_.size(); }
  // Read accessors taking a lattice index never throw: they require lattice < lattice_count(), as
  // std::vector::operator[] does (the sanitizer build checks it, with _GLIBCXX_ASSERTIONS). Setters refuse a bad
  // index: the per-frame ones with a Status, the configuration ones (set_elastic, set_shape, set_motion) with
  // deform::Error.
  const LatticeSpec& spec(std::size_t lattice) const noexcept { return lattices_[lattice].spec; }
  // The lattice index with this name, or -1.
  std::int32_t find(std::string_view name) const noexcept;
  // The nearest lattice whose bone is a proper ancestor of this lattice's bone, or -1 (the hierarchy of fig. 54).
  std::int32_t parent(std::size_t lattice) const noexcept { return lattices_[lattice].parent; }
  // The rest lattice in its bone's bind frame (frame, degree, rest control points).
  const BezierLattice& rest_lattice(std::size_t lattice) const noexcept { return lattices_[lattice].rest; }
  // Its length along the bone, |U|, model units.
  float length(std::size_t lattice) const noexcept { return lattices_[lattice].length; }
  // Points moved by the lattice's Bézier field, and points it carries (beyond its far face).
  std::size_t bound_count(std::size_t lattice) const noexcept { return lattices_[lattice].bound->binding.vertex_count; }
  std::size_t carried_count(std::size_t lattice) const noexcept {
    return lattices_[lattice].bound->carried_points.size();
  }

  // The stretch the lattice springs toward, model units along its bone (negative squashes). Refuses, changing
  // nothing, a lattice index out of range or a stretch that is not finite and > -length(). O(control points), no
  // allocation.
  Status set_stretch_target(std::size_t lattice, float stretch);
  float stretch_target(std::size_t lattice) const noexcept { return lattices_[lattice].target; }
  // The stretch it shows now: the far face's displacement along the bone (model units), after the length floor of
  // its StretchShape (so length() + stretch() >= min_length_fraction · length()). O(control points).
  float stretch(std::size_t lattice) const noexcept;
  // Changes a lattice's elastic settings keeping its state. Throws deform::Error when invalid or the index is out
  // of range.
  void set_elastic(std::size_t lattice, const ElasticSettings& settings);
  // Changes a lattice's length floor and volume compensation; shown from the next update(). Throws deform::Error
  // when invalid (require_valid_shape) or the index is out of range.
  void set_shape(std::size_t lattice, const StretchShape& shape);

  // Changes a lattice's inertia and gravity, keeping its state. Throws deform::Error when invalid
  // (require_valid_motion) or the index is out of range.
  void set_motion(std::size_t lattice, const LatticeMotion& motion);
  // Every lattice's inertia at `scale` of its part's tuned inertia (scaled_inertia), the rest of its motion and its
  // state kept: 1 the tuned jiggle, 0 none. Throws deform::Error, changing nothing, when `scale` is not in [0, 1].
  void set_inertia_scale(float scale);
  // The lattice's next step takes its bone's motion as it is then, with no jolt, as the first step does: for a bone
  // that jumped (a reach that snapped the limb). Refuses a lattice index out of range. No allocation.
  Status restart_motion(std::size_t lattice) noexcept;

  // Advances every lattice's springs by dt seconds (see ElasticLattice::step), the bones held still: no lattice
  // feels its bone's motion, gravity still pulls. Refuses, changing nothing, a dt that is negative or not finite.
  // No allocation.
  Status step(float dt);
  // The same with the bones' matrices at the end of the step (`world`, one per bone, as update() takes them), from
  // which lattices with a LatticeMotion take their bone's motion since the last step, and optionally their rates of
  // change (`world_rate`: d(world)/dt per bone at the end of the step, e.g. (world at t + ε − world at t) / ε for an
  // animation sampled a millisecond ahead; empty when unknown):
  //  - with world_rate, each control point's rest moves between two steps along the cubic through its positions and
  //    velocities, and the step is the exact flow of the springs under that motion (forced_step): a clip played at
  //    15 Hz and at 240 Hz gives the same curve to far better than 0.1% of its amplitude (docs/elasticity.md);
  //  - without, the rest moves linearly within each step and turns at the steps' ends: exact for such motion and
  //    second order in the step for smooth motion (about 1–2% of the amplitude between 15 and 240 Hz).
  // The first step after construction or reset() takes the motion as it is, with no jolt; a step with dt = 0 takes
  // a changed pose as a jump (a cut, a teleport), not as motion. Refuses, changing nothing, a dt that is
  // negative or not finite, or spans of the wrong size. No allocation.
  Status step(float dt, std::span<const glm::mat4> world, std::span<const glm::mat4> world_rate = {});
  // Every control point back on the unstretched rest, at rest; stretch targets 0.
  void reset();
  // Cache hints for the state the next step(), update() and apply() read and write (deform/runtime/prefetch.hpp):
  // no effect on it.
  void prefetch() const noexcept;

  // Per frame, after step(): carries the lattices into world space with the bones' current matrices (`world`, one per
  // bone, from LocalToWorldJob for the pose the points were skinned with). Refuses, changing nothing, a size
  // mismatch. O(lattices × control points), no allocation.
  Status update(std::span<const glm::mat4> world);
  // Adds every lattice's displacement to `positions` (the skinned points, mesh.point_count() entries). Refuses,
  // changing nothing, a size mismatch. O(bound points) Bézier evaluations (LatticeEvaluateJob) plus one add per
  // carried point; a lattice at rest is skipped. No allocation. Exactly apply_carried(), then for every active
  // lattice l, in index order, the field: positions[p] += bound_weights(l)[n] · D_l(n) for each lane n of
  // binding(l) with a point p (D_l(n): LatticeEvaluateJob's output for binding(l) with displacements(l)).
  Status apply(std::span<glm::vec3> positions);
  // apply() without the Bézier fields: adds only the translations of the carried points (beyond the far faces), for
  // a caller that evaluates the fields itself, e.g. on a GPU. Refuses, changing nothing, a size mismatch.
  // O(carried points), no allocation.
  Status apply_carried(std::span<glm::vec3> positions);
  // apply() carrying per-point unit normals along (`normals`: one per point, e.g. SkinningJob's out_normals, in the
  // space of `positions`): the carried points' normals are kept (a translation), and a bound point's normal becomes
  // (1 - weight) · n + weight · n_l, renormalised, where n_l is n mapped by the cofactor of the lattice's map
  // (LatticeEvaluateJob's normals, with n taken back into the bind pose by the transpose of the bone's palette
  // matrix). Exact for a point of selection weight 1 skinned rigidly to the lattice's bone (the FFD map of its
  // skinned neighbourhood); where weights blend it leaves out the gradient of the weight and blends directions.
  // The positions are apply()'s, bit for bit. Refuses, changing nothing, a size mismatch. No allocation; per bound
  // point one evaluation with normals (about twice apply()'s field cost) for a rest lattice on its frame's grid, as
  // bind_hierarchy fits them; for a sculpted rest lattice, apply()'s evaluation and one of the map below.
  Status apply(std::span<glm::vec3> positions, std::span<glm::vec3> normals);

  // What evaluating a lattice's field takes, for callers of apply_carried():
  // Its binding, made at construction: the bound points (mesh point indices, each once, in 16-lane blocks, padding
  // lanes LatticeBinding::no_vertex) and their (u, v, w) in the lattice's rest frame (bone bind space).
  const LatticeBinding& binding(std::size_t lattice) const noexcept { return lattices_[lattice].bound->binding; }
  // One selection weight per binding lane (binding(l).vertices.size() entries, 0 in padding lanes): in (0, 1].
  std::span<const float> bound_weights(std::size_t lattice) const noexcept {
    return lattices_[lattice].bound->lane_weights;
  }
  // As of update(): the control points of the lattice's displacement field, world space, i-fastest (point_counts of
  // rest_lattice(l)); evaluating binding(l) with them gives each bound point's displacement before its weight.
  std::span<const glm::vec3> displacements(std::size_t lattice) const noexcept {
    return lattices_[lattice].field.control_points();
  }
  // What apply_carried() adds, for callers that add it themselves (e.g. on a GPU, GpuLatticeFields::apply_into): the
  // points beyond the lattice's far face (mesh point indices, made at construction), their selection weights (one
  // per point, in (0, 1]), and, as of update(), the far face's displacement δ, world space: apply_carried() adds
  // carried_weights(l)[n] · far_displacement(l) to point carried_points(l)[n] for every active lattice l.
  std::span<const std::uint32_t> carried_points(std::size_t lattice) const noexcept {
    return lattices_[lattice].bound->carried_points;
  }
  std::span<const float> carried_weights(std::size_t lattice) const noexcept {
    return lattices_[lattice].bound->carried_weights;
  }
  glm::vec3 far_displacement(std::size_t lattice) const noexcept { return lattices_[lattice].far_displacement; }
  // What apply(positions, normals) turns the normals by, for callers that do it themselves (GpuLatticeFields with
  // normals), as of update(): the lattice's map without its translation as control points, linear · rest +
  // displacements(l), written into `out` (rest_lattice(l).point_count() entries; nothing is written otherwise), and
  // the matrix that takes a skinned normal back into the bind pose the binding's normal_basis expects. A bound
  // point's normal n becomes normalise(n + w · (n_l − n)) (kept when that is shorter than 1e-6), w its bound weight
  // and n_l the LatticeEvaluateJob normal of binding(l) with those control points for the input normal
  // normals_to_bind(l) · n: a LatticeEvaluateJob with those control points, normals_in_to_binding = normals_to_bind(l)
  // and weights = bound_weights(l) does both (apply() itself, for a rest lattice on its frame's regular grid, gets
  // the same Jacobian to rounding in one evaluation of the displacements, the frame's edges mapped by the bone as an
  // offset). No allocation.
  void mapped_points(std::size_t lattice, std::span<glm::vec3> out) const noexcept;
  glm::mat3 normals_to_bind(std::size_t lattice) const noexcept;
  // As of update(): false when the lattice is at rest (no control point is displaced by more than 1e-7 of its
  // length), which apply() skips.
  bool active(std::size_t lattice) const noexcept { return lattices_[lattice].active; }
  // The displacement update() gives a point `bind_point` (bind-pose world space) that moves with `bone` with full
  // weight: e.g. a bone's head, an IK effector. O(lattices).
  glm::vec3 point_displacement(std::int32_t bone, glm::vec3 bind_point) const noexcept;
  // The lattice's control points in world space as of update(), i-fastest (for drawing): the bone-carried,
  // elastically displaced points, plus what the lattices above carry them by. Computed for every lattice at the first
  // call after an update() (O(control points · lattices)), which keeps them out of a frame that does not draw them;
  // like the other calls, not to be made from two threads at once. The span is valid until the next update().
  std::span<const glm::vec3> control_points(std::size_t lattice) const noexcept;

 private:
  // What bind_hierarchy computed for a lattice and no frame changes: shared by the copies of a hierarchy (a
  // character's instances), so a crowd keeps one copy in memory and in the caches.
  struct Binding {
    LatticeBinding binding;                     // BoundLattice::binding, by mesh point
    std::vector<float> lane_weights;            // BoundLattice's
    std::vector<std::uint32_t> carried_points;  // BoundLattice's
    std::vector<float> carried_weights;         // BoundLattice's
    // The rest lattice's terms of the stretch shape (update, shape_slices): per control point its part across the
    // bone, rest - axis (rest · axis); per slice along U the sum of its control points' rest · axis.
    std::vector<glm::vec3> radial;
    std::array<float, max_bezier_degree + 1> slice_along{};
  };
  struct Lattice {
    LatticeSpec spec;  // per copy: its settings may change (set_shape, set_elastic, set_motion)
    BezierLattice rest{LatticeFrame{}};
    glm::vec3 axis{0.0f, 1.0f, 0.0f};
    float length = 0.0f;
    std::shared_ptr<const Binding> bound;
    std::int32_t parent = -1;
    glm::mat4 bind_world{1.0f};  // the bone's bind world matrix and its inverse
    glm::mat4 inverse_bind_world{1.0f};
    // Per frame (update): the control points are the world displacements (displacements(); point_displacement).
    BezierLattice field{LatticeFrame{}};
    std::vector<std::uint32_t> far_face;  // control point indices with i = l
    ElasticLattice elastic;
    std::vector<glm::vec3> target_points;  // rest stretched by `target`, bone frame
    float target = 0.0f;
    // Per frame (update): the far face's displacement; world control points.
    glm::vec3 far_displacement{0.0f};
    mutable std::vector<glm::vec3> world_points;  // for drawing, computed by control_points()
    glm::mat4 bone_world{1.0f};                   // the bone's world matrix as of update()
    glm::mat3 linear{1.0f};                       // the bone's world 3×3 (rotation, with any scale)
    // Secondary motion (step with world): the bone's matrix and rate at the last step, each slice centre's world
    // rest velocity over the last step (linear motion; the first point_counts().x entries), and this step's
    // accelerations in the bone's frame, per control point (its slice's).
    glm::mat4 motion_world{1.0f};
    glm::mat4 motion_rate{0.0f};
    bool motion_known = false;
    bool rate_known = false;
    bool rest_velocity_known = false;
    std::vector<glm::vec3> rest_velocity;
    std::vector<glm::vec3> accel_start;
    std::vector<glm::vec3> accel_end;
    // The motion along the bone (LatticeMotion): per slice the oscillator's offset and velocity, model units along
    // U, before the bound; its exact step for the last dt.
    std::array<float, max_bezier_degree + 1> along_offset{};
    std::array<float, max_bezier_degree + 1> along_velocity{};
    OscillatorStep along_step;
    ForcedStep along_forced;
    double along_dt = -1.0;
    std::vector<glm::vec3> mapped_points;  // apply(positions, normals): linear · rest + world displacement
    bool regular_rest = false;             // rest control points on the frame's grid (one evaluation for normals)
    bool active = false;
  };
  void stretch_points(Lattice& lattice) const;
  // The lattice a configuration setter changes; throws deform::Error for an index out of range.
  Lattice& configured(std::size_t index);
  Status step_lattice(Lattice& lattice, float dt, const glm::mat4* world, const glm::mat4* world_rate);
  // Per slice along U (rest_lattice(l).point_counts().x of them): the shift along the bone the length floor adds to
  // the slice's mean displacement and the slice's scale across the bone.
  struct SliceShape {
    std::array<float, max_bezier_degree + 1> shift{};
    std::array<float, max_bezier_degree + 1> scale{};
  };
  static void shape_slices(const Lattice& lattice, SliceShape& slices) noexcept;
  // Per slice: what the motion shows along the bone (LatticeMotion::along_bound), model units along U.
  static void along_shown(const Lattice& lattice, std::array<float, max_bezier_degree + 1>& shown) noexcept;
  // Steps every slice's along oscillator by dt under an along forcing linear over the step, per slice (slice 0,
  // pinned, stays at rest).
  static void step_along(Lattice& lattice, float dt, const std::array<float, max_bezier_degree + 1>& start,
                         const std::array<float, max_bezier_degree + 1>& end) noexcept;
  // The evaluation of a lattice's displacement field, added to `positions` by the points' weights.
  static LatticeEvaluateJob field_job(const Lattice& lattice, std::span<glm::vec3> positions);
  bool is_ancestor(std::int32_t ancestor, std::int32_t bone) const noexcept;

  std::vector<std::int32_t> bone_parents_;  // the skeleton's, per bone
  std::vector<Lattice> lattices_;
  mutable bool drawing_current_ = false;  // world_points as of the last update()
  std::size_t point_count_ = 0;           // the mesh's points, which apply() takes
};

}  // namespace deform
