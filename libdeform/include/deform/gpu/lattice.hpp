#pragma once
// deform::gpu (optional component, link deform::gpu): Bézier lattices evaluated by an OpenGL 4.3 compute shader, the
// same map as deform::LatticeEvaluateJob, Q(u, v, w) = Σ P_ijk B_i,l(u) B_j,m(v) B_k,n(w) with Jacobian normals, one
// shader invocation per bound vertex. The binding is made on the CPU (bind_lattice) and uploaded once; each frame only
// the control points travel to the GPU. docs/gpu.md.
//
// The caller owns the OpenGL context: every call that touches GL, the destructor and release() included, needs a
// current OpenGL 4.3 context (or one sharing its objects with the one current at create()). The library loads GL
// through libepoxy, which works beside any loader the application uses; this header includes no GL header (buffer
// names are GLuint, i.e. unsigned int). Nothing here opens windows or makes contexts.
//
// Two outputs:
//  - evaluate() + read_back(): results in a buffer of the lattice's own, scattered on the CPU into spans indexed by
//    point (for tests and tools);
//  - evaluate_into(): results written straight into the application's interleaved vertex buffer at the binding's
//    vertex indices, so a mesh draws with no CPU evaluation and no upload of vertices. The binding's indices must then
//    be render vertices: bind the lattice over the render vertices' positions (each point gathered by
//    Mesh::vertex_point), with the render vertex normals as the rest normals.
//
// Additive lattices (create_additive) serve a deform::DeformerHierarchy, whose control points are displacements: they
// add weight · Q(u, v, w) to positions already in the vertex buffer (skinned on the CPU or by GpuSkinning) and map
// the hierarchy's mesh points to render vertices themselves. GpuLatticeFields runs one per lattice of a character.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/gpu/export.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/lattice.hpp"

namespace deform {

// Where evaluate_into() writes inside each vertex of an interleaved float buffer, in floats. The default is
// u v, nx ny nz, x y z (8 floats per vertex).
struct GpuVertexLayout {
  int floats_per_vertex = 8;
  int position_offset = 5;  // x y z
  int normal_offset = 2;    // nx ny nz (written only by a lattice created with normals)
};

// One Bézier lattice binding on the GPU: its bound vertices' parameters in storage buffers, and a compute program
// whose loops are compiled for the binding's degree. Movable, not copyable.
class DEFORM_GPU_API GpuBezierLattice {
 public:
  GpuBezierLattice() noexcept = default;
  GpuBezierLattice(GpuBezierLattice&& other) noexcept;
  GpuBezierLattice& operator=(GpuBezierLattice&& other) noexcept;
  GpuBezierLattice(const GpuBezierLattice&) = delete;
  GpuBezierLattice& operator=(const GpuBezierLattice&) = delete;
  // Deletes the GL objects (release()): needs the context current when create() has succeeded.
  ~GpuBezierLattice();

  // True when the current context is desktop OpenGL 4.3 or newer (compute shaders, shader storage buffers). Needs a
  // current context.
  static bool supported();

  // Uploads the binding's bound vertices (their index and u, v, w; padding lanes are dropped) and, when
  // `rest_normals` is not empty (indexed like the binding, larger than binding.max_vertex), their rest normals, which
  // turns on Jacobian normals; compiles the program. Replaces what the lattice held. Refuses, holding nothing, when
  // the context is not 4.3, the binding is not a Bézier one of degree 1..max_bezier_degree (B-spline bindings stay on
  // the CPU), `rest_normals` is too short, or the driver rejects the shader (shader_log() has its message).
  // Bind time: allocates, O(bound vertices).
  Status create(const LatticeBinding& binding, std::span<const glm::vec3> rest_normals = {});

  // Additive mode, for a lattice whose control points are displacements (DeformerHierarchy::displacements):
  // evaluate_into() then adds weight · Q(u, v, w) to the position of every render vertex r whose point
  // vertex_point[r] the binding holds, and leaves its normal and everything else alone. `weights`: one per binding
  // lane (DeformerHierarchy::bound_weights); `vertex_point`: Mesh::vertex_point. Refuses as create() does, or when
  // weights.size() differs from the lane count. evaluate() and read_back() refuse an additive lattice.
  // With `normals`, it also turns each such vertex's normal in the buffer as DeformerHierarchy::apply(positions,
  // normals) does: per frame it then takes the lattice's mapped points and normals_to_bind matrix too (the
  // evaluate_into overload below; the plain one refuses). Bind time: allocates, O(lanes + render vertices).
  Status create_additive(const LatticeBinding& binding, std::span<const float> weights,
                         std::span<const std::uint32_t> vertex_point, bool normals = false);

  // Deletes the GL objects; the lattice then holds nothing (as default-constructed). Needs the context current when
  // it holds anything.
  void release() noexcept;

  bool created() const noexcept { return program_ != 0; }
  bool additive() const noexcept { return additive_; }
  bool has_normals() const noexcept { return has_normals_; }
  // Vertices the shader writes: bound vertices (create) or render vertices of bound points (create_additive).
  std::size_t vertex_count() const noexcept { return count_; }
  glm::ivec3 point_counts() const noexcept { return point_counts_; }
  // The driver's compiler or linker message when create() refused the shader; empty otherwise.
  const std::string& shader_log() const noexcept { return shader_log_; }

  // Uploads the control points (i-fastest, point_counts() per axis, as BezierLattice::control_points()) and
  // dispatches the shader into the lattice's own result buffer. Refuses when nothing was created, the lattice is
  // additive or the point count differs. Asynchronous: read_back() waits. Per frame: no allocation.
  Status evaluate(std::span<const glm::vec3> control_points);
  // Waits for the last evaluate() and writes positions[p] (and normals[p], when `normals` is not empty and the
  // lattice has normals) for every bound vertex p; other entries are left as they are. Refuses spans not larger than
  // the largest bound index. Per frame: no allocation.
  Status read_back(std::span<glm::vec3> positions, std::span<glm::vec3> normals = {});

  // Uploads the control points and writes each bound vertex's position (and normal), or adds its weighted field
  // (additive), into `vertex_buffer`: the name (GLuint) of a buffer of at least (largest index written + 1) vertices
  // in `layout`; nothing else in it changes. Issues the barrier that makes the writes visible to vertex fetching,
  // buffer reads and the next shader, so the buffer draws right after and additive lattices over it can follow one
  // another. Refuses, writing nothing, when nothing was created, the point count differs, the layout does not fit its
  // stride, or the buffer is 0 or too small. Per frame: no allocation.
  Status evaluate_into(std::span<const glm::vec3> control_points, unsigned int vertex_buffer,
                       const GpuVertexLayout& layout = {});
  // What evaluate_into() would refuse, changing nothing (it asks GL for the buffer's size).
  Status validate_into(std::span<const glm::vec3> control_points, unsigned int vertex_buffer,
                       const GpuVertexLayout& layout = {}) const;
  // An additive lattice created with normals: adds the weighted field of `displacements` to each vertex's position
  // and turns its normal (in the buffer) by the map whose control points are `mapped_points`, the normal taken into
  // the binding's space by `to_bind` (DeformerHierarchy::mapped_points, normals_to_bind). Refuses, writing nothing,
  // as evaluate_into() does, when the lattice is not an additive one with normals, or the mapped point count differs.
  Status evaluate_into(std::span<const glm::vec3> displacements, std::span<const glm::vec3> mapped_points,
                       const glm::mat3& to_bind, unsigned int vertex_buffer, const GpuVertexLayout& layout = {});
  Status validate_into(std::span<const glm::vec3> displacements, std::span<const glm::vec3> mapped_points,
                       unsigned int vertex_buffer, const GpuVertexLayout& layout = {}) const;

 private:
  struct Uniforms {
    int first_vertex = -1, vertex_count = -1, normal_basis = -1, with_normals = -1, scatter = -1, additive = -1,
        stride = -1, position_offset = -1, normal_offset = -1, to_bind = -1, noise_floor2 = -1;
  };

  Status upload(glm::ivec3 point_counts, const glm::mat3& normal_basis, std::span<const float> params,
                std::span<const float> normals, std::span<const float> weights);
  void dispatch(std::span<const glm::vec3> control_points, unsigned int output, bool scatter,
                const GpuVertexLayout& layout, std::span<const glm::vec3> mapped_points = {},
                const glm::mat3& to_bind = glm::mat3(1.0f));

  unsigned int program_ = 0;
  unsigned int targets_ = 0, params_ = 0, normals_ = 0, points_ = 0, results_ = 0, weights_ = 0,
               mapped_ = 0;  // storage buffers
  Uniforms uniforms_;
  std::size_t count_ = 0;
  std::uint32_t max_target_ = 0;
  glm::ivec3 point_counts_{0};
  glm::mat3 normal_basis_{1.0f};
  bool has_normals_ = false;
  bool additive_ = false;
  std::vector<std::uint32_t> target_list_;  // CPU copy of the indices for read_back's scatter
  std::vector<float> staging_;              // read_back's destination, sized once
  std::string shader_log_;
};

// The Bézier fields of a character's lattices on the GPU: one additive GpuBezierLattice per lattice of a
// DeformerHierarchy (and one for its carried points). Two splits (docs/gpu.md):
//  - deform::Character::settings.lattice_fields = false: the CPU skins and adds the carried translations, the
//  application
//    uploads those positions into its vertex buffer, add_into() adds every moving lattice's field there;
//  - deform::Character::settings.deform_on_cpu = false: GpuSkinning writes the skinned buffer, apply_into() adds the
//  carried
//    translations and the fields: the whole deformation on the GPU.
// Either gives the Character's full deformation to float rounding. Normals stay those in the buffer (of the surface
// before the fields) unless created with normals, which turns them as the CPU's transported normals are turned.
// Movable, not copyable.
class DEFORM_GPU_API GpuLatticeFields {
 public:
  GpuLatticeFields() noexcept = default;
  GpuLatticeFields(GpuLatticeFields&&) noexcept = default;
  GpuLatticeFields& operator=(GpuLatticeFields&&) noexcept = default;
  GpuLatticeFields(const GpuLatticeFields&) = delete;
  GpuLatticeFields& operator=(const GpuLatticeFields&) = delete;
  ~GpuLatticeFields() = default;

  // Creates one additive lattice per hierarchy lattice (`vertex_point`: the mesh's Mesh::vertex_point), and one for
  // its carried points (a degree-1 lattice that binds them all at (0, 0, 0), where the field is exactly its first
  // control point: apply_into() makes them all the far face's displacement). Refuses, keeping nothing, as
  // GpuBezierLattice::create_additive does. Call again after the hierarchy is rebuilt. Bind time: allocates.
  // With `normals`, add_into() and apply_into() also turn the normals in the buffer by the lattices' maps, as
  // DeformerHierarchy::apply(positions, normals) does (Character's transported normals): the buffer's normals must
  // then be the skinned ones (GpuSkinning with normals, or the CPU's). Per frame that costs a second contraction per
  // vertex and the upload of each active lattice's mapped points.
  Status create(const DeformerHierarchy& hierarchy, std::span<const std::uint32_t> vertex_point, bool normals = false);
  // Deletes every lattice's GL objects (needs the context current).
  void clear() noexcept {
    lattices_.clear();
    carried_.clear();
    carried_points_.clear();
    mapped_points_.clear();
  }
  bool has_normals() const noexcept { return normals_; }
  std::size_t lattice_count() const noexcept { return lattices_.size(); }

  // Per frame, after the hierarchy's update() and the positions' upload: uploads each active lattice's displacements
  // (DeformerHierarchy::active, displacements) and adds its field into `vertex_buffer` (a GLuint), lattice after
  // lattice in index order. Refuses, adding nothing, when the hierarchy's lattice count differs from create()'s or
  // a lattice would refuse (validate_into: a displacement count, the layout, a buffer too small). No allocation.
  Status add_into(const DeformerHierarchy& hierarchy, unsigned int vertex_buffer, const GpuVertexLayout& layout = {});
  // What DeformerHierarchy::apply() adds, all on the GPU: first every active lattice's carried points (render
  // vertices of carried_points(l), + carried_weights(l) · far_displacement(l)), then the fields as add_into() does.
  // For a buffer the GPU skinned (GpuSkinning::skin_into, whose barrier orders it before these), with
  // Character::settings.deform_on_cpu = false: the CPU then uploads only the palette and the control points. Normals
  // stay as skinned (the CPU's transported normals also turn by the lattices' Jacobians: docs/gpu.md). Refuses, adding
  // nothing, as add_into() does. No allocation.
  Status apply_into(const DeformerHierarchy& hierarchy, unsigned int vertex_buffer, const GpuVertexLayout& layout = {});

 private:
  // The fields of the active lattices, in index order (checked by the caller).
  void add_fields(const DeformerHierarchy& hierarchy, unsigned int vertex_buffer, const GpuVertexLayout& layout);

  std::vector<GpuBezierLattice> lattices_;
  std::vector<GpuBezierLattice> carried_;  // per lattice: its carried points (see create())
  std::vector<glm::vec3> carried_points_;  // per lattice, 8 control points (the far displacement), per frame
  std::vector<glm::vec3> mapped_points_;   // with normals: the largest lattice's mapped points, per frame
  bool normals_ = false;
};

}  // namespace deform
