#pragma once
// The Bézier lattice evaluated on the GPU (the thesis' future work, §10): the same map as deform::LatticeEvaluateJob,
// Q(u, v, w) = Σ P_ijk B_i,l(u) B_j,m(v) B_k,n(w) with Jacobian normals, run by an OpenGL 4.3 compute shader with one
// invocation per bound vertex. The binding is made on the CPU (BezierLattice::bind) and uploaded once; each frame only
// the control points travel to the GPU. docs/gpu.md.
//
// Two outputs:
//  - evaluate() + read_back(): results in a buffer of its own, scattered on the CPU into spans indexed by point (the
//    test compares them with the CPU kernel);
//  - evaluate_into(): results written straight into an interleaved vertex buffer (MeshRenderer's u v nx ny nz x y z)
//    at the binding's vertex indices, so a mesh draws with no CPU evaluation and no upload of vertices. The binding's
//    indices must then be render vertices: bind the lattice over the render vertices' positions (each point gathered
//    by Mesh::vertex_point), with the render vertex normals as the rest normals.
//
// Additive lattices (create_additive) serve a deform::DeformerHierarchy, whose control points are displacements: they
// add weight · Q(u, v, w) to positions already in the vertex buffer (skinned on the CPU) and map the hierarchy's mesh
// points to render vertices themselves. GpuLatticeFields runs one per lattice of a character.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/io/lattice_json.hpp"
namespace sample {

// Where evaluate_into() writes inside each vertex of an interleaved float buffer; the defaults are MeshRenderer's.
struct InterleavedLayout {
  int floats_per_vertex = 8;
  int position_offset = 5;  // x y z
  int normal_offset = 2;    // nx ny nz (written only when the lattice was created with normals)
};

class GpuBezierLattice {
 public:
  GpuBezierLattice() = default;
  GpuBezierLattice(const GpuBezierLattice&) = delete;
  GpuBezierLattice& operator=(const GpuBezierLattice&) = delete;
  ~GpuBezierLattice();

  // True when the current OpenGL context is 4.3 or newer (compute shaders and shader storage buffers).
  static bool supported();

  // Uploads the binding's bound vertices (their index and u, v, w; padding lanes are dropped) and, when `rest_normals`
  // is not empty (size > binding.max_vertex, indexed like the binding), their rest normals, which turns on Jacobian
  // normals. Needs a current context. Returns false, creating nothing, when the context lacks compute, the binding is
  // not a Bézier one (B-spline bindings are not handled here) or `rest_normals` is too short. Allocates; O(vertices).
  bool create(const deform::LatticeBinding& binding, std::span<const glm::vec3> rest_normals = {});

  // Additive mode, for a lattice whose control points are displacements (deform::DeformerHierarchy::displacements):
  // evaluate_into() then adds weight · Q(u, v, w) to the position of every render vertex r whose point
  // vertex_point[r] the binding holds, and leaves its normal and everything else alone. `weights`: one per binding
  // lane (DeformerHierarchy::bound_weights); `vertex_point`: Mesh::vertex_point. Returns false as create() does, or
  // when weights.size() differs from the lane count. evaluate() and read_back() refuse an additive lattice.
  // Allocates; O(lanes + render vertices).
  bool create_additive(const deform::LatticeBinding& binding, std::span<const float> weights,
                       std::span<const std::uint32_t> vertex_point);

  bool additive() const { return additive_; }
  bool has_normals() const { return has_normals_; }
  std::size_t vertex_count() const { return count_; }
  glm::ivec3 point_counts() const { return point_counts_; }

  // Uploads the control points (i-fastest, point_counts() per axis, as BezierLattice::control_points()) and
  // dispatches the shader into this object's own result buffer. Returns false when create() has not succeeded or the
  // point count differs. Asynchronous: read_back() waits.
  bool evaluate(std::span<const glm::vec3> control_points);
  // Waits for the last evaluate() and writes positions[p] (and normals[p] when `normals` is not empty and the lattice
  // has normals) for every bound vertex p; other entries are left as they are. Spans must be larger than the largest
  // bound index (else false). No allocation.
  bool read_back(std::span<glm::vec3> positions, std::span<glm::vec3> normals = {});

  // Uploads the control points and writes each bound vertex's position (and normal) into `vertex_buffer`, an
  // interleaved float buffer of at least (largest bound index + 1) vertices in `layout`; nothing else in it changes.
  // Issues the barrier that makes the writes visible to vertex fetching, so the buffer can be drawn right after, and
  // to the next shader, so additive lattices over the same buffer can follow one another.
  bool evaluate_into(std::span<const glm::vec3> control_points, GLuint vertex_buffer,
                     const InterleavedLayout& layout = {});

 private:
  // Uploads per-vertex targets, parameters, rest normals (3 floats each, or none) and weights (or none).
  void upload(glm::ivec3 point_counts, const glm::mat3& normal_basis, std::span<const float> params,
              std::span<const float> normals, std::span<const float> weights);
  bool dispatch(std::span<const glm::vec3> control_points, GLuint output, bool scatter, const InterleavedLayout& layout);
  void release();

  GLuint program_ = 0;
  GLuint targets_ = 0, params_ = 0, normals_ = 0, points_ = 0, results_ = 0, weights_ = 0;  // storage buffers
  std::size_t count_ = 0;
  std::uint32_t max_target_ = 0;
  glm::ivec3 point_counts_{0};
  glm::mat3 normal_basis_{1.0f};
  bool has_normals_ = false;
  bool additive_ = false;
  std::vector<std::uint32_t> target_list_;  // CPU copy of the indices for read_back's scatter
  std::vector<float> staging_;              // read_back's destination, sized once
};

// The Bézier fields of a character's lattices on the GPU: one additive GpuBezierLattice per lattice of a
// DeformerHierarchy. With deform::Character::lattice_fields = false, the CPU skins (and adds the carried
// translations); MeshRenderer::upload streams that; add_into() then adds every moving lattice's field in the vertex
// buffer, which gives Character's full deformation to float rounding. Normals stay those the CPU uploaded (of the
// surface before the fields). docs/gpu.md.
class GpuLatticeFields {
 public:
  // Creates one additive lattice per hierarchy lattice (`vertex_point`: the mesh's Mesh::vertex_point). Needs a
  // current OpenGL 4.3 context; returns false, keeping nothing, otherwise. Call again after the hierarchy is rebuilt.
  bool create(const deform::DeformerHierarchy& hierarchy, std::span<const std::uint32_t> vertex_point);
  void clear() { lattices_.clear(); }

  // Per frame, after the hierarchy's update() and the positions' upload: uploads each active lattice's displacements
  // (DeformerHierarchy::active, displacements) and adds its field into `vertex_buffer`. Returns false when the
  // hierarchy has a different lattice count than at create() or a dispatch is refused. No allocation.
  bool add_into(const deform::DeformerHierarchy& hierarchy, GLuint vertex_buffer, const InterleavedLayout& layout = {});

 private:
  std::vector<std::unique_ptr<GpuBezierLattice>> lattices_;
};

}  // namespace sample
