// The Character facade: pose, reach (IK + elastic stretch), release, and the per-frame deformation.
#include "deform/character/character.hpp"
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "deform/offline/hierarchy_binding.hpp"
#include "deform/runtime/prefetch.hpp"
#include "finite.hpp"

namespace deform {
namespace {

// The largest target coordinate reach() takes: beyond, |target - effector|^2 overflows a float (about 3.4e38).
constexpr float max_reach_coordinate = 1e18f;

// Bones on the longest parent path, the root counted: 1 for a lone root.
std::size_t skeleton_depth(const Skeleton& skeleton) {
  std::vector<std::size_t> depth(skeleton.bone_count(), 1);
  std::size_t deepest = 0;
  for (const std::int32_t id : skeleton.order()) {
    const auto b = std::size_t(id);
    const std::int32_t parent = skeleton.bones()[b].parent;
    if (parent >= 0) depth[b] = depth[std::size_t(parent)] + 1;
    deepest = std::max(deepest, depth[b]);
  }
  return deepest;
}

SpringChains make_springs(const Model& model, const Rig& rig) {
  try {
    return SpringChains(model.skeleton, rig.spring_chains, rig.colliders, rig.spring_substep);
  } catch (const Error& error) {
    throw Error::in_file(model.name, "rig", error.message());
  }
}

// The checks set_pose makes of a pose.
Status check_pose(const Pose& pose, std::size_t bones) {
  if (pose.rotations.size() != bones || pose.translations.size() != bones)
    return Status::failure("pose does not have one entry per bone");
  for (std::size_t b = 0; b < bones; ++b) {
    const glm::quat q = pose.rotations[b];
    if (!finite(pose.translations[b]) || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) ||
        !std::isfinite(q.w)) {
      return Status::failure("pose is not finite");
    }
    if (!(glm::dot(q, q) > 1e-12f)) return Status::failure("pose has a zero rotation");
  }
  return {};
}

}  // namespace

Character::Character(Model model) : Character(std::move(model), Rig{}) {}

Character::Character(Model model, const Rig& rig)
    : bind_([&] {
        auto bind = std::make_shared<BindData>();
        bind->model = std::move(model);
        // The rig's corrective shapes join the model's morph targets (require_valid_morph_targets checks them below).
        for (const CorrectiveSpec& group : rig.correctives)
          for (const CorrectiveShape& shape : group.shapes)
            bind->model.morph_targets.push_back({shape.name, "", 0.0f, shape.points, shape.deltas, {}});
        bind->vertex_normals = bind_vertex_normals(bind->model.mesh);
        // The bind pose's angle-weighted normals, one per point (every render vertex of a point gets the same).
        const Mesh& mesh = bind->model.mesh;
        std::vector<glm::vec3> vertex_normals(mesh.vertex_count());
        std::vector<glm::vec4> scratch(bind->vertex_normals.scratch_size());
        VertexNormalsJob job;
        job.binding = &bind->vertex_normals;
        job.positions = mesh.positions;
        job.normals = vertex_normals;
        job.scratch = scratch;
        if (!job.run()) throw Error::in_file(bind->model.name, "mesh", "vertex normals refused the mesh");
        bind->point_normals.assign(mesh.point_count(), glm::vec3(0.0f));
        for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
          bind->point_normals[mesh.vertex_point[v]] = vertex_normals[v];
        }
        for (const Bone& bone : bind->model.skeleton.bones()) bind->limits.push_back(prepare_limits(bone.limits));
        bind->normals_in_place = mesh.point_count() <= mesh.vertex_count();
        if (bind->normals_in_place) bind->normals_gather = plan_in_place_gather(mesh.vertex_point, mesh.point_count());
        return std::shared_ptr<const BindData>(std::move(bind));
      }()),
      rig_(rig),
      hierarchy_(bind_hierarchy(bind_->model.skeleton, bind_->model.mesh.positions, bind_->model.weights, rig_.lattices,
                                bind_->model.name)),
      springs_(make_springs(bind_->model, rig_)),
      pose_(bind_->model.skeleton.bind_pose()),
      later_(pose_),
      work_(pose_) {
  const Model& bound = bind_->model;
  const auto bones = std::int32_t(bound.skeleton.bone_count());
  if (rig_.reach_effector >= bones || rig_.reach_root >= bones) {
    throw Error::in_file(bound.name, "rig", "reach bone out of range");
  }
  for (const Rig::ReachChain& chain : rig_.reach_chains) {
    if (chain.effector <= 0 || chain.effector >= bones || chain.root < 0 || chain.root >= bones ||
        chain.root == chain.effector || !bound.skeleton.is_ancestor(chain.root, chain.effector)) {
      throw Error::in_file(bound.name, "rig", "a reach chain's root must be a proper ancestor of its effector");
    }
  }
  if (!(rig_.max_stretch >= 0.0f) || !std::isfinite(rig_.max_stretch)) {
    throw Error::in_file(bound.name, "rig", "max_stretch must be finite and >= 0");
  }
  require_valid_morph_targets(bound.morph_targets, bound.mesh.point_count(), bound.name);
  for (const MorphTarget& target : bound.morph_targets) {
    if (!std::isfinite(target.default_weight)) {
      throw Error::in_file(bound.name, "morph target '" + target.name + "'", "default weight is not finite");
    }
  }
  forget_held_specs();
  allocate_frame_state();
  // Each corrective group's driver, over the morph targets its shapes became (the last ones, in the rig's order).
  std::size_t next_target = bound.morph_targets.size();
  for (const CorrectiveSpec& group : rig_.correctives) next_target -= group.shapes.size();
  for (const CorrectiveSpec& group : rig_.correctives) {
    std::vector<std::uint32_t> targets(group.shapes.size());
    for (std::uint32_t& t : targets) t = std::uint32_t(next_target++);
    if (const Status status = add_pose_driver(bind_corrective(group, bound.skeleton), targets); !status)
      throw Error::in_file(bound.name, "corrective group '" + group.name + "'", status.reason());
  }
  const SkinningJob job =
      skinning_job(bound.mesh.positions, bind_->point_normals, true, bound.weights, positions_, point_normals());
  if (!job.validate()) throw Error::in_file(bound.name, "weights", "skin weights do not fit the mesh and skeleton");
  if (const Status status = update(0.0f); !status) throw Error::in_file(bound.name, "bind pose", status.reason());
}

Character::Character(std::shared_ptr<const BindData> bind, const Rig& rig, const DeformerHierarchy& hierarchy)
    : bind_(std::move(bind)),
      rig_(rig),
      hierarchy_(hierarchy),
      springs_(make_springs(bind_->model, rig_)),
      pose_(bind_->model.skeleton.bind_pose()),
      later_(pose_),
      work_(pose_) {
  hierarchy_.reset();
  forget_held_specs();
  allocate_frame_state();
}

void Character::forget_held_specs() noexcept {
  rig_.lattices.clear();
  rig_.spring_chains.clear();
  rig_.colliders.clear();
}

Rig Character::rig() const {
  Rig whole = rig_;
  for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) whole.lattices.push_back(hierarchy_.spec(l));
  for (std::size_t c = 0; c < springs_.chain_count(); ++c) whole.spring_chains.push_back(springs_.spec(c));
  whole.colliders.assign(springs_.colliders().begin(), springs_.colliders().end());
  whole.spring_substep = springs_.substep();
  return whole;
}

void Character::allocate_frame_state() {
  const Model& bound = bind_->model;
  const std::size_t bones = bound.skeleton.bone_count();
  world_.assign(bones, glm::mat4(1.0f));
  world_later_.assign(bones, glm::mat4(1.0f));
  world_rate_.assign(bones, glm::mat4(0.0f));
  palette_.assign(bones, glm::mat4(1.0f));
  dual_quats_.assign(bones, DualQuat{});
  scales_.assign(bones, glm::mat3(1.0f));
  positions_ = bound.mesh.positions;
  // In place: one entry more, the gather's scratch (normals() shows the first vertex_count()).
  normals_.assign(bound.mesh.vertex_count() + (bind_->normals_in_place ? 1 : 0), glm::vec3(0.0f));
  if (bind_->normals_in_place) {
    std::copy(bind_->point_normals.begin(), bind_->point_normals.end(), normals_.begin());
  } else {
    point_normals_ = bind_->point_normals;
  }
  morph_weights_.clear();
  for (const MorphTarget& target : bound.morph_targets) morph_weights_.push_back(target.default_weight);
  if (!bound.morph_targets.empty()) {
    morphed_positions_ = bound.mesh.positions;
    morphed_normals_ = bind_->point_normals;
  }
  // reach()'s storage for the deepest chain any effector can have.
  const std::size_t depth = skeleton_depth(bound.skeleton);
  const std::size_t chain_bones = std::min(depth, max_chain_bones);
  chain_.bones.reserve(chain_bones);
  chain_.limits.reserve(chain_bones - 1);
  chain_.swing_twist.reserve(chain_bones - 1);
  chain_.ancestors.reserve(depth - 1);
  ik_scratch_.resize(IkJob::scratch_size(chain_bones - 1));
  chain_world_.resize(chain_bones);
  chain_lattices_.reserve(hierarchy_.lattice_count());
  stretched_.reserve(hierarchy_.lattice_count());
}

Character Character::instance() const {
  Character copy(bind_, rig(), hierarchy_);  // the spring chains made with their current settings
  copy.settings = settings;
  copy.set_normals_mode(normals_mode_);
  copy.direct_mush_ = direct_mush_;  // Direct Delta Mush: the binding shared (its job has no scratch)
  copy.reduced_mush_ = reduced_mush_;
  copy.drivers_ = drivers_;  // pose-space correctives: each driver shared, the weights' room this copy's own
  copy.mush_ = mush_;        // Delta Mush: the binding shared; the job's and the normals' scratch this copy's own
  if (mush_) {
    copy.mush_scratch_.resize(mush_scratch_.size());
    if (copy.normals_scratch_.empty()) copy.normals_scratch_.resize(bind_->vertex_normals.scratch_size());
  }
  if (levels_) {  // levels of detail: shared, at this character's level, the buffers this copy's own
    copy.levels_ = levels_;
    copy.allocate_level_state();
    copy.level_ = copy.shown_ = level_;
  }
  // The same update as this character's at construction, which succeeded on the same data.
  copy.update(0.0f);
  return copy;
}

std::span<glm::vec3> Character::point_normals() noexcept {
  if (bind_->normals_in_place) return std::span<glm::vec3>(normals_).first(bind_->model.mesh.point_count());
  return point_normals_;
}

void Character::set_normals_mode(NormalsMode mode) {
  if (mode == NormalsMode::recomputed && normals_scratch_.empty()) {
    normals_scratch_.resize(bind_->vertex_normals.scratch_size());
  }
  normals_mode_ = mode;
}

// Skeleton::clamp_to_limits on every bone, to float rounding, through the prepared limits: no trigonometric calls
// (they were a tenth of the whole frame). A rotation within its limits keeps its exact bits, as there.
void Character::clamp_pose(Pose& pose) const noexcept {
  for (std::size_t b = 0; b < pose.rotations.size(); ++b) {
    glm::quat rotation = pose.rotations[b];
    if (clamp_rotation(bind_->limits[b], rotation)) pose.rotations[b] = rotation;
  }
}

Status Character::set_pose(const Pose& pose) {
  const std::size_t bones = skeleton().bone_count();
  if (const Status status = check_pose(pose, bones); !status) return status;
  std::copy(pose.rotations.begin(), pose.rotations.end(), pose_.rotations.begin());
  std::copy(pose.translations.begin(), pose.translations.end(), pose_.translations.begin());
  clamp_pose(pose_);
  lead_ = 0.0f;
  return {};
}

Status Character::set_pose(const Pose& pose, const Pose& later, float lead) {
  const std::size_t bones = skeleton().bone_count();
  if (!(lead > 0.0f) || !std::isfinite(lead)) return Status::failure("lead is not finite and > 0");
  if (const Status status = check_pose(later, bones); !status) return Status::failure(status.reason());
  if (const Status status = set_pose(pose); !status) return status;
  std::copy(later.rotations.begin(), later.rotations.end(), later_.rotations.begin());
  std::copy(later.translations.begin(), later.translations.end(), later_.translations.begin());
  clamp_pose(later_);
  lead_ = lead;
  return {};
}

Status Character::set_morph_weight(std::size_t target, float weight) noexcept {
  if (target >= morph_weights_.size()) return Status::failure("morph target out of range");
  if (!std::isfinite(weight)) return Status::failure("morph weight is not finite");
  morph_weights_[target] = weight;
  return {};
}

Status Character::set_morph_weight(std::string_view name, float weight) noexcept {
  if (!std::isfinite(weight)) return Status::failure("morph weight is not finite");
  const std::vector<MorphTarget>& targets = model().morph_targets;
  bool found = false;
  for (std::size_t k = 0; k < targets.size(); ++k) {
    if (targets[k].name == name) morph_weights_[k] = weight, found = true;
  }
  return found ? Status{} : Status::failure("no morph target of that name");
}

Status Character::set_morph_weights(std::span<const float> weights) noexcept {
  if (weights.size() != morph_weights_.size()) return Status::failure("weights and morph targets differ in count");
  for (const float w : weights) {
    if (!std::isfinite(w)) return Status::failure("morph weight is not finite");
  }
  std::copy(weights.begin(), weights.end(), morph_weights_.begin());
  return {};
}

Status Character::set_morph_weights(const Animation& clip, float seconds) noexcept {
  // sample_morph_weights writes nothing when it refuses; the tracks were validated with the clip (finite keys).
  return sample_morph_weights(clip, seconds, morph_weights_);
}

void Character::reset_morph_weights() noexcept {
  const std::vector<MorphTarget>& targets = model().morph_targets;
  for (std::size_t k = 0; k < targets.size(); ++k) morph_weights_[k] = targets[k].default_weight;
}

// One reach's solve over work_: the CCD or FABRIK job, or the two-bone job (settings.reach_solver), and what they
// write. Its jobs point into it: set up in place by start_reach_solve, never moved.
struct Character::ReachSolve {
  bool two_bone = false;
  IkResult result;
  std::uint32_t random_state = ik_random_seed;  // one generator over every solve of this reach
  IkJob chain;
  TwoBoneIkJob limb;
  Status run() const noexcept { return two_bone ? limb.run() : chain.run(); }
  float tolerance() const noexcept { return chain.settings.tolerance; }
};

Status Character::refuse_reach(std::int32_t effector, glm::vec3 target) const noexcept {
  if (effector <= 0 || std::size_t(effector) >= skeleton().bone_count())
    return Status::failure("effector out of range or the root");
  if (!finite(target)) return Status::failure("target is not finite");
  if (glm::any(glm::greaterThan(glm::abs(target), glm::vec3(max_reach_coordinate))))
    return Status::failure("target is too far: beyond 1e18, distances to it overflow");
  return {};
}

// The root of the chain for a solver other than the two-bone one: the rig's root (reach_root, or the effector's
// entry in reach_chains), else the parent of the topmost lattice bone above the effector — that bone itself when its
// parent is the skeleton's root, which places the whole body (a leg's chain starts at the thigh, not the hips:
// turning the hips would spin the character to point the leg) — else two bones up.
std::int32_t Character::reach_chain_root(std::int32_t effector) const noexcept {
  const Skeleton& skel = skeleton();
  std::int32_t root = effector == rig_.reach_effector ? rig_.reach_root : -1;
  for (const Rig::ReachChain& chain : rig_.reach_chains)  // (a few entries: a rig's limbs)
    if (chain.effector == effector && effector != rig_.reach_effector) root = chain.root;
  if (root >= 0 && skel.is_ancestor(root, effector) && root != effector) return root;
  root = -1;
  for (std::int32_t b = skel.bone(effector).parent; b >= 0; b = skel.bone(b).parent) {
    for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) {
      if (hierarchy_.spec(l).bone == b) root = b;
    }
  }
  if (root > 0 && skel.bone(root).parent > 0) root = skel.bone(root).parent;
  if (root < 0) {
    root = skel.bone(effector).parent;
    if (skel.bone(root).parent >= 0) root = skel.bone(root).parent;
  }
  return root;
}

// chain_ for `effector` and the settings, rebuilt only for another effector or setting (its root depends on the
// effector alone): two bones up for the two-bone solver, else reach_chain_root.
Status Character::prepare_reach_chain(std::int32_t effector) {
  if (effector == chain_effector_ && settings.reach_limits == chain_limits_ && settings.reach_solver == chain_solver_)
    return {};
  const Skeleton& skel = skeleton();
  std::int32_t root = -1;
  if (settings.reach_solver == ReachSolver::two_bone) {
    root = skel.bone(effector).parent >= 0 ? skel.bone(skel.bone(effector).parent).parent : -1;
    if (root < 0) return Status::failure("the two-bone solver needs an effector two bones below another");
  } else {
    root = reach_chain_root(effector);
  }
  chain_effector_ = -1;
  if (const Status status = assign_chain(chain_, skel, root, effector); !status)
    return status;  // a chain longer than a solve takes
  chain_.swing_twist.clear();
  if (settings.reach_limits == JointLimits::swing_twist) {  // (capacity reserved at construction)
    chain_.swing_twist.resize(chain_.joint_count());
    for (std::size_t k = 0; k < chain_.joint_count(); ++k) {
      chain_.swing_twist[k] =
          swing_twist_from_euler(skel.bone(chain_.bones[k]).limits, skel.bone(chain_.bones[k + 1]).bind_translation);
      chain_.limits[k] = EulerLimits{};
    }
  }
  chain_limits_ = settings.reach_limits;
  chain_solver_ = settings.reach_solver;
  chain_effector_ = effector;
  return {};
}

// The lattices that stretch: on the chain above the effector, carrying it (their far face is behind it).
void Character::find_chain_lattices(std::int32_t effector) {
  const Skeleton& skel = skeleton();
  const std::int32_t root = chain_.bones.front();
  chain_lattices_.clear();
  const glm::vec3 effector_bind = glm::vec3(skel.bind_world()[std::size_t(effector)][3]);
  for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) {
    const LatticeSpec& spec = hierarchy_.spec(l);
    if (spec.bone == effector || !spec.carry_descendants || !skel.is_ancestor(root, spec.bone) ||
        !skel.is_ancestor(spec.bone, effector)) {
      continue;
    }
    const BezierLattice& rest = hierarchy_.rest_lattice(l);
    const glm::vec3 local = glm::vec3(skel.inverse_bind_world()[std::size_t(spec.bone)] * glm::vec4(effector_bind, 1));
    if (rest.frame().to_lattice(local).x < 1.0f - 1e-4f) continue;
    std::int32_t child = effector;
    while (skel.bone(child).parent != spec.bone) child = skel.bone(child).parent;
    chain_lattices_.push_back({l, child, rest.frame().u_axis / hierarchy_.length(l)});
  }
}

// Sets up `solve` over work_ for `target`; `continuing`: a reach held frame after frame, solved without the random
// restarts of the stall escape, so that the solution moves with its target instead of flipping between solutions.
Status Character::start_reach_solve(ReachSolve& solve, glm::vec3 target, float reach_length, bool continuing) {
  solve.two_bone = settings.reach_solver == ReachSolver::two_bone;
  IkJob& chain = solve.chain;
  chain.chain = &chain_;
  chain.rotations = work_.rotations;
  chain.translations = work_.translations;
  chain.target = target;
  chain.settings = settings.ik;
  chain.settings.tolerance = std::max(1e-5f * reach_length, 1e-7f);
  if (continuing) chain.settings.escape_stalls = false;
  chain.scratch = ik_scratch_;
  chain.random_state = &solve.random_state;
  chain.result = &solve.result;
  chain.pole = settings.reach_pole;
  chain.use_pole = settings.use_reach_pole;
  if (const Status status = chain_base(chain_, work_.rotations, work_.translations, chain.base); !status) return status;
  TwoBoneIkJob& limb = solve.limb;
  limb.chain = &chain_;
  limb.base = chain.base;
  limb.rotations = work_.rotations;
  limb.translations = work_.translations;
  limb.target = target;
  limb.tolerance = chain.settings.tolerance;
  limb.soften = settings.reach_soften;
  if (settings.use_reach_pole)
    limb.pole = settings.reach_pole, limb.pole_kind = PoleKind::point;  // else the pose's bend plane
  limb.result = &solve.result;
  return {};
}

// The effector's motion per unit λ of stretch: each chain lattice's axis carried by its bone's model-space matrix,
// the product of the local matrices down the chain (as LocalToWorldJob multiplies them), in chain_world_.
glm::vec3 Character::stretch_growth() noexcept {
  glm::mat4 model(1.0f);
  bool first = true;
  auto descend = [&](std::int32_t bone) {
    const glm::mat4 local = local_matrix(work_.rotations[std::size_t(bone)], work_.translations[std::size_t(bone)]);
    model = first ? local : model * local;
    first = false;
  };
  for (const std::int32_t bone : chain_.ancestors) descend(bone);
  for (std::size_t k = 0; k < chain_.joint_count(); ++k) {
    descend(chain_.bones[k]);
    chain_world_[k] = model;
  }
  glm::vec3 growth(0.0f);
  for (const Stretched& s : chain_lattices_) {
    const std::int32_t bone = hierarchy_.spec(s.lattice).bone;
    std::size_t k = 0;
    while (chain_.bones[k] != bone) ++k;  // a joint: the root is an ancestor of the bone, the bone of the effector
    growth += glm::mat3(chain_world_[k]) * (s.axis * hierarchy_.length(s.lattice));
  }
  return growth;
}

// Stretch λ·length_L on every chain lattice, λ fitted to the remaining gap, then IK again with the longer chain; at
// most 16 rounds. The stretch moves only chain bones below the root, so the base stays. Returns λ; sets
// result.distance and counts result.iterations.
float Character::stretch_to_target(ReachSolve& solve, glm::vec3 target, ReachResult& result) {
  float lambda = 0.0f;
  float distance = solve.result.distance;
  for (int round = 0;
       round < 16 && !chain_lattices_.empty() && distance > 1e-3f * result.residual && distance > solve.tolerance();
       ++round) {
    const glm::vec3 growth = stretch_growth();
    const float growth2 = glm::dot(growth, growth);
    if (!(growth2 > 0.0f)) break;
    glm::vec3 reached(0.0f);
    if (!effector_position(chain_, work_.rotations, work_.translations, reached)) break;  // spans fit: made for it
    const glm::vec3 gap = target - reached;
    const float next = std::clamp(lambda + glm::dot(gap, growth) / growth2, 0.0f, rig_.max_stretch);
    if (next == lambda && round > 0) break;
    lambda = next;
    for (const Stretched& s : chain_lattices_) {
      work_.translations[std::size_t(s.child)] = pose_.translations[std::size_t(s.child)];
    }
    for (const Stretched& s : chain_lattices_) {  // (two lattices on one bone both push its child)
      work_.translations[std::size_t(s.child)] += s.axis * (lambda * hierarchy_.length(s.lattice));
    }
    if (!solve.run()) break;
    distance = solve.result.distance;
    ++result.iterations;
  }
  result.distance = distance;
  return lambda;
}

// The solved pose becomes the pose, keeping the IK rotations; the lattices, not the bones, carry the stretch λ.
void Character::hold_reach(std::int32_t effector, float lambda, bool continuing, ReachResult& result) {
  for (const Stretched& s : chain_lattices_) {
    work_.translations[std::size_t(s.child)] = pose_.translations[std::size_t(s.child)];
  }
  std::swap(pose_, work_);
  // The reached joints hold still relative to their parents: the later pose's motion of them is the body's.
  for (const std::int32_t bone : chain_.bones) later_.rotations[std::size_t(bone)] = pose_.rotations[std::size_t(bone)];
  for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) hierarchy_.set_stretch_target(l, 0.0f);
  stretched_.clear();
  for (const Stretched& s : chain_lattices_) {
    hierarchy_.set_stretch_target(s.lattice, lambda * hierarchy_.length(s.lattice));
    stretched_.push_back(s.lattice);
    result.stretch += lambda * hierarchy_.length(s.lattice);
  }
  effector_ = effector;
  if (!continuing) jumped_root_ = chain_.bones.front();  // the limb snaps to the reach: a jump, not a motion
  reaching_ = true;
}

ReachResult Character::reach(std::int32_t effector, glm::vec3 target) {
  ReachResult result;
  if (const Status refused = refuse_reach(effector, target); !refused) {
    result.status = refused;
    return result;
  }
  if (const Status status = prepare_reach_chain(effector); !status) {
    result.status = status;
    return result;
  }
  find_chain_lattices(effector);
  std::copy(pose_.rotations.begin(), pose_.rotations.end(), work_.rotations.begin());
  std::copy(pose_.translations.begin(), pose_.translations.end(), work_.translations.begin());
  const float reach_length = chain_length(chain_, work_.translations);
  // A reach held frame after frame: the same effector, not released, the target within a tenth of the chain's
  // length of the last one.
  const bool continuing =
      reaching_ && effector == effector_ && glm::length(target - reach_target_) <= 0.1f * reach_length;
  reach_target_ = target;
  ReachSolve solve;
  if (const Status status = start_reach_solve(solve, target, reach_length, continuing); !status) {
    result.status = status;
    return result;
  }
  if (const Status status = solve.run(); !status) {
    result.status = status;
    return result;
  }
  result.residual = solve.result.distance;
  result.iterations = 1;
  const float lambda = stretch_to_target(solve, target, result);
  hold_reach(effector, lambda, continuing, result);
  return result;
}

Status Character::set_max_stretch(float max_stretch) noexcept {
  if (!(max_stretch >= 0.0f && max_stretch <= 1000.0f)) return Status::failure("max_stretch not within [0, 1000]");
  rig_.max_stretch = max_stretch;
  return {};
}

void Character::release() {
  for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) hierarchy_.set_stretch_target(l, 0.0f);
  if (reaching_ && !chain_.bones.empty()) jumped_root_ = chain_.bones.front();  // the next pose may snap back
  reaching_ = false;
}

void Character::prefetch_record() const noexcept { prefetch_bytes(this, sizeof(*this)); }

bool Character::next_update_deforms() const noexcept {
  if (!levels_ || !settings.deform_on_cpu) return true;
  const std::uint32_t interval = levels_->costs[level_].update_interval;
  return !(interval > 1 && shown_ == level_ && tick_ + 1 < interval && approach_left_ > 0);
}

void Character::prefetch() const noexcept {
  // An update that only interpolates streams the points and touches none of this.
  if (!next_update_deforms()) return;
  prefetch_span(pose_.rotations);
  prefetch_span(pose_.translations);
  prefetch_span(world_);
  prefetch_span(palette_);
  if (lead_ > 0.0f) {
    prefetch_span(later_.rotations);
    prefetch_span(later_.translations);
    prefetch_span(world_later_);
    prefetch_span(world_rate_);
  }
  if (levels_ && !levels_->costs[level_].deformers) return;
  springs_.prefetch();
  if (runs_lattices(level_)) hierarchy_.prefetch();
}

// The skinning job of this character's weights and palette, from `rest_positions` (and, transporting, their normals)
// into positions_ and point_normals(); the method and DQS palette are the caller's. No allocation.
SkinningJob Character::skinning_job(std::span<const glm::vec3> rest_positions, std::span<const glm::vec3> rest_normals,
                                    bool transport, const SkinWeights& weights, std::span<glm::vec3> out_positions,
                                    std::span<glm::vec3> out_normals) noexcept {
  SkinningJob job;
  job.matrices = palette_;
  job.bone_indices = weights.bones;
  job.bone_weights = weights.weights;
  job.extra_vertices = weights.extra_points;
  job.extra_offsets = weights.extra_offsets;
  job.extra_bones = weights.extra_bones;
  job.extra_weights = weights.extra_weights;
  job.in_positions = as_floats(rest_positions);
  job.out_positions = as_floats(out_positions);
  if (transport) {
    job.in_normals = as_floats(rest_normals);
    job.out_normals = as_floats(out_normals);
  }
  return job;
}

// LBS or DQS (settings.skinning) of the (morphed) bind points and, transporting, their normals into positions_ and
// point_normals(). No allocation.
Status Character::skin(std::span<const glm::vec3> rest_positions, std::span<const glm::vec3> rest_normals,
                       bool transport, const SkinWeights& weights, std::span<glm::vec3> out_positions,
                       std::span<glm::vec3> out_normals) noexcept {
  SkinningJob job = skinning_job(rest_positions, rest_normals, transport, weights, out_positions, out_normals);
  job.method = settings.skinning;
  if (settings.skinning == SkinningMethod::dqs) {
    bool has_scale = false;
    if (!compute_dual_quat_palette(palette_, dual_quats_, scales_, has_scale))
      return Status::failure("skinning palette is singular or not finite");
    job.dual_quats = dual_quats_;
    if (has_scale) job.scales = scales_;
  }
  return job.run();
}

Status Character::skin_subset(std::size_t level) noexcept {
  const LevelPoints& subset = levels_->subsets[level];
  const std::size_t count = subset.points.size();
  std::span<const glm::vec3> rest_positions = subset.rest_positions;
  std::span<const glm::vec3> rest_normals = subset.rest_normals;
  if (morphed_) {
    // The subset's points (and bind normals, transported) of the morphed bind arrays.
    const std::span<glm::vec3> positions = std::span<glm::vec3>(level_rest_).first(count);
    const std::span<glm::vec3> normals = std::span<glm::vec3>(level_rest_).subspan(count, count);
    for (std::size_t i = 0; i < count; ++i) {
      positions[i] = morphed_positions_[subset.points[i]];
      normals[i] = morphed_normals_[subset.points[i]];
    }
    rest_positions = positions;
    rest_normals = normals;
  }
  // A range of points is skinned in place; scattered ones through level_positions_.
  const std::span<glm::vec3> out = subset.contiguous
                                       ? std::span<glm::vec3>(positions_).subspan(subset.points.front(), count)
                                       : std::span<glm::vec3>(level_positions_).first(count);
  const std::span<glm::vec3> normals = std::span<glm::vec3>(subset.normals_in_place ? normals_ : level_normals_);
  if (const Status status =
          skin(rest_positions, rest_normals, true, levels_->weights[level], out, normals.first(count));
      !status)
    return status;
  if (!subset.contiguous)
    for (std::size_t i = 0; i < count; ++i) positions_[subset.points[i]] = out[i];
  subset_normals_ = std::int32_t(level);
  return {};
}

// f(p) for each point of `level`: all of them, or its subset's (the others are not drawn and keep stale values).
template <class F>
void Character::for_each_point(std::size_t level, F&& f) const {
  const LevelPoints& subset = levels_->subsets[level];
  if (subset.points.empty()) {
    for (std::size_t p = 0; p < positions_.size(); ++p) f(p);
  } else if (subset.contiguous) {
    const std::size_t begin = subset.points.front(), end = begin + subset.points.size();
    for (std::size_t p = begin; p < end; ++p) f(p);
  } else {
    for (const std::uint32_t p : subset.points) f(std::size_t(p));
  }
}

// The frame shown by a renderer interpolation in progress, made the CPU's again: positions_ (its `from`) becomes that
// frame, as update() would have moved it (the points of `level`, or all). A frame shown whole (share 1) is `to`
// itself: the buffers swap, nothing is copied. O(points) unless the share is 1 or 0.
void Character::settle_interpolation(std::size_t level) noexcept {
  if (!lerp_) return;
  lerp_ = false;
  if (approach_left_ == 0) {
    std::swap(positions_, target_);
    std::swap(positions_version_, target_version_);
    return;
  }
  const std::uint32_t done = lerp_span_ - approach_left_;
  if (done == 0) return;
  const float share = float(done) / float(lerp_span_);
  for_each_point(level, [&](std::size_t p) { positions_[p] += share * (target_[p] - positions_[p]); });
  positions_version_ = ++version_counter_;
}

Status Character::update(float dt) {
  if (!(dt >= 0.0f) || !std::isfinite(dt)) return Status::failure("dt is negative or not finite");
  if (!levels_) {
    positions_version_ = ++version_counter_;
    return deform_frame(dt, 0);
  }
  if (!settings.deform_on_cpu) {
    // Posing only: no points to blend or interpolate; positions() keeps the frame shown last.
    settle_interpolation(shown_);
    shown_ = level_;
    approach_left_ = 0;
    blend_left_ = 0;
    return deform_frame(dt, level_);
  }
  const LevelCost& cost = levels_->costs[level_];
  const std::uint32_t interval = cost.update_interval;
  bool from_changed = false;  // a deformed update's `from` is not the last `to` as it was (interpolation())
  if (!next_update_deforms()) {
    // Between deformed updates: the time adds up for the next one, positions() goes a share of the way on (below).
    ++tick_;
    pending_dt_ += dt;
  } else {
    // The CPU's state again (positions_ the frame shown last): the renderer's interpolation, if any, settled.
    const std::uint64_t shown_version = lerp_ && approach_left_ == 0 ? target_version_ : 0;
    settle_interpolation(shown_);
    from_changed = shown_version == 0 || positions_version_ != shown_version;
    const float step = dt + pending_dt_;
    tick_ = 0;
    pending_dt_ = 0.0f;
    const std::size_t outgoing = shown_;
    const bool switching = outgoing != level_;
    from_changed = from_changed || switching;
    // Deformers that come back on start again from the pose: the spring chains after a level without deformers, the
    // lattices after one without them or with a point subset (which runs the springs only).
    const bool restart_springs = switching && !levels_->costs[outgoing].deformers && cost.deformers;
    const bool restart_lattices = switching && !runs_lattices(outgoing) && runs_lattices(level_);
    // The outgoing level interpolates, behind the pose by up to its interval: the blend starts where positions()
    // would have gone this update, not from that level's points at the pose (a jump of a few updates' motion).
    const bool from_shown = switching && levels_->costs[outgoing].update_interval > 1;
    if (from_shown) {
      const float share = approach_left_ > 0 ? 1.0f / float(approach_left_) : 0.0f;
      for_each_point(level_, [&](std::size_t p) { blend_[p] = positions_[p] + share * (target_[p] - positions_[p]); });
    }
    approach_left_ = 0;
    // Deform into target_ when the level interpolates, into positions_ (what positions() shows) otherwise.
    const bool approach = interval > 1;
    if (approach) std::swap(positions_, target_);
    Status status;
    if (switching && !from_shown) {
      // The frame at the outgoing level (the whole step) is the blend's start; the new level then takes no more time.
      status = deform_frame(step, outgoing);
      if (status) for_each_point(level_, [&](std::size_t p) { blend_[p] = positions_[p]; });
    }
    if (status && restart_lattices)  // as they are after a cut
      for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) (void)hierarchy_.restart_motion(l);
    if (status && restart_springs)
      for (std::size_t c = 0; c < springs_.chain_count(); ++c) (void)springs_.restart(c);
    if (status) status = deform_frame(switching && !from_shown ? 0.0f : step, level_);
    if (status && switching) {
      // A point new to the level was not drawn: no offset, it starts at its new place.
      for_each_point(level_, [&](std::size_t p) {
        blend_[p] = level_has(outgoing, p) ? blend_[p] - positions_[p] : glm::vec3(0.0f);
      });
      blend_left_ = levels_->blend_frames;
    }
    shown_ = level_;
    if (status && blend_left_ > 0) {
      // The switch's offset, shrinking linearly: all of it on the switch's update, none after blend_frames.
      const float share = float(blend_left_) / float(levels_->blend_frames);
      for_each_point(level_, [&](std::size_t p) { positions_[p] += share * blend_[p]; });
      --blend_left_;
    }
    if (approach) std::swap(positions_, target_);
    target_version_ = ++version_counter_;  // approach or not: the deformed points, positions_'s when not
    if (!status) return status;
    if (approach && switching) {
      // Interpolating, a point new to the level starts at its deformed place too, not on its way from a stale one.
      for_each_point(level_, [&](std::size_t p) {
        if (!level_has(outgoing, p)) positions_[p] = target_[p];
      });
    }
    approach_left_ = approach ? interval : 0;
  }
  if (approach_left_ > 0 && settings.renderer_interpolates) {
    // The renderer draws from + share · (to − from): no point moves here. A deformed update (or the opt-in taken
    // up between them) starts from the frame shown now, `approach_left_` updates from the last deformed points.
    if (!lerp_) {
      lerp_ = true;
      lerp_span_ = approach_left_;
      if (from_changed) positions_version_ = ++version_counter_;
    }
    --approach_left_;
    return {};
  }
  settle_interpolation(shown_);  // the opt-in given up between deformed updates: the CPU moves the points again
  if (approach_left_ > 0) {
    // Piecewise linear toward the last deformed points: 1 / approach_left_ of the way that remains.
    const float share = 1.0f / float(approach_left_);
    for_each_point(shown_, [&](std::size_t p) { positions_[p] += share * (target_[p] - positions_[p]); });
    --approach_left_;
  }
  positions_version_ = ++version_counter_;
  return {};
}

// One frame of the held pose at `level` (update()'s work, see the top of character.hpp).
Status Character::deform_frame(float dt, std::size_t level) {
  const bool deformers = !levels_ || levels_->costs[level].deformers;
  const bool lattices = runs_lattices(level);  // false on a point subset: the spring chains alone (LevelOptions)
  const SkinWeights& weights = levels_ ? levels_->weights[level] : bind_->model.weights;
  // A crowd's characters are cold when their update starts: ask for every small array at once, so that their
  // first lines arrive together rather than one wait each (the large per-point arrays the streaming hardware
  // prefetcher fetches well once skinning runs through them).
  prefetch();
  const Model& bound = bind_->model;
  const Skeleton& skel = bound.skeleton;
  LocalToWorldJob fk;
  fk.skeleton = &skel;
  fk.rotations = pose_.rotations;
  fk.translations = pose_.translations;
  fk.world = world_;
  fk.palette = palette_;
  if (const Status status = fk.run(); !status) return status;
  // The bones' velocities, from the pose a moment later (set_pose with a lead), for the springs that feel motion.
  std::span<const glm::mat4> rate;
  if (lead_ > 0.0f) {
    fk.rotations = later_.rotations;
    fk.translations = later_.translations;
    fk.world = world_later_;
    fk.palette = {};
    if (const Status status = fk.run(); !status) return status;
    for (std::size_t b = 0; b < world_.size(); ++b) world_rate_[b] = (world_later_[b] - world_[b]) / lead_;
    rate = world_rate_;
  }
  if (jumped_root_ >= 0) {
    // A reach that started or ended moved its limb at once: the lattices and spring chains there start again from
    // the pose as it is, rather than feeling the snap as motion.
    for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l)
      if (skel.is_ancestor(jumped_root_, hierarchy_.spec(l).bone)) (void)hierarchy_.restart_motion(l);  // in range
    for (std::size_t c = 0; c < springs_.chain_count(); ++c)
      if (skel.is_ancestor(jumped_root_, springs_.spec(c).bones.front())) (void)springs_.restart(c);
    jumped_root_ = -1;
  }
  if (deformers)
    if (const Status status = springs_.run(dt, world_, rate, palette_); !status) return status;
  if (lattices)
    if (const Status status = hierarchy_.step(dt, world_, rate); !status) return status;
  // Pose-space correctives: each driver's weights become its shapes' morph weights (validated when it was added),
  // before the early return below, so that a caller deforming elsewhere morphs with them too.
  for (Driven& driven : drivers_) {
    PoseDriverJob drive;
    drive.binding = driven.binding.get();
    drive.rotations = pose_.rotations;
    drive.weights = driven.weights;
    if (const Status status = drive.run(); !status) return status;
    for (std::size_t s = 0; s < driven.targets.size(); ++s) morph_weights_[driven.targets[s]] = driven.weights[s];
  }
  // Posing only: the deformation is the caller's (a GPU), from palette_ and the hierarchy's state.
  if (!settings.deform_on_cpu) return lattices ? hierarchy_.update(world_) : Status();
  // A subset level transports its normals whatever the mode (LevelOptions::points).
  const bool subset = levels_ && !levels_->subsets[level].points.empty();
  const bool transport = normals_mode_ == NormalsMode::transported || subset;
  // Morph targets, in bind space before skinning; skipped (the bind arrays skinned directly) when every weight is 0.
  std::span<const glm::vec3> rest_positions = bound.mesh.positions;
  std::span<const glm::vec3> rest_normals = bind_->point_normals;
  morphed_ = std::any_of(morph_weights_.begin(), morph_weights_.end(), [](float w) { return w != 0.0f; });
  if (morphed_) {
    MorphJob morph;
    morph.targets = bound.morph_targets;
    morph.weights = morph_weights_;
    morph.rest_positions = bound.mesh.positions;
    morph.out_positions = morphed_positions_;
    if (transport) {
      morph.rest_normals = bind_->point_normals;
      morph.out_normals = morphed_normals_;
      rest_normals = morphed_normals_;
    }
    if (const Status status = morph.run(); !status) return status;
    rest_positions = morphed_positions_;
  }
  normals_current_ = false;
  transported_current_ = false;
  subset_normals_ = -1;
  if (subset) return skin_subset(level);  // the spring chains moved its bones above; no lattices or mushes
  if (direct_mush_ && deformers && level == 0) {
    // Direct Delta Mush in place of settings.skinning: the morphed points' offsets from the rest points turn with
    // their points, and so do the transported normals (the rotation of each point's smoothed neighbourhood).
    DirectDeltaMushJob ddm;
    ddm.binding = direct_mush_.get();
    ddm.matrices = palette_;
    if (morphed_) ddm.in_positions = rest_positions;
    ddm.out_positions = positions_;
    if (transport) {
      ddm.in_normals = rest_normals;
      ddm.out_normals = point_normals();
    }
    if (const Status status = ddm.run(); !status) return status;
  } else if (reduced_mush_ && deformers && level == 0) {
    // The reduced form alike, with the bones' rotations from the DQS palette of the same matrices.
    bool has_scale = false;
    if (const Status status = compute_dual_quat_palette(palette_, dual_quats_, scales_, has_scale); !status)
      return status;
    DirectDeltaMushReducedJob ddm;
    ddm.binding = reduced_mush_.get();
    ddm.matrices = palette_;
    ddm.dual_quats = dual_quats_;
    if (morphed_) ddm.in_positions = rest_positions;
    ddm.out_positions = positions_;
    if (transport) {
      ddm.in_normals = rest_normals;
      ddm.out_normals = point_normals();
    }
    if (const Status status = ddm.run(); !status) return status;
  } else if (const Status status = skin(rest_positions, rest_normals, transport, weights, positions_, point_normals());
             !status) {
    return status;
  }
  if (!deformers) {
    transported_current_ = transport;
    return {};
  }
  if (const Status status = hierarchy_.update(world_); !status) return status;
  if (!settings.lattice_fields) {
    // The carried points only translate: their normals stay as skinned.
    if (const Status status = hierarchy_.apply_carried(positions_); !status) return status;
  } else if (const Status status =
                 transport ? hierarchy_.apply(positions_, point_normals()) : hierarchy_.apply(positions_);
             !status) {
    return status;
  }
  if (mush_ && settings.lattice_fields) {
    // Delta Mush after the lattices, in place; the normals are then recomputed from the mushed points.
    DeltaMushJob mush;
    mush.binding = mush_.get();
    mush.in_positions = positions_;
    mush.out_positions = positions_;
    mush.scratch = mush_scratch_;
    if (const Status status = mush.run(); !status) return status;
    return {};
  }
  transported_current_ = transport;
  return {};
}

void Character::set_delta_mush(const DeltaMushSettings& mush) {
  auto binding = std::make_shared<const DeltaMushBinding>(bind_delta_mush(bind_->model.mesh, mush));
  if (binding->iterations == 0) return clear_delta_mush();
  std::vector<glm::vec4> scratch(DeltaMushJob::scratch_size(*binding));
  if (normals_scratch_.empty()) normals_scratch_.resize(bind_->vertex_normals.scratch_size());
  mush_ = std::move(binding);
  mush_scratch_ = std::move(scratch);
}

void Character::set_direct_delta_mush(const DirectDeltaMushSettings& ddm) {
  auto binding = std::make_shared<const DirectDeltaMushBinding>(
      bind_direct_delta_mush(bind_->model.mesh, bind_->model.weights, ddm));
  if (ddm.variant == DirectDeltaMushVariant::reduced) {
    auto reduced = std::make_shared<DirectDeltaMushReducedBinding>();
    if (const Status status = reduce_direct_delta_mush(*binding, *reduced); !status)
      throw Error::invalid_argument("direct delta mush", status.reason());
    // Checked once here, as below; the DQS palette's rotations are identities until update() computes them.
    DirectDeltaMushReducedJob job;
    job.binding = reduced.get();
    job.matrices = palette_;
    job.dual_quats = dual_quats_;
    job.out_positions = positions_;
    if (const Status status = job.validate(); !status)
      throw Error::invalid_argument("direct delta mush", status.reason());
    direct_mush_.reset();
    reduced_mush_ = std::move(reduced);
    return;
  }
  // Checked once here, so that update() cannot refuse it: the palette is the skeleton's, the spans one per point.
  DirectDeltaMushJob job;
  job.binding = binding.get();
  job.matrices = palette_;
  job.out_positions = positions_;
  if (const Status status = job.validate(); !status)
    throw Error::invalid_argument("direct delta mush", status.reason());
  reduced_mush_.reset();
  direct_mush_ = std::move(binding);
}

void Character::clear_direct_delta_mush() noexcept {
  direct_mush_.reset();
  reduced_mush_.reset();
}

Status Character::add_pose_driver(const PoseDriverBinding& driver, std::span<const std::uint32_t> targets) {
  std::vector<float> weights(driver.shape_count);
  PoseDriverJob job;
  job.binding = &driver;
  job.rotations = pose_.rotations;
  job.weights = weights;
  if (const Status status = job.validate(); !status) return status;
  if (targets.size() != driver.shape_count) return Status::failure("targets are not one per shape");
  for (const std::uint32_t t : targets)
    if (t >= morph_weights_.size()) return Status::failure("morph target out of range");
  drivers_.push_back(
      {std::make_shared<const PoseDriverBinding>(driver), {targets.begin(), targets.end()}, std::move(weights)});
  return Status();
}

void Character::clear_pose_drivers() noexcept { drivers_.clear(); }

void Character::clear_delta_mush() noexcept {
  mush_.reset();
  mush_scratch_.clear();
}

std::span<const glm::vec3> Character::normals() {
  if (!normals_current_) {
    if (subset_normals_ >= 0) {
      // A subset level: its render vertices only (the others keep stale values; LevelOptions::points).
      const LevelPoints& subset = levels_->subsets[std::size_t(subset_normals_)];
      const std::vector<glm::vec3>& skinned = subset.normals_in_place ? normals_ : level_normals_;
      for (std::size_t i = subset.normals_in_place ? subset.points.size() : 0; i < subset.vertices.size(); ++i)
        normals_[subset.vertices[i]] = skinned[subset.vertex_slot[i]];
    } else if (transported_current_ && bind_->normals_in_place) {
      InPlaceGatherJob gather;
      gather.plan = &bind_->normals_gather;
      gather.values = normals_;
      gather.run();  // cannot refuse: the plan was made for this mesh, normals_ sized by it
    } else if (transported_current_) {
      const std::vector<std::uint32_t>& vertex_point = bind_->model.mesh.vertex_point;
      for (std::size_t v = 0; v < vertex_point.size(); ++v) normals_[v] = point_normals_[vertex_point[v]];
    } else if (!normals_scratch_.empty()) {
      VertexNormalsJob job;
      job.binding = &bind_->vertex_normals;
      job.positions = positions();  // the last deformed points, while the renderer interpolates
      job.normals = std::span<glm::vec3>(normals_).first(bind_->model.mesh.vertex_count());
      job.scratch = normals_scratch_;
      job.run();
    }
    normals_current_ = true;
  }
  return std::span<const glm::vec3>(normals_).first(bind_->model.mesh.vertex_count());
}

void Character::set_levels(const BoneLod& lod, std::span<const LevelOptions> options, std::uint32_t blend_frames) {
  const Model& bound = bind_->model;
  const std::size_t point_count = bound.mesh.point_count();
  if (lod.levels.empty()) throw Error::invalid_argument("level 0", "no levels");
  if (lod.levels.size() != options.size())
    throw Error::invalid_argument("level " + std::to_string(std::min(lod.levels.size(), options.size())),
                                  "levels and options differ in count");
  if (blend_frames > 1000) throw Error::invalid_argument("blend_frames", "more than 1000");
  auto data = std::make_shared<LevelData>();
  data->blend_frames = blend_frames;
  for (std::size_t l = 0; l < lod.levels.size(); ++l) {
    const std::string element = "level " + std::to_string(l);
    const BoneLodLevel& level = lod.levels[l];
    if (options[l].update_interval < 1 || options[l].update_interval > 64)
      throw Error::invalid_argument(element, "update_interval must be in [1, 64]");
    // Checked once here, so that update() cannot refuse it (the palette is the skeleton's).
    SkinningJob job = skinning_job(bound.mesh.positions, bind_->point_normals, false, level.weights, positions_, {});
    if (level.weights.size() != point_count) throw Error::invalid_argument(element, "skin is not one entry per point");
    if (const Status status = job.validate(); !status) throw Error::invalid_argument(element, status.reason());
    LevelPoints subset;
    SkinWeights weights;
    if (options[l].points.empty()) {
      weights = level.weights;
    } else {
      subset.member.assign(point_count, 0);
      for (const std::uint32_t p : options[l].points) {
        if (p >= point_count) throw Error::invalid_argument(element, "point " + std::to_string(p) + " out of range");
        if (subset.member[p]) throw Error::invalid_argument(element, "point " + std::to_string(p) + " listed twice");
        subset.member[p] = 1;
      }
      // Ascending, for the skinning's and the scatter's memory order; the skin, bind points and normals gathered.
      for (std::uint32_t p = 0; p < point_count; ++p)
        if (subset.member[p]) subset.points.push_back(p);
      subset.contiguous = subset.points.back() - subset.points.front() + 1 == subset.points.size();
      std::vector<std::uint32_t> slot(point_count, 0);
      for (std::size_t i = 0; i < subset.points.size(); ++i) {
        const std::uint32_t p = subset.points[i];
        slot[p] = std::uint32_t(i);
        weights.bones.push_back(level.weights.bones[p]);
        weights.weights.push_back(level.weights.weights[p]);
        subset.rest_positions.push_back(bound.mesh.positions[p]);
        subset.rest_normals.push_back(bind_->point_normals[p]);
        const auto extra = std::lower_bound(level.weights.extra_points.begin(), level.weights.extra_points.end(), p);
        if (extra != level.weights.extra_points.end() && *extra == p) {
          const std::size_t j = std::size_t(extra - level.weights.extra_points.begin());
          if (weights.extra_offsets.empty()) weights.extra_offsets.push_back(0);
          weights.extra_points.push_back(std::uint32_t(i));
          for (std::uint32_t k = level.weights.extra_offsets[j]; k < level.weights.extra_offsets[j + 1]; ++k) {
            weights.extra_bones.push_back(level.weights.extra_bones[k]);
            weights.extra_weights.push_back(level.weights.extra_weights[k]);
          }
          weights.extra_offsets.push_back(std::uint32_t(weights.extra_bones.size()));
        }
      }
      const std::vector<std::uint32_t>& vertex_point = bound.mesh.vertex_point;
      for (std::size_t v = 0; v < vertex_point.size(); ++v) {
        if (!subset.member[vertex_point[v]]) continue;
        subset.vertices.push_back(std::uint32_t(v));
        subset.vertex_slot.push_back(slot[vertex_point[v]]);
      }
      data->largest_subset = std::max(data->largest_subset, subset.points.size());
      // In place when subset point i is vertex i's: the seams' vertices come after them all (vertices ascending).
      bool own = subset.vertices.size() >= subset.points.size();
      for (std::size_t i = 0; own && i < subset.points.size(); ++i)
        own = subset.vertices[i] == i && subset.vertex_slot[i] == i;
      subset.normals_in_place = own;
      if (!own) data->largest_scattered_subset = std::max(data->largest_scattered_subset, subset.points.size());
    }
    LevelCost cost;
    cost.points = weights.size();
    cost.influences = 0;
    for (std::size_t p = 0; p < cost.points; ++p) cost.influences += influence_count(weights, p);
    std::vector<bool> used(bound.skeleton.bone_count(), false);
    for (std::size_t p = 0; p < cost.points; ++p)
      for (int k = 0; k < 4; ++k)
        if (weights.weights[p][k] > 0.0f) used[weights.bones[p][k]] = true;
    for (const std::uint16_t b : weights.extra_bones) used[b] = true;
    cost.bones = std::size_t(std::count(used.begin(), used.end(), true));
    cost.deformers = options[l].deformers;
    cost.update_interval = options[l].update_interval;
    data->weights.push_back(std::move(weights));
    data->costs.push_back(cost);
    data->subsets.push_back(std::move(subset));
  }
  settle_interpolation(shown_);  // the frame shown stays, at the outgoing levels' numbering
  levels_ = std::move(data);
  allocate_level_state();
}

// The per-character state of the levels (set_levels, instance()): the blend and interpolation buffers, a subset
// level's skinned points and normals, and its gathered morphed rest points; at level 0's start, or as instance() copies
// it, at the level this character asks for.
void Character::allocate_level_state() {
  const std::size_t subset = levels_->largest_subset;
  blend_.assign(positions_.size(), glm::vec3(0.0f));
  target_ = positions_;
  target_version_ = positions_version_;
  lerp_ = false;
  level_positions_.assign(subset, glm::vec3(0.0f));
  level_normals_.assign(levels_->largest_scattered_subset, glm::vec3(0.0f));
  level_rest_.assign(morph_weights_.empty() ? 0 : 2 * subset, glm::vec3(0.0f));
  subset_normals_ = -1;
  level_ = shown_ = 0;
  tick_ = 0;
  pending_dt_ = 0.0f;
  blend_left_ = approach_left_ = 0;
}

std::size_t Character::level_count() const noexcept { return levels_ ? levels_->costs.size() : 1; }

Status Character::set_level(std::size_t level) noexcept {
  if (level >= level_count()) return Status::failure("level out of range");
  level_ = level;
  return {};
}

Character::LevelCost Character::level_cost(std::size_t level) const noexcept {
  if (levels_) return level < levels_->costs.size() ? levels_->costs[level] : LevelCost{0, 0, 0, false, 0};
  if (level != 0) return {0, 0, 0, false, 0};
  const Model& bound = bind_->model;
  LevelCost cost;
  cost.points = bound.mesh.point_count();
  for (std::size_t p = 0; p < cost.points; ++p) cost.influences += influence_count(bound.weights, p);
  cost.bones = bound.skeleton.bone_count();
  return cost;
}

float screen_height(float extent, float distance, float vertical_fov) noexcept {
  if (!(extent > 0.0f) || !(distance > 0.0f) || !(vertical_fov > 0.0f) || !std::isfinite(extent) ||
      !std::isfinite(distance) || !(vertical_fov < 3.14159265f))
    return 0.0f;
  return 2.0f * std::atan(0.5f * extent / distance) / vertical_fov;
}

std::size_t pick_level(std::span<const float> thresholds, float height) noexcept {
  std::size_t level = 0;
  while (level < thresholds.size() && height < thresholds[level]) ++level;
  return level;
}

glm::vec3 Character::bone_position(std::int32_t bone) const {
  const auto b = std::size_t(bone);
  if (bone < 0 || b >= world_.size()) return glm::vec3(0.0f);
  return glm::vec3(world_[b][3]) + hierarchy_.point_displacement(bone, glm::vec3(skeleton().bind_world()[b][3]));
}

float Character::stretch() const {
  float sum = 0.0f;
  for (std::size_t l : stretched_) sum += hierarchy_.stretch(l);
  return sum;
}

}  // namespace deform
