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
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <epoxy/gl.h>
#include <glm/glm.hpp>

#include "deform/lattice.hpp"

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
  // Issues the barrier that makes the writes visible to vertex fetching, so the buffer can be drawn right after.
  bool evaluate_into(std::span<const glm::vec3> control_points, GLuint vertex_buffer,
                     const InterleavedLayout& layout = {});

 private:
  bool dispatch(std::span<const glm::vec3> control_points, GLuint output, bool scatter, const InterleavedLayout& layout);
  void release();

  GLuint program_ = 0;
  GLuint targets_ = 0, params_ = 0, normals_ = 0, points_ = 0, results_ = 0;  // shader storage buffers
  std::size_t count_ = 0;
  std::uint32_t max_target_ = 0;
  glm::ivec3 point_counts_{0};
  glm::mat3 normal_basis_{1.0f};
  bool has_normals_ = false;
  std::vector<std::uint32_t> target_list_;  // CPU copy of the indices for read_back's scatter
  std::vector<float> staging_;              // read_back's destination, sized once
};

}  // namespace sample
