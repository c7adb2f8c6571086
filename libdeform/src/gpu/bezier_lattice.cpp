// GpuBezierLattice (deform/gpu/lattice.hpp): the CPU kernel's arithmetic as an OpenGL 4.3 compute shader.
#include <epoxy/gl.h>  // first: epoxy must precede every other GL header

#include "deform/gpu/lattice.hpp"
#include "gl_objects.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <glm/gtc/type_ptr.hpp>

namespace deform {
namespace {

using gpu_detail::build_compute_program;
using gpu_detail::storage_buffer;

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "control points are uploaded as packed float triples");
static_assert(sizeof(GLuint) == sizeof(unsigned int), "GL object names are held as unsigned int");

constexpr GLuint group_size = 64;

// The CPU kernel's arithmetic (libdeform/src/runtime/simd/lattice_kernel.inl) in GLSL: Bernstein bases by de
// Casteljau's triangle, derivatives from the degree n − 1 basis, the contraction over u inside v inside w, and
// n' = cofactor(J)·(G·n) normalised, the input normal kept where the Jacobian is degenerate. upload() prepends the
// version and the degree as a constant, so each lattice gets its own program with loops of known length (unrolled,
// arrays in registers: several times faster on llvmpipe than a runtime degree).
constexpr const char* shader_body = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Targets { uint target[]; };        // per vertex: index in the output
layout(std430, binding = 1) readonly buffer Params { float param[]; };         // per vertex: u v w
layout(std430, binding = 2) readonly buffer RestNormals { float normal_in[]; }; // per vertex: nx ny nz
layout(std430, binding = 3) readonly buffer Points { float point[]; };         // control points, i-fastest, x y z
layout(std430, binding = 4) buffer Output { float result[]; };
layout(std430, binding = 5) readonly buffer Weights { float weight[]; };       // per vertex (additive only)
layout(std430, binding = 6) readonly buffer Mapped { float mapped[]; };        // additive with normals: the map's points

uniform uint first_vertex;
uniform uint vertex_count;
uniform mat3 normal_basis;
uniform bool with_normals;
uniform bool scatter;  // write at target[] (an interleaved vertex buffer) or at the vertex's own slot (read back)
uniform bool additive;  // add weight[] · Q to the position there instead of writing Q (control points = displacements)
// Additive with normals (with_normals && additive): turn the buffer's normal n by the map whose control points are
// mapped[] — n_l = cofactor(J)·(G·to_bind·n) normalised — blended by the weight: normalise(n + weight (n_l − n)).
uniform mat3 to_bind;
uniform float noise_floor2;  // (1e-5 · the largest coordinate of the points the Jacobian is summed from)²
uniform uint stride, position_offset, normal_offset;

const int max_points = 17;  // deform::max_bezier_degree + 1

void basis(int n, float t, out float b[max_points], out float d[max_points]) {
  float lower[max_points];
  float s = 1.0 - t;
  b[0] = 1.0;
  for (int r = 1; r <= n; ++r) {
    if (r == n)
      for (int i = 0; i < n; ++i) lower[i] = b[i];
    float saved = 0.0;
    for (int i = 0; i < r; ++i) {
      float tmp = b[i];
      b[i] = saved + s * tmp;
      saved = t * tmp;
    }
    b[r] = saved;
  }
  float fn = float(n);
  d[0] = lower[0] * -fn;
  for (int i = 1; i < n; ++i) d[i] = (lower[i - 1] - lower[i]) * fn;
  d[n] = lower[n - 1] * fn;
}

vec3 control_point(bool from_mapped, int index) {
  return from_mapped ? vec3(mapped[3 * index], mapped[3 * index + 1], mapped[3 * index + 2])
                     : vec3(point[3 * index], point[3 * index + 1], point[3 * index + 2]);
}

float bu[max_points], bv[max_points], bw[max_points], du[max_points], dv[max_points], dw[max_points];

// Q and, with derivatives, ∂Q/∂u, ∂Q/∂v, ∂Q/∂w of the control points point[] (or mapped[]).
void contract(bool from_mapped, bool derivatives, out vec3 q, out vec3 qu, out vec3 qv, out vec3 qw) {
  int nu = degree.x + 1, nv = degree.y + 1;
  q = vec3(0.0), qu = vec3(0.0), qv = vec3(0.0), qw = vec3(0.0);
  for (int k = 0; k <= degree.z; ++k) {
    vec3 s = vec3(0.0), su = vec3(0.0), sv = vec3(0.0);
    for (int j = 0; j <= degree.y; ++j) {
      int row = nu * (j + nv * k);
      vec3 r = vec3(0.0), rd = vec3(0.0);
      for (int i = 0; i <= degree.x; ++i) {
        vec3 p = control_point(from_mapped, row + i);
        r += bu[i] * p;
        if (derivatives) rd += du[i] * p;
      }
      s += bv[j] * r;
      if (derivatives) {
        sv += dv[j] * r;
        su += bv[j] * rd;
      }
    }
    q += bw[k] * s;
    if (derivatives) {
      qw += dw[k] * s;
      qv += bw[k] * sv;
      qu += bw[k] * su;
    }
  }
}

// n' = cofactor(J)·(G·n) normalised; `fallback` where the Jacobian is degenerate (a lattice collapsed to a point, onto
// a line, or nearly: its second singular value, |cof(J)·m| / (|J|·|m|), below 1e-5 of the points' largest
// coordinate, as the CPU kernel decides).
vec3 jacobian_normal(vec3 n_in, vec3 qu, vec3 qv, vec3 qw, vec3 fallback) {
  vec3 m = normal_basis * n_in;
  vec3 n = m.x * cross(qv, qw) + m.y * cross(qw, qu) + m.z * cross(qu, qv);
  float len2 = dot(n, n);
  float floor2 = noise_floor2 * (dot(qu, qu) + dot(qv, qv) + dot(qw, qw)) * dot(m, m);
  return len2 > floor2 && len2 <= 3.0e38 ? n * (1.0 / sqrt(len2)) : fallback;
}

void main() {
  uint e = first_vertex + gl_GlobalInvocationID.x;
  if (e >= vertex_count) return;
  basis(degree.x, param[3 * e], bu, du);
  basis(degree.y, param[3 * e + 1], bv, dv);
  basis(degree.z, param[3 * e + 2], bw, dw);

  vec3 q, qu, qv, qw;
  contract(false, with_normals && !additive, q, qu, qv, qw);

  uint base = (scatter ? target[e] : e) * stride;
  if (additive) {
    float we = weight[e];
    q *= we;
    result[base + position_offset] += q.x;
    result[base + position_offset + 1u] += q.y;
    result[base + position_offset + 2u] += q.z;
    if (!with_normals) return;
    // DeformerHierarchy::apply(positions, normals)'s normal, per render vertex.
    vec3 unused;
    contract(true, true, unused, qu, qv, qw);
    vec3 n0 = vec3(result[base + normal_offset], result[base + normal_offset + 1u], result[base + normal_offset + 2u]);
    vec3 n_bind = to_bind * n0;
    vec3 blended = n0 + we * (jacobian_normal(n_bind, qu, qv, qw, n0) - n0);  // degenerate: n0 kept, as on the CPU
    float length2 = dot(blended, blended);
    if (length2 > 1.0e-12) {
      blended = blended / sqrt(length2);
      result[base + normal_offset] = blended.x;
      result[base + normal_offset + 1u] = blended.y;
      result[base + normal_offset + 2u] = blended.z;
    }
    return;
  }
  result[base + position_offset] = q.x;
  result[base + position_offset + 1u] = q.y;
  result[base + position_offset + 2u] = q.z;
  if (with_normals) {
    vec3 n_in = vec3(normal_in[3 * e], normal_in[3 * e + 1], normal_in[3 * e + 2]);
    // A degenerate Jacobian (a collapsed lattice) has no normal to give: the input normal is kept.
    vec3 n = jacobian_normal(n_in, qu, qv, qw, n_in);
    result[base + normal_offset] = n.x;
    result[base + normal_offset + 1u] = n.y;
    result[base + normal_offset + 2u] = n.z;
  }
}
)";
Status check_binding(const LatticeBinding& binding) {
  if (!GpuBezierLattice::supported()) return Status::failure("the current context is not OpenGL 4.3");
  if (binding.kind != LatticeKind::bezier) return Status::failure("only Bezier bindings are evaluated on the GPU");
  if (glm::any(glm::lessThan(binding.point_counts, glm::ivec3(2))) ||
      glm::any(glm::greaterThan(binding.point_counts, glm::ivec3(max_bezier_degree + 1))))
    return Status::failure("the binding's degree is outside 1..max_bezier_degree");
  return {};
}

}  // namespace

GpuBezierLattice::GpuBezierLattice(GpuBezierLattice&& other) noexcept { *this = std::move(other); }

GpuBezierLattice& GpuBezierLattice::operator=(GpuBezierLattice&& other) noexcept {
  if (this == &other) return *this;
  release();
  program_ = std::exchange(other.program_, 0);
  targets_ = std::exchange(other.targets_, 0);
  params_ = std::exchange(other.params_, 0);
  normals_ = std::exchange(other.normals_, 0);
  points_ = std::exchange(other.points_, 0);
  results_ = std::exchange(other.results_, 0);
  weights_ = std::exchange(other.weights_, 0);
  mapped_ = std::exchange(other.mapped_, 0);
  uniforms_ = std::exchange(other.uniforms_, Uniforms{});
  count_ = std::exchange(other.count_, 0);
  max_target_ = std::exchange(other.max_target_, 0);
  point_counts_ = std::exchange(other.point_counts_, glm::ivec3(0));
  normal_basis_ = std::exchange(other.normal_basis_, glm::mat3(1.0f));
  has_normals_ = std::exchange(other.has_normals_, false);
  additive_ = std::exchange(other.additive_, false);
  target_list_ = std::move(other.target_list_);
  staging_ = std::move(other.staging_);
  shader_log_ = std::move(other.shader_log_);
  other.target_list_.clear();
  other.staging_.clear();
  other.shader_log_.clear();
  return *this;
}

GpuBezierLattice::~GpuBezierLattice() { release(); }

void GpuBezierLattice::release() noexcept {
  const GLuint buffers[] = {targets_, params_, normals_, points_, results_, weights_, mapped_};
  for (GLuint b : buffers)
    if (b) glDeleteBuffers(1, &b);
  if (program_) glDeleteProgram(program_);
  program_ = targets_ = params_ = normals_ = points_ = results_ = weights_ = mapped_ = 0;
  uniforms_ = Uniforms{};
  count_ = 0;
  max_target_ = 0;
  point_counts_ = glm::ivec3(0);
  has_normals_ = additive_ = false;
  target_list_.clear();
  staging_.clear();
}

bool GpuBezierLattice::supported() { return epoxy_is_desktop_gl() && epoxy_gl_version() >= 43; }

Status GpuBezierLattice::create(const LatticeBinding& binding, std::span<const glm::vec3> rest_normals) {
  release();
  shader_log_.clear();
  if (const Status status = check_binding(binding); !status) return status;
  const bool normals = !rest_normals.empty();
  if (normals && binding.vertex_count > 0 && rest_normals.size() <= binding.max_vertex)
    return Status::failure("the rest normals do not cover every bound vertex");

  std::vector<float> params, normal_list;
  for (std::size_t lane = 0; lane < binding.vertices.size(); ++lane) {
    const std::uint32_t vertex = binding.vertices[lane];
    if (vertex == LatticeBinding::no_vertex) continue;
    target_list_.push_back(vertex);
    params.insert(params.end(), {binding.u[lane], binding.v[lane], binding.w[lane]});
    if (normals) {
      const glm::vec3 n = rest_normals[vertex];
      normal_list.insert(normal_list.end(), {n.x, n.y, n.z});
    }
  }
  return upload(binding.point_counts, binding.normal_basis, params, normal_list, {});
}

Status GpuBezierLattice::create_additive(const LatticeBinding& binding, std::span<const float> weights,
                                         std::span<const std::uint32_t> vertex_point, bool normals) {
  release();
  shader_log_.clear();
  if (const Status status = check_binding(binding); !status) return status;
  if (weights.size() != binding.vertices.size()) return Status::failure("one weight per binding lane is needed");
  // Each bound point's lane, then one entry per render vertex of a bound point (a point split at a UV or normal
  // seam is evaluated once per render vertex, as in create()).
  std::vector<std::uint32_t> lane_of_point(binding.vertex_count ? std::size_t{binding.max_vertex} + 1 : 0,
                                           LatticeBinding::no_vertex);
  for (std::size_t lane = 0; lane < binding.vertices.size(); ++lane) {
    const std::uint32_t point = binding.vertices[lane];
    if (point != LatticeBinding::no_vertex) lane_of_point[point] = std::uint32_t(lane);
  }
  std::vector<float> params, weight_list;
  for (std::size_t r = 0; r < vertex_point.size(); ++r) {
    const std::uint32_t point = vertex_point[r];
    if (point >= lane_of_point.size() || lane_of_point[point] == LatticeBinding::no_vertex) continue;
    const std::size_t lane = lane_of_point[point];
    target_list_.push_back(std::uint32_t(r));
    params.insert(params.end(), {binding.u[lane], binding.v[lane], binding.w[lane]});
    weight_list.push_back(weights[lane]);
  }
  const Status status = upload(binding.point_counts, binding.normal_basis, params, {}, weight_list);
  additive_ = status.ok();
  if (status && normals) {  // the normals are the buffer's own: only the mapped points' storage is needed
    has_normals_ = true;
    mapped_ = storage_buffer(nullptr, binding.control_point_count() * sizeof(glm::vec3), GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  }
  return status;
}

Status GpuBezierLattice::upload(glm::ivec3 point_counts, const glm::mat3& normal_basis, std::span<const float> params,
                                std::span<const float> normals, std::span<const float> weights) {
  const glm::ivec3 d = point_counts - 1;
  const std::string source = "#version 430\nconst ivec3 degree = ivec3(" + std::to_string(d.x) + ", " +
                             std::to_string(d.y) + ", " + std::to_string(d.z) + ");\n" + shader_body;
  program_ = build_compute_program(source.c_str(), shader_log_);
  if (!program_) {
    release();
    return Status::failure("the driver rejected the compute shader (shader_log() has its message)");
  }
  const auto location = [&](const char* name) { return glGetUniformLocation(program_, name); };
  uniforms_ = {location("first_vertex"), location("vertex_count"),    location("normal_basis"),
               location("with_normals"), location("scatter"),         location("additive"),
               location("stride"),       location("position_offset"), location("normal_offset"),
               location("to_bind"),      location("noise_floor2")};

  count_ = target_list_.size();
  max_target_ = count_ ? *std::max_element(target_list_.begin(), target_list_.end()) : 0;
  point_counts_ = point_counts;
  normal_basis_ = normal_basis;
  has_normals_ = !normals.empty();
  targets_ = storage_buffer(target_list_.data(), target_list_.size() * sizeof(std::uint32_t), GL_STATIC_DRAW);
  params_ = storage_buffer(params.data(), params.size() * sizeof(float), GL_STATIC_DRAW);
  normals_ = storage_buffer(normals.data(), normals.size() * sizeof(float), GL_STATIC_DRAW);
  weights_ = storage_buffer(weights.data(), weights.size() * sizeof(float), GL_STATIC_DRAW);
  const std::size_t point_count =
      std::size_t(point_counts.x) * std::size_t(point_counts.y) * std::size_t(point_counts.z);
  points_ = storage_buffer(nullptr, point_count * sizeof(glm::vec3), GL_STREAM_DRAW);
  staging_.assign(count_ * 6, 0.0f);
  results_ = storage_buffer(nullptr, staging_.size() * sizeof(float), GL_STREAM_READ);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  return {};
}

void GpuBezierLattice::dispatch(std::span<const glm::vec3> control_points, unsigned int output, bool scatter,
                                const GpuVertexLayout& layout, std::span<const glm::vec3> mapped_points,
                                const glm::mat3& to_bind) {
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, points_);
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(control_points.size() * sizeof(glm::vec3)),
                  control_points.data());
  if (!mapped_points.empty()) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, mapped_);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(mapped_points.size() * sizeof(glm::vec3)),
                    mapped_points.data());
  }
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  if (count_ == 0) return;

  glUseProgram(program_);
  glUniform1ui(uniforms_.vertex_count, GLuint(count_));
  glUniformMatrix3fv(uniforms_.normal_basis, 1, GL_FALSE, glm::value_ptr(normal_basis_));
  glUniform1i(uniforms_.with_normals, has_normals_ ? 1 : 0);
  glUniform1i(uniforms_.scatter, scatter ? 1 : 0);
  glUniform1i(uniforms_.additive, additive_ ? 1 : 0);
  glUniform1ui(uniforms_.stride, GLuint(layout.floats_per_vertex));
  glUniform1ui(uniforms_.position_offset, GLuint(layout.position_offset));
  glUniform1ui(uniforms_.normal_offset, GLuint(layout.normal_offset));
  glUniformMatrix3fv(uniforms_.to_bind, 1, GL_FALSE, glm::value_ptr(to_bind));
  // The degenerate-normal floor of the CPU kernel (lattice_kernel.inl, degenerate_normal), from the points the
  // normals' Jacobian is summed from: the mapped points when adding, else the control points.
  float largest = 0.0f;
  for (const glm::vec3& p : additive_ && !mapped_points.empty() ? mapped_points : control_points)
    largest = std::max({largest, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  glUniform1f(uniforms_.noise_floor2, 1e-10f * largest * largest);
  // An unused binding still gets a buffer (the points): every declared block is backed.
  const GLuint buffers[] = {targets_, params_, normals_, points_, output, weights_, mapped_ ? mapped_ : points_};
  for (GLuint i = 0; i < 7; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, buffers[i]);

  // Dispatches of at most 65,535 groups (the least every 4.3 driver allows), 4 million vertices each.
  const std::size_t per_dispatch = std::size_t{65535} * group_size;
  for (std::size_t first = 0; first < count_; first += per_dispatch) {
    const std::size_t n = std::min(per_dispatch, count_ - first);
    glUniform1ui(uniforms_.first_vertex, GLuint(first));
    glDispatchCompute(GLuint((n + group_size - 1) / group_size), 1, 1);
  }
  for (GLuint i = 0; i < 7; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
  glUseProgram(0);
}

Status GpuBezierLattice::evaluate(std::span<const glm::vec3> control_points) {
  if (!program_) return Status::failure("nothing was created");
  if (additive_) return Status::failure("an additive lattice only adds into a vertex buffer");
  if (control_points.size() !=
      std::size_t(point_counts_.x) * std::size_t(point_counts_.y) * std::size_t(point_counts_.z))
    return Status::failure("the control point count differs from the binding's");
  dispatch(control_points, results_, false, GpuVertexLayout{6, 0, 3});
  return {};
}

Status GpuBezierLattice::read_back(std::span<glm::vec3> positions, std::span<glm::vec3> normals) {
  if (!program_) return Status::failure("nothing was created");
  if (additive_) return Status::failure("an additive lattice only adds into a vertex buffer");
  if (count_ == 0) return {};
  if (positions.size() <= max_target_ || (!normals.empty() && normals.size() <= max_target_))
    return Status::failure("the spans do not cover every bound vertex");
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, results_);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(staging_.size() * sizeof(float)), staging_.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  const bool with_normals = has_normals_ && !normals.empty();
  for (std::size_t e = 0; e < count_; ++e) {
    const float* r = staging_.data() + 6 * e;
    positions[target_list_[e]] = glm::vec3(r[0], r[1], r[2]);
    if (with_normals) normals[target_list_[e]] = glm::vec3(r[3], r[4], r[5]);
  }
  return {};
}

Status GpuBezierLattice::validate_into(std::span<const glm::vec3> control_points, unsigned int vertex_buffer,
                                       const GpuVertexLayout& layout) const {
  if (!program_) return Status::failure("nothing was created");
  if (control_points.size() !=
      std::size_t(point_counts_.x) * std::size_t(point_counts_.y) * std::size_t(point_counts_.z))
    return Status::failure("the control point count differs from the binding's");
  if (layout.floats_per_vertex <= 0 || layout.position_offset < 0 || layout.normal_offset < 0 ||
      layout.position_offset + 3 > layout.floats_per_vertex || layout.normal_offset + 3 > layout.floats_per_vertex)
    return Status::failure("the vertex layout does not fit its stride");
  if (vertex_buffer == 0) return Status::failure("no vertex buffer");
  if (count_ > 0) {  // the buffer must hold every vertex written
    GLint64 bytes = 0;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_buffer);
    glGetBufferParameteri64v(GL_SHADER_STORAGE_BUFFER, GL_BUFFER_SIZE, &bytes);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    const std::size_t needed = (std::size_t{max_target_} + 1) * std::size_t(layout.floats_per_vertex) * sizeof(float);
    if (bytes < 0 || std::size_t(bytes) < needed) return Status::failure("the vertex buffer is too small");
  }
  return {};
}

Status GpuBezierLattice::evaluate_into(std::span<const glm::vec3> control_points, unsigned int vertex_buffer,
                                       const GpuVertexLayout& layout) {
  if (additive_ && has_normals_)
    return Status::failure("an additive lattice with normals also takes its mapped points and to_bind");
  if (const Status status = validate_into(control_points, vertex_buffer, layout); !status) return status;
  dispatch(control_points, vertex_buffer, true, layout);
  glMemoryBarrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  return {};
}

}  // namespace deform

namespace deform {

Status GpuBezierLattice::validate_into(std::span<const glm::vec3> displacements,
                                       std::span<const glm::vec3> mapped_points, unsigned int vertex_buffer,
                                       const GpuVertexLayout& layout) const {
  if (!program_) return Status::failure("nothing was created");
  if (!additive_ || !has_normals_) return Status::failure("not an additive lattice with normals");
  if (mapped_points.size() != displacements.size())
    return Status::failure("the mapped point count differs from the binding's");
  return validate_into(displacements, vertex_buffer, layout);
}

Status GpuBezierLattice::evaluate_into(std::span<const glm::vec3> displacements,
                                       std::span<const glm::vec3> mapped_points, const glm::mat3& to_bind,
                                       unsigned int vertex_buffer, const GpuVertexLayout& layout) {
  if (const Status status = validate_into(displacements, mapped_points, vertex_buffer, layout); !status) return status;
  dispatch(displacements, vertex_buffer, true, layout, mapped_points, to_bind);
  glMemoryBarrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  return {};
}

}  // namespace deform
