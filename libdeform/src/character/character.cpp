// The Character facade: pose, reach (IK + elastic stretch), release, and the per-frame deformation.
#include "deform/character/character.hpp"
#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "deform/offline/hierarchy_binding.hpp"
#include "deform/runtime/error.hpp"

namespace deform {
namespace {

bool finite(glm::vec3 v) noexcept { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

Character::Character(Model model) : Character(std::move(model), Rig{}) {}

Character::Character(Model model, const Rig& rig)
    : model_(std::move(model)),
      rig_(rig),
      hierarchy_(bind_hierarchy(model_.skeleton, model_.mesh.positions, model_.weights, rig_.lattices, model_.name)),
      pose_(model_.skeleton.bind_pose()),
      world_(model_.skeleton.bone_count()),
      palette_(model_.skeleton.bone_count()),
      dual_quats_(model_.skeleton.bone_count()),
      scales_(model_.skeleton.bone_count()),
      positions_(model_.mesh.positions),
      normals_(model_.mesh.vertex_count()),
      vertex_normals_(bind_vertex_normals(model_.mesh)),
      normals_scratch_(vertex_normals_.scratch_size()) {
  const auto bones = std::int32_t(model_.skeleton.bone_count());
  if (rig_.reach_effector >= bones || rig_.reach_root >= bones) {
    throw Error::in_file(model_.name, "rig", "reach bone out of range");
  }
  if (!(rig_.max_stretch >= 0.0f) || !std::isfinite(rig_.max_stretch)) {
    throw Error::in_file(model_.name, "rig", "max_stretch must be finite and >= 0");
  }
  SkinningJob job;
  job.matrices = palette_;
  job.bone_indices = model_.weights.bones;
  job.bone_weights = model_.weights.weights;
  job.in_positions = as_floats(std::span<const glm::vec3>(model_.mesh.positions));
  job.out_positions = as_floats(std::span<glm::vec3>(positions_));
  if (!job.validate()) throw Error::in_file(model_.name, "weights", "skin weights do not fit the mesh and skeleton");
  update(0.0f);
}

bool Character::set_pose(const Pose& pose) {
  const std::size_t bones = skeleton().bone_count();
  if (pose.rotations.size() != bones || pose.translations.size() != bones) return false;
  for (std::size_t b = 0; b < bones; ++b) {
    const glm::quat q = pose.rotations[b];
    if (!finite(pose.translations[b]) || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) ||
        !std::isfinite(q.w)) {
      return false;
    }
  }
  pose_ = pose;
  for (std::size_t b = 0; b < bones; ++b) skeleton().clamp_to_limits(pose_, std::int32_t(b));
  return true;
}

ReachResult Character::reach(std::int32_t effector, glm::vec3 target) {
  ReachResult result;
  const Skeleton& skel = skeleton();
  if (effector <= 0 || std::size_t(effector) >= skel.bone_count() || !finite(target)) return result;

  // The chain root: the rig's, else the parent of the topmost lattice bone above the effector, else two bones up.
  std::int32_t root = effector == rig_.reach_effector ? rig_.reach_root : -1;
  if (root < 0 || !skel.is_ancestor(root, effector) || root == effector) {
    root = -1;
    for (std::int32_t b = skel.bone(effector).parent; b >= 0; b = skel.bone(b).parent) {
      for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) {
        if (hierarchy_.spec(l).bone == b) root = b;
      }
    }
    if (root > 0) root = skel.bone(root).parent;
    if (root < 0) {
      root = skel.bone(effector).parent;
      if (skel.bone(root).parent >= 0) root = skel.bone(root).parent;
    }
  }

  // The lattices that stretch: on the chain above the effector, carrying it (their far face is behind it).
  struct Stretched {
    std::size_t lattice;
    std::int32_t child;  // the chain bone right below the lattice's bone
    glm::vec3 axis;      // stretch per unit, in the lattice bone's frame
  };
  std::vector<Stretched> chain_lattices;
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
    chain_lattices.push_back({l, child, rest.frame().u_axis / hierarchy_.length(l)});
  }

  std::optional<CcdSolver> made;
  try {
    made.emplace(skel, root, effector);
  } catch (const Error&) {
    return result;  // a chain longer than the solver takes
  }
  CcdSolver& solver = *made;
  Pose work = pose_;
  const float reach_length = chain_length(solver.chain(), work);
  IkSettings settings = ik;
  settings.tolerance = std::max(1e-5f * reach_length, 1e-7f);
  IkResult ik_result;
  if (!solver.solve(work, target, settings, ik_result)) return result;
  result.valid = true;
  result.residual = ik_result.distance;
  result.iterations = 1;

  // Stretch λ·length_L on every chain lattice, λ fitted to the remaining gap, then IK again with the longer chain.
  float lambda = 0.0f;
  float distance = ik_result.distance;
  std::vector<glm::mat4> world(skel.bone_count());
  for (int round = 0;
       round < 16 && !chain_lattices.empty() && distance > 1e-3f * result.residual && distance > settings.tolerance;
       ++round) {
    compute_world_matrices(skel, work, world);
    glm::vec3 growth(0.0f);  // effector motion per unit λ
    for (const Stretched& s : chain_lattices) {
      growth +=
          glm::mat3(world[std::size_t(hierarchy_.spec(s.lattice).bone)]) * (s.axis * hierarchy_.length(s.lattice));
    }
    const float growth2 = glm::dot(growth, growth);
    if (!(growth2 > 0.0f)) break;
    const glm::vec3 gap = target - effector_position(skel, solver.chain(), work);
    const float next = std::clamp(lambda + glm::dot(gap, growth) / growth2, 0.0f, rig_.max_stretch);
    if (next == lambda && round > 0) break;
    lambda = next;
    for (const Stretched& s : chain_lattices) {
      work.translations[std::size_t(s.child)] = pose_.translations[std::size_t(s.child)];
    }
    for (const Stretched& s : chain_lattices) {  // (two lattices on one bone both push its child)
      work.translations[std::size_t(s.child)] += s.axis * (lambda * hierarchy_.length(s.lattice));
    }
    if (!solver.solve(work, target, settings, ik_result)) break;
    distance = ik_result.distance;
    ++result.iterations;
  }
  result.distance = distance;

  // The pose keeps the IK rotations; the lattices, not the bones, carry the stretch.
  for (const Stretched& s : chain_lattices) {
    work.translations[std::size_t(s.child)] = pose_.translations[std::size_t(s.child)];
  }
  pose_ = std::move(work);
  release();
  stretched_.clear();
  for (const Stretched& s : chain_lattices) {
    hierarchy_.set_stretch_target(s.lattice, lambda * hierarchy_.length(s.lattice));
    stretched_.push_back(s.lattice);
    result.stretch += lambda * hierarchy_.length(s.lattice);
  }
  effector_ = effector;
  return result;
}

void Character::release() {
  for (std::size_t l = 0; l < hierarchy_.lattice_count(); ++l) hierarchy_.set_stretch_target(l, 0.0f);
}

bool Character::update(float dt) {
  if (!(dt >= 0.0f) || !std::isfinite(dt)) return false;
  hierarchy_.step(dt);
  const Skeleton& skel = skeleton();
  compute_world_matrices(skel, pose_, world_);
  compute_skinning_palette(skel, world_, palette_);
  SkinningJob job;
  job.method = skinning;
  job.matrices = palette_;
  job.bone_indices = model_.weights.bones;
  job.bone_weights = model_.weights.weights;
  job.in_positions = as_floats(std::span<const glm::vec3>(model_.mesh.positions));
  job.out_positions = as_floats(std::span<glm::vec3>(positions_));
  if (skinning == SkinningMethod::dqs) {
    bool has_scale = false;
    compute_dual_quat_palette(palette_, dual_quats_, scales_, has_scale);
    job.dual_quats = dual_quats_;
    if (has_scale) job.scales = scales_;
  }
  job.run();
  hierarchy_.update(world_);
  if (lattice_fields) {
    hierarchy_.apply(positions_);
  } else {
    hierarchy_.apply_carried(positions_);
  }
  normals_current_ = false;
  return true;
}

std::span<const glm::vec3> Character::normals() {
  if (!normals_current_) {
    VertexNormalsJob job;
    job.binding = &vertex_normals_;
    job.positions = positions_;
    job.normals = normals_;
    job.scratch = normals_scratch_;
    job.run();
    normals_current_ = true;
  }
  return normals_;
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
