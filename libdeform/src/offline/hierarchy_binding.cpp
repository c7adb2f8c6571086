// Elastic lattices bound to bones, and the hierarchy that makes a stretched lattice carry what lies below it.
#include <algorithm>
#include <cmath>
#include <string>

#include "deform/runtime/error.hpp"
#include "deform/offline/hierarchy_binding.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/offline/weights.hpp"
#include "deform/offline/weights.hpp"
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

DeformerHierarchy bind_hierarchy(const Skeleton& skeleton, std::span<const glm::vec3> bind_positions,
                                 const SkinWeights& weights, std::vector<LatticeSpec> specs,
                                 const std::string& source) {
  const std::size_t point_count = bind_positions.size();
  if (weights.size() != point_count) {
    throw Error::in_file(source, "", "skin weights do not match the point count");
  }
  // The extra influences' layout (SkinWeights): ascending points in range, offsets from 0 that never decrease and
  // end at the arrays' common size.
  if (weights.has_extra()) {
    const std::size_t rows = weights.extra_points.size();
    bool ok = weights.extra_offsets.size() == rows + 1 && weights.extra_offsets.front() == 0 &&
              weights.extra_offsets.back() == weights.extra_bones.size() &&
              weights.extra_bones.size() == weights.extra_weights.size();
    for (std::size_t j = 0; ok && j < rows; ++j)
      ok = weights.extra_points[j] < point_count && weights.extra_offsets[j] <= weights.extra_offsets[j + 1] &&
           (j == 0 || weights.extra_points[j - 1] < weights.extra_points[j]);
    if (!ok) throw Error::in_file(source, "", "skin weights' extra influences are malformed");
  }
  const std::vector<BoneSegment> segments = bone_segments(skeleton);
  std::vector<BoundLattice> lattices;
  lattices.reserve(specs.size());
  for (LatticeSpec& spec : specs) {
    if (spec.name.empty()) throw spec_error(source, spec, "has no name");
    for (const BoundLattice& other : lattices) {
      if (other.spec.name == spec.name) throw spec_error(source, spec, "name is used twice");
    }
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
      require_valid_settings(spec.elastic);
    } catch (const Error& e) {
      throw spec_error(source, spec, "elastic " + e.element() + " " + e.message());
    }
    try {
      require_valid_shape(spec.shape);
    } catch (const Error& e) {
      throw spec_error(source, spec, e.message());
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
      // A point's weight on the subtree: its four slots and, past them, its extra influences (SkinWeights).
      std::vector<float> subtree_weight(point_count, 0.0f);
      for (std::size_t p = 0; p < point_count; ++p) {
        for (int slot = 0; slot < max_influences; ++slot) {
          const std::uint16_t bone = weights.bones[p][slot];
          if (bone < in_subtree.size() && in_subtree[bone]) subtree_weight[p] += weights.weights[p][slot];
        }
      }
      for (std::size_t j = 0; j < weights.extra_points.size(); ++j) {
        const std::uint32_t p = weights.extra_points[j];
        for (std::uint32_t e = weights.extra_offsets[j]; e < weights.extra_offsets[j + 1]; ++e) {
          const std::uint16_t bone = weights.extra_bones[e];
          if (bone < in_subtree.size() && in_subtree[bone]) subtree_weight[p] += weights.extra_weights[e];
        }
      }
      for (std::size_t p = 0; p < point_count; ++p) {
        const float sum = subtree_weight[p];
        selection[p] = sum > spec.weight_threshold ? std::min(sum, 1.0f) : 0.0f;
      }
    }

    // The frame: U along the bone from its head, V and W around the selected points.
    BoundLattice lattice;
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
    lattice.binding = bind_lattice(lattice.rest, bind_positions, candidates, to_bone);

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

    lattice.spec = std::move(spec);
    lattices.push_back(std::move(lattice));
  }
  return DeformerHierarchy(skeleton, std::move(lattices), point_count);
}

}  // namespace deform
