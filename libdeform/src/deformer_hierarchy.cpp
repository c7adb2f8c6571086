// Elastic lattices bound to bones, and the hierarchy that makes a stretched lattice carry what lies below it.
#include <algorithm>
#include <cmath>
#include <string>

#include "deform/error.hpp"
#include "deform/hierarchy.hpp"
#include "deform/weights.hpp"

namespace deform {
namespace {

Error spec_error(const std::string& source, const LatticeSpec& spec, const std::string& message) {
  return Error::in_file(source, "lattice '" + spec.name + "'", message);
}

// A unit vector perpendicular to `axis`, from the basis axis least aligned with it.
glm::vec3 perpendicular(glm::vec3 axis) {
  const glm::vec3 a = glm::abs(axis);
  const glm::vec3 reference = a.x <= a.y && a.x <= a.z ? glm::vec3(1, 0, 0)
                              : a.y <= a.z             ? glm::vec3(0, 1, 0)
                                                       : glm::vec3(0, 0, 1);
  return glm::normalize(glm::cross(reference, axis));
}

glm::vec3 transform_point(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

}  // namespace

DeformerHierarchy::DeformerHierarchy(const Skeleton& skeleton, std::span<const glm::vec3> bind_positions,
                                     const SkinWeights& weights, std::vector<LatticeSpec> specs,
                                     const std::string& source)
    : skeleton_(&skeleton), scratch_(bind_positions.size(), glm::vec3(0.0f)) {
  const std::size_t point_count = bind_positions.size();
  if (weights.size() != point_count) {
    throw Error::in_file(source, "", "skin weights do not match the point count");
  }
  const std::vector<BoneSegment> segments = bone_segments(skeleton);
  lattices_.reserve(specs.size());
  for (LatticeSpec& spec : specs) {
    if (spec.name.empty()) throw spec_error(source, spec, "has no name");
    if (find(spec.name) >= 0) throw spec_error(source, spec, "name is used twice");
    if (spec.bone < 0 || std::size_t(spec.bone) >= skeleton.bone_count()) {
      throw spec_error(source, spec, "bone " + std::to_string(spec.bone) + " is out of range");
    }
    for (int axis = 0; axis < 3; ++axis) {
      if (spec.degree[axis] < 1 || spec.degree[axis] > max_bezier_degree) {
        throw spec_error(source, spec, "degree must be in [1, " + std::to_string(max_bezier_degree) + "]");
      }
    }
    if (!(spec.weight_threshold >= 0.0f && spec.weight_threshold < 1.0f)) {
      throw spec_error(source, spec, "weight_threshold must be in [0, 1)");
    }
    if (!(spec.margin >= 0.0f && spec.margin <= 1.0f)) throw spec_error(source, spec, "margin must be in [0, 1]");
    try {
      validate_settings(spec.elastic);
    } catch (const Error& e) {
      throw spec_error(source, spec, "elastic " + e.element() + " " + e.message());
    }

    // Selection weight of every point.
    std::vector<float> selection(point_count, 0.0f);
    if (spec.selection == VertexSelection::list) {
      for (std::size_t n = 0; n < spec.vertices.size(); ++n) {
        const std::uint32_t p = spec.vertices[n];
        if (p >= point_count) throw spec_error(source, spec, "vertex " + std::to_string(p) + " is out of range");
        if (n > 0 && p <= spec.vertices[n - 1]) {
          throw spec_error(source, spec, "vertex " + std::to_string(p) + " is repeated or out of order");
        }
        selection[p] = 1.0f;
      }
    } else {
      std::vector<std::uint8_t> in_subtree(skeleton.bone_count());
      for (std::size_t b = 0; b < in_subtree.size(); ++b) {
        in_subtree[b] = skeleton.is_ancestor(spec.bone, std::int32_t(b)) ? 1 : 0;
      }
      for (std::size_t p = 0; p < point_count; ++p) {
        float sum = 0.0f;
        for (int slot = 0; slot < max_influences; ++slot) {
          const std::uint16_t bone = weights.bones[p][slot];
          if (bone < in_subtree.size() && in_subtree[bone]) sum += weights.weights[p][slot];
        }
        selection[p] = sum > spec.weight_threshold ? std::min(sum, 1.0f) : 0.0f;
      }
    }

    // The frame: U along the bone from its head, V and W around the selected points.
    Lattice lattice;
    const Bone& bone = skeleton.bone(spec.bone);
    const glm::mat4& to_bone = skeleton.inverse_bind_world()[std::size_t(spec.bone)];
    bool leaf = true;
    if (!bone.children.empty()) {
      const glm::vec3 to_child = skeleton.bone(bone.children.front()).bind_translation;
      if (glm::length(to_child) > 1e-6f) {
        lattice.axis = glm::normalize(to_child);
        lattice.length = glm::length(to_child);
        leaf = false;
      }
    }
    if (leaf) {
      const BoneSegment& segment = segments[std::size_t(spec.bone)];
      const glm::vec3 direction = glm::mat3(to_bone) * (segment.tail - segment.head);
      lattice.axis = glm::length(direction) > 1e-6f ? glm::normalize(direction) : glm::vec3(0.0f, 1.0f, 0.0f);
    }
    const glm::vec3 side = perpendicular(lattice.axis);
    const glm::vec3 up = glm::cross(lattice.axis, side);  // right-handed: (axis × side) · up > 0
    std::vector<glm::vec3> local(point_count);
    float farthest = 0.0f;
    for (std::size_t p = 0; p < point_count; ++p) {
      if (selection[p] == 0.0f) continue;
      local[p] = transform_point(to_bone, bind_positions[p]);
      farthest = std::max(farthest, glm::dot(local[p], lattice.axis));
    }
    if (leaf) lattice.length = farthest * (1.0f + 1e-4f);
    if (!(lattice.length > 0.0f)) throw spec_error(source, spec, "selects no point along its bone");
    glm::vec2 lo(INFINITY), hi(-INFINITY);
    std::vector<std::uint32_t> candidates;
    for (std::size_t p = 0; p < point_count; ++p) {
      if (selection[p] == 0.0f) continue;
      const float along = glm::dot(local[p], lattice.axis);
      if (along < 0.0f || along > lattice.length) continue;
      const glm::vec2 across(glm::dot(local[p], side), glm::dot(local[p], up));
      lo = glm::min(lo, across);
      hi = glm::max(hi, across);
      candidates.push_back(std::uint32_t(p));
    }
    if (candidates.empty()) throw spec_error(source, spec, "selects no point inside its box");
    const glm::vec2 pad =
        glm::max(hi - lo, glm::vec2(1e-3f * lattice.length)) * spec.margin + glm::vec2(1e-4f * lattice.length);
    lo -= pad;
    hi += pad;
    LatticeFrame frame;
    frame.origin = side * lo.x + up * lo.y;
    frame.u_axis = lattice.axis * lattice.length;
    frame.v_axis = side * (hi.x - lo.x);
    frame.w_axis = up * (hi.y - lo.y);
    lattice.rest = BezierLattice(frame, spec.degree, source);
    lattice.field = lattice.rest;
    lattice.binding = lattice.rest.bind(bind_positions, candidates, to_bone);

    // Points the Bézier field moves, and points it carries.
    std::vector<std::uint8_t> bound(point_count, 0);
    lattice.lane_weights.assign(lattice.binding.vertices.size(), 0.0f);
    for (std::size_t lane = 0; lane < lattice.binding.vertices.size(); ++lane) {
      const std::uint32_t p = lattice.binding.vertices[lane];
      if (p == LatticeBinding::no_vertex) continue;
      bound[p] = 1;
      lattice.lane_weights[lane] = selection[p];
    }
    if (spec.carry_descendants) {
      for (std::size_t p = 0; p < point_count; ++p) {
        if (selection[p] == 0.0f || bound[p] || frame.to_lattice(local[p]).x < 1.0f) continue;
        lattice.carried_points.push_back(std::uint32_t(p));
        lattice.carried_weights.push_back(selection[p]);
      }
    }

    // The springs: the first face pinned, the last face read as one rigid translation.
    const glm::ivec3 counts = lattice.rest.point_counts();
    std::vector<std::uint8_t> pinned(lattice.rest.point_count(), 0);
    for (int k = 0; k < counts.z; ++k) {
      for (int j = 0; j < counts.y; ++j) {
        pinned[lattice.rest.index(0, j, k)] = 1;
        lattice.far_face.push_back(std::uint32_t(lattice.rest.index(counts.x - 1, j, k)));
      }
    }
    lattice.elastic = ElasticLattice(lattice.rest.control_points(), spec.elastic, counts);
    lattice.elastic.set_pinned(pinned);
    lattice.target_points.assign(lattice.rest.control_points().begin(), lattice.rest.control_points().end());
    lattice.world_displacements.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    lattice.world_points.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    lattice.spec = std::move(spec);
    lattices_.push_back(std::move(lattice));
  }

  for (Lattice& lattice : lattices_) {
    for (std::int32_t b = skeleton.bone(lattice.spec.bone).parent; b >= 0 && lattice.parent < 0;
         b = skeleton.bone(b).parent) {
      for (std::size_t other = 0; other < lattices_.size(); ++other) {
        if (lattices_[other].spec.bone == b) {
          lattice.parent = std::int32_t(other);
          break;
        }
      }
    }
  }
  std::vector<glm::mat4> world(skeleton.bind_world().begin(), skeleton.bind_world().end());
  update(world);
}

std::int32_t DeformerHierarchy::find(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < lattices_.size(); ++i) {
    if (lattices_[i].spec.name == name) return std::int32_t(i);
  }
  return -1;
}

void DeformerHierarchy::stretch_points(Lattice& lattice) const {
  const glm::ivec3 counts = lattice.rest.point_counts();
  const float last = float(counts.x - 1);
  for (int k = 0; k < counts.z; ++k) {
    for (int j = 0; j < counts.y; ++j) {
      for (int i = 0; i < counts.x; ++i) {
        const std::size_t n = lattice.rest.index(i, j, k);
        lattice.target_points[n] = lattice.rest.control_points()[n] + lattice.axis * (lattice.target * float(i) / last);
      }
    }
  }
}

bool DeformerHierarchy::set_stretch_target(std::size_t index, float stretch) {
  Lattice& lattice = lattices_.at(index);
  if (!std::isfinite(stretch) || !(stretch > -lattice.length)) return false;
  lattice.target = stretch;
  stretch_points(lattice);
  return true;
}

float DeformerHierarchy::stretch(std::size_t index) const {
  const Lattice& lattice = lattices_.at(index);
  float sum = 0.0f;
  for (std::uint32_t n : lattice.far_face) {
    sum += glm::dot(lattice.elastic.positions()[n] - lattice.rest.control_points()[n], lattice.axis);
  }
  return sum / float(lattice.far_face.size());
}

void DeformerHierarchy::set_elastic(std::size_t index, const ElasticSettings& settings) {
  Lattice& lattice = lattices_.at(index);
  lattice.elastic.set_settings(settings);
  lattice.spec.elastic = settings;
}

bool DeformerHierarchy::step(float dt) {
  if (!(dt >= 0.0f) || !std::isfinite(dt)) return false;
  for (Lattice& lattice : lattices_) lattice.elastic.step(dt, lattice.target_points);
  return true;
}

void DeformerHierarchy::reset() {
  for (Lattice& lattice : lattices_) {
    lattice.target = 0.0f;
    stretch_points(lattice);
    lattice.elastic.reset(lattice.rest.control_points());
  }
}

bool DeformerHierarchy::update(std::span<const glm::mat4> world) {
  if (skeleton_ == nullptr || world.size() != skeleton_->bone_count()) return false;
  for (Lattice& lattice : lattices_) {
    const std::span<const glm::vec3> rest = lattice.rest.control_points();
    const std::span<const glm::vec3> now = lattice.elastic.positions();
    glm::vec3 far(0.0f);
    for (std::uint32_t n : lattice.far_face) far += now[n] - rest[n];
    far /= float(lattice.far_face.size());
    const glm::mat3 linear(world[std::size_t(lattice.spec.bone)]);
    const float still = 1e-7f * lattice.length;
    lattice.active = glm::length(far) > still;
    std::span<glm::vec3> field = lattice.field.control_points();
    for (std::size_t n = 0; n < rest.size(); ++n) {
      const glm::vec3 local = now[n] - rest[n];
      lattice.active = lattice.active || glm::length(local) > still;
      lattice.world_displacements[n] = linear * local;
    }
    for (std::uint32_t n : lattice.far_face) lattice.world_displacements[n] = linear * far;
    std::copy(lattice.world_displacements.begin(), lattice.world_displacements.end(), field.begin());
    lattice.far_displacement = linear * far;
  }
  // Drawing positions, once every lattice's field is known (a lattice is carried by those above it).
  for (Lattice& lattice : lattices_) {
    const std::size_t bone = std::size_t(lattice.spec.bone);
    const glm::vec3 carried = point_displacement(lattice.spec.bone, glm::vec3(skeleton_->bind_world()[bone][3]));
    const std::span<const glm::vec3> rest = lattice.rest.control_points();
    for (std::size_t n = 0; n < rest.size(); ++n) {
      lattice.world_points[n] = transform_point(world[bone], rest[n]) + lattice.world_displacements[n] + carried;
    }
  }
  return true;
}

bool DeformerHierarchy::apply_carried(std::span<glm::vec3> positions) {
  if (positions.size() != scratch_.size()) return false;
  for (const Lattice& lattice : lattices_) {
    if (!lattice.active) continue;
    for (std::size_t n = 0; n < lattice.carried_points.size(); ++n) {
      positions[lattice.carried_points[n]] += lattice.carried_weights[n] * lattice.far_displacement;
    }
  }
  return true;
}

bool DeformerHierarchy::apply(std::span<glm::vec3> positions) {
  if (!apply_carried(positions)) return false;
  for (const Lattice& lattice : lattices_) {
    if (!lattice.active) continue;
    LatticeEvaluateJob job;
    job.binding = &lattice.binding;
    job.control_points = lattice.world_displacements;
    job.positions = scratch_;
    job.run();  // cannot fail: the binding was made for these control points and scratch_ spans every point
    const std::vector<std::uint32_t>& lanes = lattice.binding.vertices;
    for (std::size_t n = 0; n < lanes.size(); ++n) {
      if (lanes[n] != LatticeBinding::no_vertex) positions[lanes[n]] += lattice.lane_weights[n] * scratch_[lanes[n]];
    }
  }
  return true;
}

glm::vec3 DeformerHierarchy::point_displacement(std::int32_t bone, glm::vec3 bind_point) const noexcept {
  glm::vec3 sum(0.0f);
  if (skeleton_ == nullptr) return sum;
  for (const Lattice& lattice : lattices_) {
    if (!lattice.active || !skeleton_->is_ancestor(lattice.spec.bone, bone)) continue;
    const glm::vec3 local =
        transform_point(skeleton_->inverse_bind_world()[std::size_t(lattice.spec.bone)], bind_point);
    const glm::vec3 uvw = lattice.rest.frame().to_lattice(local);
    if (uvw.x <= 0.0f) continue;
    if (uvw.x >= 1.0f) {
      if (lattice.spec.carry_descendants) sum += lattice.far_displacement;
      continue;
    }
    sum += lattice.field.evaluate(glm::clamp(uvw, glm::vec3(0.0f), glm::vec3(1.0f)));
  }
  return sum;
}

}  // namespace deform
