// GpuSkinning (deform/gpu/skinning.hpp): SkinningJob's portable kernels
// (libdeform/src/runtime/simd/skinning_portable.cpp) as an OpenGL 4.3 compute shader.
#include <epoxy/gl.h>  // first: epoxy must precede every other GL header

#include "deform/gpu/skinning.hpp"
#include "gl_objects.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

namespace deform {
namespace {

using gpu_detail::storage_buffer;

static_assert(sizeof(glm::mat4) == 16 * sizeof(float), "palettes are uploaded as packed column-major floats");
static_assert(sizeof(glm::u16vec4) == 8, "bone indices are uploaded as two 16-bit pairs per vertex");

constexpr GLuint group_size = 64;
constexpr std::size_t max_bones = 65536;  // SkinningJob's limit

// The portable CPU kernels' arithmetic, term for term, so that the two agree to float rounding (a driver may fuse
// multiply-adds where the CPU does not, as the AVX2/AVX-512 kernels do). Per vertex: the four influences' palette
// entries blended with their weights; LBS divides by the weight sum and maps the normal by the cofactor of the
// blended 3×3; DQS blends each dual quaternion in the hemisphere of the first influence's (antipodality), normalises
// by the real part's length, and for scaled palettes first applies the weight-normalised blend of the scale/shear
// matrices (the normal by its cofactor). Normals are renormalised; a zero normal stays zero.
constexpr const char* shader_source = R"(#version 430
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Positions { float position_in[]; };  // per vertex: x y z
layout(std430, binding = 1) readonly buffer Normals { float normal_in[]; };      // per vertex: nx ny nz
layout(std430, binding = 2) readonly buffer Indices { uint index_pair[]; };      // per vertex: 2 × (16 | 16 bits)
layout(std430, binding = 3) readonly buffer Weights { vec4 weight[]; };          // per vertex
// LBS: 16 floats per bone (a column-major mat4). DQS: 8 per bone (real x y z w, dual x y z w), then, scaled, 9 per
// bone from float 8 · bones on (the scale matrix, column by column).
layout(std430, binding = 4) readonly buffer Palette { float palette[]; };
layout(std430, binding = 5) buffer Output { float result[]; };

uniform uint first_vertex;
uniform uint vertex_count;
uniform int method;  // 0 LBS, 1 DQS
uniform bool scaled;
uniform bool with_normals;
uniform uint bones;
uniform uint stride, position_offset, normal_offset;

vec3 column(uint bone, uint c) {
  uint base = 16u * bone + 4u * c;
  return vec3(palette[base], palette[base + 1u], palette[base + 2u]);
}
vec4 quat_at(uint base) { return vec4(palette[base], palette[base + 1u], palette[base + 2u], palette[base + 3u]); }
mat3 scale_of(uint bone) {
  uint base = 8u * bones + 9u * bone;
  return mat3(palette[base], palette[base + 1u], palette[base + 2u], palette[base + 3u], palette[base + 4u],
              palette[base + 5u], palette[base + 6u], palette[base + 7u], palette[base + 8u]);
}
vec3 normalize_or_zero(vec3 n) {
  float length_squared = dot(n, n);
  return length_squared > 0.0 ? n / sqrt(length_squared) : n;
}
vec3 cofactor_times(vec3 a0, vec3 a1, vec3 a2, vec3 n) {
  return cross(a1, a2) * n.x + cross(a2, a0) * n.y + cross(a0, a1) * n.z;
}
vec3 rotate(vec4 q, vec3 v) { return v + 2.0 * cross(q.xyz, cross(q.xyz, v) + q.w * v); }

void main() {
  uint e = first_vertex + gl_GlobalInvocationID.x;
  if (e >= vertex_count) return;
  uvec4 b = uvec4(index_pair[2u * e] & 0xFFFFu, index_pair[2u * e] >> 16, index_pair[2u * e + 1u] & 0xFFFFu,
                  index_pair[2u * e + 1u] >> 16);
  vec4 w = weight[e];
  vec3 p = vec3(position_in[3u * e], position_in[3u * e + 1u], position_in[3u * e + 2u]);
  vec3 n = vec3(0.0);
  if (with_normals) n = vec3(normal_in[3u * e], normal_in[3u * e + 1u], normal_in[3u * e + 2u]);
  vec3 out_p;
  if (method == 0) {
    vec3 a0 = vec3(0.0), a1 = vec3(0.0), a2 = vec3(0.0), t = vec3(0.0);
    for (int k = 0; k < 4; ++k) {
      a0 += w[k] * column(b[k], 0u);
      a1 += w[k] * column(b[k], 1u);
      a2 += w[k] * column(b[k], 2u);
      t += w[k] * column(b[k], 3u);
    }
    float inverse_sum = 1.0 / (w.x + w.y + w.z + w.w);
    out_p = (a0 * p.x + a1 * p.y + a2 * p.z + t) * inverse_sum;
    n = normalize_or_zero(cofactor_times(a0, a1, a2, n));
  } else {
    vec4 pivot = quat_at(8u * b[0]);
    vec4 real = vec4(0.0), dual = vec4(0.0);
    mat3 scale = mat3(0.0);
    for (int k = 0; k < 4; ++k) {
      vec4 qr = quat_at(8u * b[k]);
      // q and -q are the same transform: blend each in the hemisphere of the first influence.
      float signed_weight = dot(qr, pivot) < 0.0 ? -w[k] : w[k];
      real += signed_weight * qr;
      dual += signed_weight * quat_at(8u * b[k] + 4u);
      if (scaled) scale += w[k] * scale_of(b[k]);
    }
    float inverse_length = 1.0 / sqrt(dot(real, real));
    real *= inverse_length;
    dual *= inverse_length;
    vec3 translation = 2.0 * (real.w * dual.xyz - dual.w * real.xyz + cross(real.xyz, dual.xyz));
    if (scaled) {
      scale *= 1.0 / (w.x + w.y + w.z + w.w);
      p = scale * p;
      n = cofactor_times(scale[0], scale[1], scale[2], n);
    }
    out_p = rotate(real, p) + translation;
    n = normalize_or_zero(rotate(real, n));
  }
  uint base = e * stride;
  result[base + position_offset] = out_p.x;
  result[base + position_offset + 1u] = out_p.y;
  result[base + position_offset + 2u] = out_p.z;
  if (with_normals) {
    result[base + normal_offset] = n.x;
    result[base + normal_offset + 1u] = n.y;
    result[base + normal_offset + 2u] = n.z;
  }
}
)";

}  // namespace

GpuSkinning::GpuSkinning(GpuSkinning&& other) noexcept { *this = std::move(other); }

GpuSkinning& GpuSkinning::operator=(GpuSkinning&& other) noexcept {
  if (this == &other) return *this;
  release();
  program_ = std::exchange(other.program_, 0);
  positions_ = std::exchange(other.positions_, 0);
  normals_ = std::exchange(other.normals_, 0);
  indices_ = std::exchange(other.indices_, 0);
  weights_ = std::exchange(other.weights_, 0);
  palette_ = std::exchange(other.palette_, 0);
  uniforms_ = std::exchange(other.uniforms_, Uniforms{});
  count_ = std::exchange(other.count_, 0);
  bones_ = std::exchange(other.bones_, 0);
  has_normals_ = std::exchange(other.has_normals_, false);
  dual_quats_ = std::move(other.dual_quats_);
  scales_ = std::move(other.scales_);
  staging_ = std::move(other.staging_);
  shader_log_ = std::move(other.shader_log_);
  other.dual_quats_.clear();
  other.scales_.clear();
  other.staging_.clear();
  other.shader_log_.clear();
  return *this;
}

GpuSkinning::~GpuSkinning() { release(); }

void GpuSkinning::release() noexcept {
  const GLuint buffers[] = {positions_, normals_, indices_, weights_, palette_};
  for (GLuint b : buffers)
    if (b) glDeleteBuffers(1, &b);
  if (program_) glDeleteProgram(program_);
  program_ = positions_ = normals_ = indices_ = weights_ = palette_ = 0;
  uniforms_ = Uniforms{};
  count_ = bones_ = 0;
  has_normals_ = false;
  dual_quats_.clear();
  scales_.clear();
  staging_.clear();
}

bool GpuSkinning::supported() { return epoxy_is_desktop_gl() && epoxy_gl_version() >= 43; }

Status GpuSkinning::create(const GpuSkinningBind& bind) {
  release();
  shader_log_.clear();
  if (!supported()) return Status::failure("the current context is not OpenGL 4.3");
  if (bind.bone_count == 0) return Status::failure("palette is empty");
  if (bind.bone_count > max_bones) return Status::failure("palette has more than 65536 bones");
  const std::size_t points = bind.positions.size();
  if (bind.bone_indices.size() != points || bind.bone_weights.size() != points)
    return Status::failure("bone indices, weights and positions differ in count");
  const std::size_t count = bind.vertex_point.empty() ? points : bind.vertex_point.size();
  for (const std::uint32_t p : bind.vertex_point)
    if (p >= points) return Status::failure("a vertex_point entry is not a point");
  if (!bind.normals.empty() && bind.normals.size() != count)
    return Status::failure("the normals are not one per render vertex");
  // SkinningJob's own checks of the indices and weights, with its reasons, over an identity palette of the size.
  {
    const std::vector<glm::mat4> identity(bind.bone_count, glm::mat4(1.0f));
    std::vector<glm::vec3> out(points);
    SkinningJob job;
    job.matrices = identity;
    job.bone_indices = bind.bone_indices;
    job.bone_weights = bind.bone_weights;
    job.in_positions = as_floats(bind.positions);
    job.out_positions = as_floats(out);
    if (const Status status = job.validate(); !status) return status;
  }

  // Gathered per render vertex.
  std::vector<float> positions, normals, weights;
  std::vector<std::uint32_t> indices;
  positions.reserve(count * 3);
  indices.reserve(count * 2);
  weights.reserve(count * 4);
  for (std::size_t r = 0; r < count; ++r) {
    const std::size_t p = bind.vertex_point.empty() ? r : bind.vertex_point[r];
    const glm::vec3 x = bind.positions[p];
    const glm::u16vec4 b = bind.bone_indices[p];
    const glm::vec4 w = bind.bone_weights[p];
    positions.insert(positions.end(), {x.x, x.y, x.z});
    indices.insert(indices.end(),
                   {std::uint32_t(b.x) | std::uint32_t(b.y) << 16, std::uint32_t(b.z) | std::uint32_t(b.w) << 16});
    weights.insert(weights.end(), {w.x, w.y, w.z, w.w});
    if (!bind.normals.empty()) {
      const glm::vec3 n = bind.normals[r];
      normals.insert(normals.end(), {n.x, n.y, n.z});
    }
  }

  program_ = gpu_detail::build_compute_program(shader_source, shader_log_);
  if (!program_) {
    release();
    return Status::failure("the driver rejected the compute shader (shader_log() has its message)");
  }
  const auto location = [&](const char* name) { return glGetUniformLocation(program_, name); };
  uniforms_ = {location("first_vertex"), location("vertex_count"),    location("method"),
               location("scaled"),       location("with_normals"),    location("bones"),
               location("stride"),       location("position_offset"), location("normal_offset")};
  count_ = count;
  bones_ = bind.bone_count;
  has_normals_ = !bind.normals.empty();
  positions_ = storage_buffer(positions.data(), positions.size() * sizeof(float), GL_STATIC_DRAW);
  normals_ = storage_buffer(normals.data(), normals.size() * sizeof(float), GL_STATIC_DRAW);
  indices_ = storage_buffer(indices.data(), indices.size() * sizeof(std::uint32_t), GL_STATIC_DRAW);
  weights_ = storage_buffer(weights.data(), weights.size() * sizeof(float), GL_STATIC_DRAW);
  staging_.assign(bones_ * 17, 0.0f);  // the larger of LBS's 16 and DQS's 8 + 9 floats per bone
  palette_ = storage_buffer(nullptr, staging_.size() * sizeof(float), GL_STREAM_DRAW);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  dual_quats_.assign(bones_, DualQuat{});
  scales_.assign(bones_, glm::mat3(1.0f));
  return {};
}

Status GpuSkinning::validate_into(std::size_t palette_size, unsigned int vertex_buffer,
                                  const GpuVertexLayout& layout) const {
  if (!program_) return Status::failure("nothing was created");
  if (palette_size != bones_) return Status::failure("the palette size differs from the bind's");
  if (layout.floats_per_vertex <= 0 || layout.position_offset < 0 || layout.normal_offset < 0 ||
      layout.position_offset + 3 > layout.floats_per_vertex || layout.normal_offset + 3 > layout.floats_per_vertex)
    return Status::failure("the vertex layout does not fit its stride");
  if (vertex_buffer == 0) return Status::failure("no vertex buffer");
  if (count_ > 0) {  // the buffer must hold every vertex written
    GLint64 bytes = 0;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_buffer);
    glGetBufferParameteri64v(GL_SHADER_STORAGE_BUFFER, GL_BUFFER_SIZE, &bytes);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    const std::size_t needed = count_ * std::size_t(layout.floats_per_vertex) * sizeof(float);
    if (bytes < 0 || std::size_t(bytes) < needed) return Status::failure("the vertex buffer is too small");
  }
  return {};
}

Status GpuSkinning::skin_into(SkinningMethod method, std::span<const glm::mat4> palette, unsigned int vertex_buffer,
                              const GpuVertexLayout& layout) {
  if (method != SkinningMethod::lbs && method != SkinningMethod::dqs) return Status::failure("unknown skinning method");
  if (const Status status = validate_into(palette.size(), vertex_buffer, layout); !status) return status;
  if (method == SkinningMethod::dqs) {
    bool has_scale = false;
    if (const Status status = compute_dual_quat_palette(palette, dual_quats_, scales_, has_scale); !status)
      return status;
    upload_dqs(dual_quats_, has_scale ? std::span<const glm::mat3>(scales_) : std::span<const glm::mat3>{});
    dispatch(true, has_scale, vertex_buffer, layout);
    return {};
  }
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, palette_);
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(palette.size_bytes()), palette.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  dispatch(false, false, vertex_buffer, layout);
  return {};
}

Status GpuSkinning::skin_into(std::span<const DualQuat> dual_quats, std::span<const glm::mat3> scales,
                              unsigned int vertex_buffer, const GpuVertexLayout& layout) {
  if (const Status status = validate_into(dual_quats.size(), vertex_buffer, layout); !status) return status;
  if (!scales.empty() && scales.size() != dual_quats.size())
    return Status::failure("scales and dual quaternions differ in count");
  upload_dqs(dual_quats, scales);
  dispatch(true, !scales.empty(), vertex_buffer, layout);
  return {};
}

void GpuSkinning::upload_dqs(std::span<const DualQuat> dual_quats, std::span<const glm::mat3> scales) {
  // glm::quat's member order depends on GLM_FORCE_QUAT_DATA_WXYZ: written out by name, x y z w.
  float* out = staging_.data();
  for (const DualQuat& q : dual_quats) {
    const float bone[8] = {q.real.x, q.real.y, q.real.z, q.real.w, q.dual.x, q.dual.y, q.dual.z, q.dual.w};
    std::memcpy(out, bone, sizeof bone);
    out += 8;
  }
  for (const glm::mat3& s : scales) {
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) *out++ = s[c][r];
  }
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, palette_);
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr((out - staging_.data()) * sizeof(float)), staging_.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
}

void GpuSkinning::dispatch(bool dqs, bool scaled, unsigned int vertex_buffer, const GpuVertexLayout& layout) {
  if (count_ == 0) return;
  glUseProgram(program_);
  glUniform1ui(uniforms_.vertex_count, GLuint(count_));
  glUniform1i(uniforms_.method, dqs ? 1 : 0);
  glUniform1i(uniforms_.scaled, scaled ? 1 : 0);
  glUniform1i(uniforms_.with_normals, has_normals_ ? 1 : 0);
  glUniform1ui(uniforms_.bones, GLuint(bones_));
  glUniform1ui(uniforms_.stride, GLuint(layout.floats_per_vertex));
  glUniform1ui(uniforms_.position_offset, GLuint(layout.position_offset));
  glUniform1ui(uniforms_.normal_offset, GLuint(layout.normal_offset));
  const GLuint buffers[] = {positions_, normals_, indices_, weights_, palette_, vertex_buffer};
  for (GLuint i = 0; i < 6; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, buffers[i]);
  // Dispatches of at most 65,535 groups (the least every 4.3 driver allows), 4 million vertices each.
  const std::size_t per_dispatch = std::size_t{65535} * group_size;
  for (std::size_t first = 0; first < count_; first += per_dispatch) {
    const std::size_t n = std::min(per_dispatch, count_ - first);
    glUniform1ui(uniforms_.first_vertex, GLuint(first));
    glDispatchCompute(GLuint((n + group_size - 1) / group_size), 1, 1);
  }
  for (GLuint i = 0; i < 6; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
  glUseProgram(0);
  // The next draw (vertex fetch), read back, or shader adding to the buffer (GpuLatticeFields) sees the writes.
  glMemoryBarrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

}  // namespace deform
