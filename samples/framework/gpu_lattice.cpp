#include "gpu_lattice.hpp"  // epoxy first: it must precede every other GL header

#include <algorithm>
#include <string>

#include <GLFW/glfw3.h>
#include <glm/gtc/type_ptr.hpp>

#include "framework.hpp"

namespace sample {
namespace {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "control points are uploaded as packed float triples");

constexpr GLuint group_size = 64;

// The CPU kernel's arithmetic (libdeform/src/lattice_kernel.inl) in GLSL: Bernstein bases by de Casteljau's triangle,
// derivatives from the degree n − 1 basis, the contraction over u inside v inside w, and n' = cofactor(J)·(G·n)
// normalised, the input normal kept where the Jacobian is degenerate. create() prepends the version and the degree
// as a constant, so each lattice gets its own program with loops of known length (unrolled, arrays in registers:
// several times faster on llvmpipe than a runtime degree).
constexpr const char* shader_body = R"(
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Targets { uint target[]; };        // per vertex: index in the output
layout(std430, binding = 1) readonly buffer Params { float param[]; };         // per vertex: u v w
layout(std430, binding = 2) readonly buffer RestNormals { float normal_in[]; }; // per vertex: nx ny nz
layout(std430, binding = 3) readonly buffer Points { float point[]; };         // control points, i-fastest, x y z
layout(std430, binding = 4) buffer Output { float result[]; };
layout(std430, binding = 5) readonly buffer Weights { float weight[]; };       // per vertex (additive only)

uniform uint first_vertex;
uniform uint vertex_count;
uniform mat3 normal_basis;
uniform bool with_normals;
uniform bool scatter;  // write at target[] (an interleaved vertex buffer) or at the vertex's own slot (read back)
uniform bool additive;  // add weight[] · Q to the position there instead of writing Q (control points = displacements)
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

vec3 control_point(int index) {
  return vec3(point[3 * index], point[3 * index + 1], point[3 * index + 2]);
}

void main() {
  uint e = first_vertex + gl_GlobalInvocationID.x;
  if (e >= vertex_count) return;
  float bu[max_points], bv[max_points], bw[max_points], du[max_points], dv[max_points], dw[max_points];
  basis(degree.x, param[3 * e], bu, du);
  basis(degree.y, param[3 * e + 1], bv, dv);
  basis(degree.z, param[3 * e + 2], bw, dw);

  int nu = degree.x + 1, nv = degree.y + 1;
  vec3 q = vec3(0.0), qu = vec3(0.0), qv = vec3(0.0), qw = vec3(0.0);
  for (int k = 0; k <= degree.z; ++k) {
    vec3 s = vec3(0.0), su = vec3(0.0), sv = vec3(0.0);
    for (int j = 0; j <= degree.y; ++j) {
      int row = nu * (j + nv * k);
      vec3 r = vec3(0.0), rd = vec3(0.0);
      for (int i = 0; i <= degree.x; ++i) {
        vec3 p = control_point(row + i);
        r += bu[i] * p;
        if (with_normals) rd += du[i] * p;
      }
      s += bv[j] * r;
      if (with_normals) {
        sv += dv[j] * r;
        su += bv[j] * rd;
      }
    }
    q += bw[k] * s;
    if (with_normals) {
      qw += dw[k] * s;
      qv += bw[k] * sv;
      qu += bw[k] * su;
    }
  }

  uint base = (scatter ? target[e] : e) * stride;
  if (additive) {
    q *= weight[e];
    result[base + position_offset] += q.x;
    result[base + position_offset + 1u] += q.y;
    result[base + position_offset + 2u] += q.z;
    return;
  }
  result[base + position_offset] = q.x;
  result[base + position_offset + 1u] = q.y;
  result[base + position_offset + 2u] = q.z;
  if (with_normals) {
    vec3 n_in = vec3(normal_in[3 * e], normal_in[3 * e + 1], normal_in[3 * e + 2]);
    vec3 m = normal_basis * n_in;
    vec3 n = m.x * cross(qv, qw) + m.y * cross(qw, qu) + m.z * cross(qu, qv);
    float len2 = dot(n, n);
    // A degenerate Jacobian (a collapsed lattice) has no normal to give: the input normal is kept.
    n = len2 > 0.0 && len2 <= 3.0e38 ? n * (1.0 / sqrt(len2)) : n_in;
    result[base + normal_offset] = n.x;
    result[base + normal_offset + 1u] = n.y;
    result[base + normal_offset + 2u] = n.z;
  }
}
)";

GLuint storage_buffer(const void* data, std::size_t bytes, GLenum usage) {
  GLuint buffer = 0;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
  // Never zero bytes: an empty binding still binds valid storage.
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<std::size_t>(bytes, 16)), nullptr, usage);
  if (data && bytes) glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), data);
  return buffer;
}

}  // namespace

GpuBezierLattice::~GpuBezierLattice() { release(); }

void GpuBezierLattice::release() {
  // A sample's lattice may outlive its window: with no context left there is nothing to delete (asked quietly, since
  // GLFW may already be terminated).
  if (program_) {
    const GLFWerrorfun previous = glfwSetErrorCallback(nullptr);
    if (!glfwGetCurrentContext()) program_ = targets_ = params_ = normals_ = points_ = results_ = weights_ = 0;
    glfwSetErrorCallback(previous);
  }
  const GLuint buffers[] = {targets_, params_, normals_, points_, results_, weights_};
  for (GLuint b : buffers)
    if (b) glDeleteBuffers(1, &b);
  if (program_) glDeleteProgram(program_);
  program_ = targets_ = params_ = normals_ = points_ = results_ = weights_ = 0;
  count_ = 0;
  has_normals_ = additive_ = false;
}

bool GpuBezierLattice::supported() { return epoxy_gl_version() >= 43; }

namespace {

bool usable(const deform::LatticeBinding& binding) {
  return GpuBezierLattice::supported() && binding.kind == deform::LatticeKind::bezier &&
         !glm::any(glm::lessThan(binding.point_counts, glm::ivec3(2))) &&
         !glm::any(glm::greaterThan(binding.point_counts, glm::ivec3(deform::max_bezier_degree + 1)));
}

}  // namespace

bool GpuBezierLattice::create(const deform::LatticeBinding& binding, std::span<const glm::vec3> rest_normals) {
  release();
  if (!usable(binding)) return false;
  const bool normals = !rest_normals.empty();
  if (normals && binding.vertex_count > 0 && rest_normals.size() <= binding.max_vertex) return false;

  std::vector<float> params, normal_list;
  target_list_.clear();
  for (std::size_t lane = 0; lane < binding.vertices.size(); ++lane) {
    const std::uint32_t vertex = binding.vertices[lane];
    if (vertex == deform::LatticeBinding::no_vertex) continue;
    target_list_.push_back(vertex);
    params.insert(params.end(), {binding.u[lane], binding.v[lane], binding.w[lane]});
    if (normals) {
      const glm::vec3 n = rest_normals[vertex];
      normal_list.insert(normal_list.end(), {n.x, n.y, n.z});
    }
  }
  upload(binding.point_counts, binding.normal_basis, params, normal_list, {});
  return true;
}

bool GpuBezierLattice::create_additive(const deform::LatticeBinding& binding, std::span<const float> weights,
                                       std::span<const std::uint32_t> vertex_point) {
  release();
  if (!usable(binding) || weights.size() != binding.vertices.size()) return false;
  // Each bound point's lane, then one entry per render vertex of a bound point (a point split at a UV or normal
  // seam is evaluated once per render vertex, as in create()).
  std::vector<std::uint32_t> lane_of_point(binding.vertex_count ? std::size_t{binding.max_vertex} + 1 : 0,
                                           deform::LatticeBinding::no_vertex);
  for (std::size_t lane = 0; lane < binding.vertices.size(); ++lane) {
    const std::uint32_t point = binding.vertices[lane];
    if (point != deform::LatticeBinding::no_vertex) lane_of_point[point] = std::uint32_t(lane);
  }
  std::vector<float> params, weight_list;
  target_list_.clear();
  for (std::size_t r = 0; r < vertex_point.size(); ++r) {
    const std::uint32_t point = vertex_point[r];
    if (point >= lane_of_point.size() || lane_of_point[point] == deform::LatticeBinding::no_vertex) continue;
    const std::size_t lane = lane_of_point[point];
    target_list_.push_back(std::uint32_t(r));
    params.insert(params.end(), {binding.u[lane], binding.v[lane], binding.w[lane]});
    weight_list.push_back(weights[lane]);
  }
  upload(binding.point_counts, binding.normal_basis, params, {}, weight_list);
  additive_ = true;
  return true;
}

void GpuBezierLattice::upload(glm::ivec3 point_counts, const glm::mat3& normal_basis, std::span<const float> params,
                              std::span<const float> normals, std::span<const float> weights) {
  count_ = target_list_.size();
  max_target_ = count_ ? *std::max_element(target_list_.begin(), target_list_.end()) : 0;
  point_counts_ = point_counts;
  normal_basis_ = normal_basis;
  has_normals_ = !normals.empty();

  const glm::ivec3 d = point_counts - 1;
  const std::string source = "#version 430\nconst ivec3 degree = ivec3(" + std::to_string(d.x) + ", " +
                             std::to_string(d.y) + ", " + std::to_string(d.z) + ");\n" + shader_body;
  program_ = build_compute_program(source.c_str());
  targets_ = storage_buffer(target_list_.data(), target_list_.size() * sizeof(std::uint32_t), GL_STATIC_DRAW);
  params_ = storage_buffer(params.data(), params.size() * sizeof(float), GL_STATIC_DRAW);
  normals_ = storage_buffer(normals.data(), normals.size() * sizeof(float), GL_STATIC_DRAW);
  weights_ = storage_buffer(weights.data(), weights.size() * sizeof(float), GL_STATIC_DRAW);
  const std::size_t point_count =
      std::size_t(point_counts.x) * std::size_t(point_counts.y) * std::size_t(point_counts.z);
  points_ = storage_buffer(nullptr, point_count * sizeof(glm::vec3), GL_STREAM_DRAW);
  staging_.assign(count_ * 6, 0.0f);
  results_ = storage_buffer(nullptr, staging_.size() * sizeof(float), GL_STREAM_READ);
}

bool GpuBezierLattice::dispatch(std::span<const glm::vec3> control_points, GLuint output, bool scatter,
                                const InterleavedLayout& layout) {
  if (!program_) return false;
  const std::size_t point_count = std::size_t(point_counts_.x) * std::size_t(point_counts_.y) *
                                  std::size_t(point_counts_.z);
  if (control_points.size() != point_count) return false;
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, points_);
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(point_count * sizeof(glm::vec3)), control_points.data());
  if (count_ == 0) return true;

  glUseProgram(program_);
  glUniform1ui(glGetUniformLocation(program_, "vertex_count"), GLuint(count_));
  glUniformMatrix3fv(glGetUniformLocation(program_, "normal_basis"), 1, GL_FALSE, glm::value_ptr(normal_basis_));
  glUniform1i(glGetUniformLocation(program_, "with_normals"), has_normals_ ? 1 : 0);
  glUniform1i(glGetUniformLocation(program_, "scatter"), scatter ? 1 : 0);
  glUniform1i(glGetUniformLocation(program_, "additive"), additive_ ? 1 : 0);
  glUniform1ui(glGetUniformLocation(program_, "stride"), GLuint(layout.floats_per_vertex));
  glUniform1ui(glGetUniformLocation(program_, "position_offset"), GLuint(layout.position_offset));
  glUniform1ui(glGetUniformLocation(program_, "normal_offset"), GLuint(layout.normal_offset));
  const GLuint buffers[] = {targets_, params_, normals_, points_, output, weights_};
  for (GLuint i = 0; i < 6; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, buffers[i]);

  // Dispatches of at most 65,535 groups (the least every 4.3 driver allows), 4 million vertices each.
  const GLint first_location = glGetUniformLocation(program_, "first_vertex");
  const std::size_t per_dispatch = std::size_t{65535} * group_size;
  for (std::size_t first = 0; first < count_; first += per_dispatch) {
    const std::size_t n = std::min(per_dispatch, count_ - first);
    glUniform1ui(first_location, GLuint(first));
    glDispatchCompute(GLuint((n + group_size - 1) / group_size), 1, 1);
  }
  for (GLuint i = 0; i < 6; ++i) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, i, 0);
  glUseProgram(0);
  return true;
}

bool GpuBezierLattice::evaluate(std::span<const glm::vec3> control_points) {
  if (additive_) return false;
  return dispatch(control_points, results_, false, InterleavedLayout{6, 0, 3});
}

bool GpuBezierLattice::read_back(std::span<glm::vec3> positions, std::span<glm::vec3> normals) {
  if (!program_ || additive_) return false;
  if (count_ == 0) return true;
  if (positions.size() <= max_target_ || (!normals.empty() && normals.size() <= max_target_)) return false;
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, results_);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(staging_.size() * sizeof(float)), staging_.data());
  const bool with_normals = has_normals_ && !normals.empty();
  for (std::size_t e = 0; e < count_; ++e) {
    const float* r = staging_.data() + 6 * e;
    positions[target_list_[e]] = glm::vec3(r[0], r[1], r[2]);
    if (with_normals) normals[target_list_[e]] = glm::vec3(r[3], r[4], r[5]);
  }
  return true;
}

bool GpuBezierLattice::evaluate_into(std::span<const glm::vec3> control_points, GLuint vertex_buffer,
                                     const InterleavedLayout& layout) {
  if (!program_ || vertex_buffer == 0) return false;
  if (count_ > 0) {  // the buffer must hold every bound vertex
    GLint64 bytes = 0;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, vertex_buffer);
    glGetBufferParameteri64v(GL_SHADER_STORAGE_BUFFER, GL_BUFFER_SIZE, &bytes);
    const std::size_t needed = (std::size_t{max_target_} + 1) * std::size_t(layout.floats_per_vertex) * sizeof(float);
    if (bytes < 0 || std::size_t(bytes) < needed) return false;
  }
  if (!dispatch(control_points, vertex_buffer, true, layout)) return false;
  glMemoryBarrier(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  return true;
}

bool GpuLatticeFields::create(const deform::DeformerHierarchy& hierarchy, std::span<const std::uint32_t> vertex_point) {
  lattices_.clear();
  for (std::size_t l = 0; l < hierarchy.lattice_count(); ++l) {
    auto lattice = std::make_unique<GpuBezierLattice>();
    if (!lattice->create_additive(hierarchy.binding(l), hierarchy.bound_weights(l), vertex_point)) {
      lattices_.clear();
      return false;
    }
    lattices_.push_back(std::move(lattice));
  }
  return true;
}

bool GpuLatticeFields::add_into(const deform::DeformerHierarchy& hierarchy, GLuint vertex_buffer,
                                const InterleavedLayout& layout) {
  if (hierarchy.lattice_count() != lattices_.size()) return false;
  for (std::size_t l = 0; l < lattices_.size(); ++l) {
    // A lattice at rest adds nothing (its displacements are below 1e-7 of its length): skipped, as the CPU does.
    if (hierarchy.active(l) && !lattices_[l]->evaluate_into(hierarchy.displacements(l), vertex_buffer, layout)) {
      return false;
    }
  }
  return true;
}

}  // namespace sample
