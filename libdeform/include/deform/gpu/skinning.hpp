#pragma once
// deform::gpu (optional component, link deform::gpu): skinning in an OpenGL 4.3 compute shader, the same arithmetic
// as deform::SkinningJob (linear blend and dual quaternion, four influences per vertex), one invocation per vertex,
// writing positions and normals straight into the application's interleaved vertex buffer (GpuVertexLayout, as the
// lattices do). The bind pose (positions, normals, bone indices and weights) is uploaded once; each frame only the
// palette travels. Followed by GpuLatticeFields::apply_into on the same buffer, a deform::Character's whole
// deformation runs on the GPU (docs/gpu.md).
//
// The caller owns the OpenGL context, as for deform/gpu/lattice.hpp: every call that touches GL, the destructor and
// release() included, needs a current OpenGL 4.3 context (or one sharing objects with the one current at create()).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/type_precision.hpp>

#include "deform/gpu/export.hpp"
#include "deform/gpu/lattice.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skinning.hpp"

namespace deform {

// What GpuSkinning::create() binds. The shader runs per *render vertex*: vertex r of the output reads point
// vertex_point[r] of the per-point arrays (Mesh::vertex_point; empty = vertex r is point r), so a point split at a UV
// or normal seam is skinned once per render vertex and nothing is gathered per frame.
struct GpuSkinningBind {
  std::span<const glm::vec3> positions;         // per point, bind pose
  std::span<const glm::u16vec4> bone_indices;   // per point: four influences (SkinWeights::bones)
  std::span<const glm::vec4> bone_weights;      // per point (SkinWeights::weights), as SkinningJob::validate accepts
  std::span<const std::uint32_t> vertex_point;  // render vertex -> point; empty: one vertex per point
  // Bind normals per *render vertex* (vertex_point.size() entries, or one per point when vertex_point is empty):
  // Mesh::vertex_normals, or Character::bind_normals() gathered through vertex_point to get Character::normals().
  // Empty: the shader writes no normals.
  std::span<const glm::vec3> normals;
  std::size_t bone_count = 0;  // the palette size every frame must have, 1..65536
};

// A skinned mesh on the GPU. Movable, not copyable.
//
// Influences: exactly four per vertex (a glm::u16vec4 and a glm::vec4, as SkinningJob and SkinWeights hold them). A
// skin with more influences per vertex is not taken: reduce it to the four strongest, renormalised (what the importer
// does), or skin it on the CPU.
class DEFORM_GPU_API GpuSkinning {
 public:
  GpuSkinning() noexcept = default;
  GpuSkinning(GpuSkinning&& other) noexcept;
  GpuSkinning& operator=(GpuSkinning&& other) noexcept;
  GpuSkinning(const GpuSkinning&) = delete;
  GpuSkinning& operator=(const GpuSkinning&) = delete;
  ~GpuSkinning();  // release(): needs the context current when create() has succeeded

  // True when the current context is desktop OpenGL 4.3 or newer. Needs a current context.
  static bool supported();

  // Checks the bind as SkinningJob::validate() does (every index below bone_count, weights finite, >= 0, not
  // denormal, each vertex's sum within [min_skin_weight_sum, max_skin_weight_sum], with the same reasons), and that
  // vertex_point's entries are points and the normals cover the vertices; uploads the per-vertex data (gathered per
  // render vertex) into storage buffers and compiles the program. Replaces what it held. Refuses, holding nothing,
  // when the context is not 4.3, the bind is malformed, or the driver rejects the shader (shader_log()).
  // Bind time: allocates, O(vertices + points).
  Status create(const GpuSkinningBind& bind);
  // Deletes the GL objects; holds nothing afterwards. Needs the context current when it holds anything.
  void release() noexcept;

  bool created() const noexcept { return program_ != 0; }
  bool has_normals() const noexcept { return has_normals_; }
  std::size_t vertex_count() const noexcept { return count_; }
  std::size_t bone_count() const noexcept { return bones_; }
  const std::string& shader_log() const noexcept { return shader_log_; }

  // Per frame: uploads the palette and writes every vertex's skinned position (and normal, with normals) into
  // `vertex_buffer` (a GLuint of at least vertex_count() vertices in `layout`; the other floats of each vertex are
  // left alone), then issues the barrier that lets the buffer be drawn, read, or added to by the next shader
  // (GpuLatticeFields::apply_into) right away.
  //  - LBS: `palette` as SkinningJob::matrices (LocalToWorldJob::palette, T_W · T_B⁻¹), one per bone.
  //  - DQS from the same matrices: converted by compute_dual_quat_palette on the CPU (O(bones), into storage sized
  //    at create()); the per-bone scale/shear is uploaded only when some bone has one, as SkinningJob::scales.
  // Refuses, writing nothing, when nothing was created, the palette size differs from bone_count() ("the palette
  // size differs from the bind's"), a DQS palette is singular or not finite (compute_dual_quat_palette's reason), the
  // layout does not fit its stride, or the buffer is 0 or too small. Palette entries are otherwise not checked (as
  // SkinningJob::run: a non-finite matrix gives non-finite vertices). No allocation.
  Status skin_into(SkinningMethod method, std::span<const glm::mat4> palette, unsigned int vertex_buffer,
                   const GpuVertexLayout& layout = {});
  // DQS with a palette already converted (compute_dual_quat_palette): `scales` empty for a rigid palette, else one
  // per bone (SkinningJob::scales). Refuses as above, and scales of another count.
  Status skin_into(std::span<const DualQuat> dual_quats, std::span<const glm::mat3> scales, unsigned int vertex_buffer,
                   const GpuVertexLayout& layout = {});
  // What skin_into() would refuse for a palette of `palette_size` bones, changing nothing (it asks GL for the
  // buffer's size).
  Status validate_into(std::size_t palette_size, unsigned int vertex_buffer, const GpuVertexLayout& layout = {}) const;

 private:
  struct Uniforms {
    int first_vertex = -1, vertex_count = -1, method = -1, scaled = -1, with_normals = -1, bones = -1, stride = -1,
        position_offset = -1, normal_offset = -1;
  };
  // The DQS palette into the palette buffer (8 floats per bone, then 9 per bone of scales when given).
  void upload_dqs(std::span<const DualQuat> dual_quats, std::span<const glm::mat3> scales);
  void dispatch(bool dqs, bool scaled, unsigned int vertex_buffer, const GpuVertexLayout& layout);

  unsigned int program_ = 0;
  unsigned int positions_ = 0, normals_ = 0, indices_ = 0, weights_ = 0, palette_ = 0;  // storage buffers
  Uniforms uniforms_;
  std::size_t count_ = 0;
  std::size_t bones_ = 0;
  bool has_normals_ = false;
  // Per-frame staging, sized at create(): the DQS conversion's outputs and the floats uploaded (16 per bone for LBS;
  // 8 + 9 for DQS: real x y z w, dual x y z w, then the scale matrix's 9 floats column by column).
  std::vector<DualQuat> dual_quats_;
  std::vector<glm::mat3> scales_;
  std::vector<float> staging_;
  std::string shader_log_;
};

}  // namespace deform
