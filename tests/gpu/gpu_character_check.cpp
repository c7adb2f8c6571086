// Checks deform::GpuLatticeFields (deform/gpu/lattice.hpp, the viewer's GPU lattices) against the CPU: the built-in
// character reaches for an out-of-reach target and stretches; one deform::Character deforms completely on the CPU, a
// twin with lattice_fields = false is skinned on the CPU, uploaded into an interleaved vertex buffer as an application
// would, and gets its lattice fields added there by the GPU. At several frames (stretching, overshooting, springing
// back after a release), for lattice degrees 3 and 1, and 5 with neighbour springs (which make the fields non-affine),
// the buffer's positions must match the CPU's to 1e-4 of the model's size, its UVs and normals must be what was
// uploaded to the bit, and the fields must really move the arm (else the check proves nothing). Exits 1 on a failure, 0
// with "skipped" when the context lacks OpenGL 4.3.
#include "hidden_context.hpp"  // epoxy first

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <span>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/deform.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/gpu/lattice.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"

namespace {

constexpr float tolerance = 1e-4f;  // of the model's size (its bounding box diagonal)
constexpr int floats_per_vertex = deform::GpuVertexLayout{}.floats_per_vertex;  // u v, nx ny nz, x y z

// The vertex buffer an application draws the character from (GpuVertexLayout's default), rewritten on upload().
class VertexBuffer {
 public:
  explicit VertexBuffer(const deform::Mesh& mesh) : mesh_(mesh) { glGenBuffers(1, &name_); }
  ~VertexBuffer() { glDeleteBuffers(1, &name_); }
  VertexBuffer(const VertexBuffer&) = delete;
  VertexBuffer& operator=(const VertexBuffer&) = delete;

  void upload(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals) {
    std::vector<float> data(positions.size() * floats_per_vertex);
    for (std::size_t r = 0; r < positions.size(); ++r) {
      const glm::vec2 uv = mesh_.vertex_uvs.empty() ? glm::vec2(0.0f) : mesh_.vertex_uvs[r];
      const float vertex[floats_per_vertex] = {uv.x,         uv.y,           normals[r].x,   normals[r].y,
                                               normals[r].z, positions[r].x, positions[r].y, positions[r].z};
      std::memcpy(data.data() + r * floats_per_vertex, vertex, sizeof vertex);
    }
    glBindBuffer(GL_ARRAY_BUFFER, name_);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(), GL_STREAM_DRAW);
  }
  GLuint name() const { return name_; }

 private:
  const deform::Mesh& mesh_;
  GLuint name_ = 0;
};

bool check_degree(int degree, bool springs) {
  deform::Model model = deform::builtin_character();
  deform::Rig rig = deform::builtin_rig(model);
  for (deform::LatticeSpec& spec : rig.lattices) {
    spec.degree = glm::ivec3(degree);
    spec.elastic.springs.structural = spec.elastic.springs.shear = spec.elastic.springs.bend = springs;
    spec.elastic.springs.stiffness = 300.0f;
  }
  deform::Character cpu(model, rig), gpu(model, rig);
  gpu.settings.lattice_fields = false;
  const deform::Mesh& mesh = gpu.model().mesh;
  const deform::Bounds bounds = deform::compute_bounds(mesh.positions);
  const float size = glm::length(bounds.max - bounds.min);

  VertexBuffer vertex_buffer(mesh);
  deform::GpuLatticeFields fields;
  if (!fields.create(gpu.deformers(), mesh.vertex_point)) {
    std::printf("FAIL degree %d: GpuLatticeFields::create refused the character's lattices\n", degree);
    return false;
  }

  const std::int32_t hand = cpu.skeleton().find("hand_l");
  const glm::vec3 target(1.3f, 1.6f, 0.4f);  // the smoke test's reach: out of the left arm's reach
  if (!cpu.reach(hand, target).status || !gpu.reach(hand, target).status) {
    std::printf("FAIL degree %d: reach refused\n", degree);
    return false;
  }
  const int checkpoints[] = {3, 12, 30, 50};
  const int release_at = 30;
  std::vector<glm::vec3> positions(mesh.vertex_count());
  std::vector<float> buffer(mesh.vertex_count() * floats_per_vertex);
  bool ok = true;
  float largest_field = 0.0f;
  for (int frame = 1, next = 0; next < 4; ++frame) {
    if (frame == release_at) {
      cpu.release();
      gpu.release();
    }
    cpu.update(1.0f / 60.0f);
    gpu.update(1.0f / 60.0f);
    if (frame != checkpoints[next]) continue;
    ++next;

    for (std::size_t r = 0; r < positions.size(); ++r) positions[r] = gpu.positions()[mesh.vertex_point[r]];
    const auto normals = gpu.normals();
    vertex_buffer.upload(positions, normals);
    if (!fields.add_into(gpu.deformers(), vertex_buffer.name())) {
      std::printf("FAIL degree %d frame %d: add_into refused\n", degree, frame);
      return false;
    }
    glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer.name());
    glGetBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(buffer.size() * sizeof(float)), buffer.data());

    float worst = 0.0f, field = 0.0f;
    std::size_t changed = 0;
    for (std::size_t r = 0; r < positions.size(); ++r) {
      const float* v = buffer.data() + r * floats_per_vertex;
      const glm::vec3 expected = cpu.positions()[mesh.vertex_point[r]];
      worst = std::max(worst, glm::length(glm::vec3(v[5], v[6], v[7]) - expected));
      field = std::max(field, glm::length(expected - positions[r]));
      const glm::vec2 uv = mesh.vertex_uvs.empty() ? glm::vec2(0.0f) : mesh.vertex_uvs[r];
      const float kept[5] = {uv.x, uv.y, normals[r].x, normals[r].y, normals[r].z};
      changed += std::memcmp(kept, v, sizeof kept) != 0;
    }
    largest_field = std::max(largest_field, field);
    const bool pass = worst <= tolerance * size && changed == 0;
    std::printf(
        "%s degree %d%s frame %2d: stretch %.4f m, GPU vs CPU %.2e of the size (field up to %.2e), "
        "%zu UVs/normals changed\n",
        pass ? "ok  " : "FAIL", degree, springs ? " + springs" : "", frame, double(cpu.stretch()), double(worst / size),
        double(field / size), changed);
    ok = ok && pass;
  }
  // The fields carry the stretch: a GPU path that added nothing would fail here.
  if (!(largest_field > 1e-2f * size)) {
    std::printf("FAIL degree %d: the lattice fields moved nothing (%.2e of the size)\n", degree,
                double(largest_field / size));
    ok = false;
  }
  return ok;
}

// Bad input is refused, not drawn.
bool check_refusals() {
  const deform::Character character = deform::make_builtin_character();
  const deform::DeformerHierarchy& h = character.deformers();
  const deform::Mesh& mesh = character.model().mesh;
  deform::GpuBezierLattice lattice;
  bool ok = true;
  const std::vector<float> short_weights(h.bound_weights(0).size() - 1, 1.0f);
  ok = ok && !lattice.create_additive(h.binding(0), short_weights, mesh.vertex_point);
  ok = ok && lattice.create_additive(h.binding(0), h.bound_weights(0), mesh.vertex_point) && lattice.additive();
  std::vector<glm::vec3> out(mesh.vertex_count());
  ok = ok && !lattice.evaluate(h.displacements(0)) && !lattice.read_back(out);  // additive: only into a buffer
  deform::GpuLatticeFields fields;
  const deform::Character bare(deform::builtin_character(), deform::Rig{});
  ok = ok && fields.create(bare.deformers(), mesh.vertex_point) && !fields.add_into(h, 1);  // lattice count differs
  std::printf("%s refusals\n", ok ? "ok  " : "FAIL");
  return ok;
}

}  // namespace

int main() {
  return gpu_test::run_in_context("gpu_character_check", [] {
    bool ok = check_refusals();
    ok = check_degree(3, false) && ok;
    ok = check_degree(1, false) && ok;
    ok = check_degree(5, true) && ok;
    return ok ? 0 : 1;
  });
}
