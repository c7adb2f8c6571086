// Checks deform::GpuSkinning (deform/gpu/skinning.hpp) against the CPU's SkinningJob, and the whole deformation on
// the GPU (GpuSkinning + GpuLatticeFields::apply_into) against the CPU's deform::Character:
//  - seeded random skins (5,000 points, 24 bones, one to four influences with unnormalised sums, random unit
//    normals) under several palettes each — rigid rotations of up to 180°, uniform scale, non-uniform scale and
//    shear — by LBS and DQS (rigid and scaled), written into interleaved buffers of two layouts; also against a
//    double-precision reference of the same formulas;
//  - the built-in character posed by each of its clips (no lattices: skinning alone), LBS and DQS, per render
//    vertex, with its bind normals, against Character::positions() and normals();
//  - the built-in character reaching out of reach with its lattices stretching and springing back (degree 3, and 5
//    with neighbour springs), LBS and DQS: one Character deforming on the CPU, a twin posing only (deform_on_cpu =
//    false) whose deformation is skinned and lattice-added on the GPU, normals turned by the lattices too
//    (GpuLatticeFields with normals) against the CPU's transported normals, or, without, against a third twin's with
//    lattice_fields = false (the skinned ones); the same under the walk with the full rig's lattices on every limb
//    jiggling (inertia);
//  - the refusals (bind errors, wrong palette size, buffer 0 or too small, a layout that does not fit, scales of
//    another count, an OpenGL ES context: no compute on desktop GL) and moves.
// Bounds: positions within 1e-5 of the model's (deformed) bounding-box diagonal; normals within 1e-3 rad where the
// normal is well conditioned (the blended matrix's cofactor does not nearly vanish). Every float of the buffer the
// skinning does not write must be unchanged. Exits 1 on a failure, 0 with "skipped" without OpenGL 4.3.
//
// gpu_skinning_check --bench prints indicative per-frame times instead (not a test: docs/gpu.md).
#include "hidden_context.hpp"  // epoxy first

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/gpu/lattice.hpp"
#include "deform/gpu/skinning.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skinning.hpp"

namespace {

constexpr float position_tolerance = 1e-5f;  // of the bounding-box diagonal
constexpr double normal_tolerance = 1e-3;    // radians

// An interleaved vertex buffer filled with a recognisable pattern, so that floats the GPU must not touch can be
// checked to the bit.
class Buffer {
 public:
  Buffer(std::size_t vertices, const deform::GpuVertexLayout& layout)
      : layout_(layout), initial_(vertices * std::size_t(layout.floats_per_vertex)) {
    for (std::size_t i = 0; i < initial_.size(); ++i) initial_[i] = 1000.0f + float(i % 977);
    glGenBuffers(1, &name_);
    glBindBuffer(GL_ARRAY_BUFFER, name_);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(initial_.size() * sizeof(float)), initial_.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
  }
  ~Buffer() { glDeleteBuffers(1, &name_); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  GLuint name() const { return name_; }
  const std::vector<float>& initial() const { return initial_; }
  // The buffer's floats now.
  std::vector<float> read() const {
    std::vector<float> data(initial_.size());
    glBindBuffer(GL_ARRAY_BUFFER, name_);
    glGetBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(data.size() * sizeof(float)), data.data());
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    return data;
  }
  // Positions and normals from a read().
  glm::vec3 position(const std::vector<float>& data, std::size_t v) const {
    const float* p = data.data() + v * std::size_t(layout_.floats_per_vertex) + layout_.position_offset;
    return {p[0], p[1], p[2]};
  }
  glm::vec3 normal(const std::vector<float>& data, std::size_t v) const {
    const float* p = data.data() + v * std::size_t(layout_.floats_per_vertex) + layout_.normal_offset;
    return {p[0], p[1], p[2]};
  }
  // Floats other than the position and the normal that changed.
  std::size_t others_changed(const std::vector<float>& data) const {
    std::size_t changed = 0;
    const auto stride = std::size_t(layout_.floats_per_vertex);
    for (std::size_t i = 0; i < data.size(); ++i) {
      const auto f = int(i % stride);
      const bool written = (f >= layout_.position_offset && f < layout_.position_offset + 3) ||
                           (f >= layout_.normal_offset && f < layout_.normal_offset + 3);
      if (!written && std::memcmp(&data[i], &initial_[i], sizeof(float)) != 0) ++changed;
    }
    return changed;
  }

 private:
  deform::GpuVertexLayout layout_;
  GLuint name_ = 0;
  std::vector<float> initial_;
};

double angle_between(glm::vec3 a, glm::vec3 b) {
  const glm::dvec3 x(a), y(b);
  return std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y));
}

float diagonal(std::span<const glm::vec3> points) {
  const deform::Bounds b = deform::compute_bounds(points);
  return glm::length(b.max - b.min);
}

// ---- Random skins --------------------------------------------------------------------------------------------------

struct Skin {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::u16vec4> bones;
  std::vector<glm::vec4> weights;
};

glm::vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  for (;;) {
    const glm::vec3 n{g(rng), g(rng), g(rng)};
    if (glm::length(n) > 1e-3f) return glm::normalize(n);
  }
}

Skin random_skin(std::mt19937& rng, std::size_t points, int bones) {
  Skin skin;
  std::uniform_real_distribution<float> coordinate(-1.0f, 1.0f), weight(0.05f, 1.0f), sum(0.5f, 2.0f);
  std::uniform_int_distribution<int> bone(0, bones - 1), influences(1, 4);
  for (std::size_t i = 0; i < points; ++i) {
    skin.positions.push_back({coordinate(rng), coordinate(rng), coordinate(rng)});
    skin.normals.push_back(random_unit(rng));
    glm::u16vec4 b;
    glm::vec4 w(0.0f);
    const int used = influences(rng);
    for (int k = 0; k < 4; ++k) {
      b[k] = std::uint16_t(bone(rng));  // unused slots: weight 0 and any index
      if (k < used) w[k] = weight(rng);
    }
    if (i % 3 != 0) w *= sum(rng) / (w.x + w.y + w.z + w.w);  // sums away from 1: normalised on the fly
    skin.bones.push_back(b);
    skin.weights.push_back(w);
  }
  return skin;
}

enum class PaletteKind { rigid, uniform_scale, scale_shear };

// Bone matrices: rotations of up to 180° about random axes, translations within ±2 (the skin is 2 wide), and a
// uniform scale in [0.5, 2] or a non-uniform scale with shear.
std::vector<glm::mat4> random_palette(std::mt19937& rng, int bones, PaletteKind kind) {
  std::uniform_real_distribution<float> angle(0.0f, 3.14159265f), offset(-2.0f, 2.0f), scale(0.5f, 2.0f),
      shear(-0.3f, 0.3f);
  std::vector<glm::mat4> palette;
  for (int b = 0; b < bones; ++b) {
    const float turn = angle(rng);
    glm::mat4 m = glm::mat4_cast(glm::angleAxis(turn, random_unit(rng)));
    if (kind == PaletteKind::uniform_scale) m = m * glm::mat4(glm::mat3(scale(rng)));
    if (kind == PaletteKind::scale_shear) {
      glm::mat3 s(1.0f);
      s[0][0] = scale(rng), s[1][1] = scale(rng), s[2][2] = scale(rng);
      s[1][0] = shear(rng), s[2][0] = shear(rng), s[2][1] = shear(rng);
      m = m * glm::mat4(s);
    }
    m[3] = glm::vec4{offset(rng), offset(rng), offset(rng), 1.0f};
    palette.push_back(m);
  }
  return palette;
}

// The double-precision reference of the kernels' formulas (SkinningJob's contract, skinning.hpp). Returns the
// position; `normal` gets the unnormalised mapped normal and `scale2` a measure of the map's squared scale, so that
// the caller can tell a well-conditioned normal (|normal| not tiny against scale2).
glm::dvec3 reference_lbs(const std::vector<glm::mat4>& palette, glm::u16vec4 b, glm::vec4 w, glm::vec3 p,
                         glm::vec3 n_in, glm::dvec3& normal, double& scale2) {
  glm::dmat4 blended(0.0);
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    blended += double(w[k]) * glm::dmat4(palette[b[k]]);
    sum += double(w[k]);
  }
  const glm::dmat3 a(blended);
  normal = glm::transpose(glm::inverse(a)) * glm::dvec3(n_in) * glm::determinant(a);
  scale2 = (glm::dot(a[0], a[0]) + glm::dot(a[1], a[1]) + glm::dot(a[2], a[2])) / 3.0;
  return glm::dvec3(blended * glm::dvec4(glm::dvec3(p), 1.0)) / sum;
}

glm::dvec3 reference_dqs(const std::vector<deform::DualQuat>& dq, const std::vector<glm::mat3>& scales, glm::u16vec4 b,
                         glm::vec4 w, glm::vec3 p, glm::vec3 n_in, glm::dvec3& normal, double& scale2) {
  const glm::dquat pivot(dq[b[0]].real);
  glm::dquat real(0.0, 0.0, 0.0, 0.0), dual(0.0, 0.0, 0.0, 0.0);
  glm::dmat3 s(0.0);
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    const glm::dquat r(dq[b[k]].real), d(dq[b[k]].dual);
    const double sw = glm::dot(r, pivot) < 0.0 ? -double(w[k]) : double(w[k]);
    real = real + r * sw;
    dual = dual + d * sw;
    if (!scales.empty()) s += double(w[k]) * glm::dmat3(scales[b[k]]);
    sum += double(w[k]);
  }
  const double length = std::sqrt(glm::dot(real, real));
  real = real * (1.0 / length);
  dual = dual * (1.0 / length);
  const glm::dquat t = dual * glm::conjugate(real) * 2.0;  // the translation, as a pure quaternion
  glm::dvec3 x(p), m(n_in);
  if (!scales.empty()) {
    s /= sum;
    x = s * x;
    m = glm::transpose(glm::inverse(s)) * m * glm::determinant(s);
  }
  normal = real * m;
  scale2 = length * length;  // a short blended real part is where DQS is ill-conditioned
  return real * x + glm::dvec3(t.x, t.y, t.z);
}

struct Worst {
  double position = 0.0, normal = 0.0, reference = 0.0;
  std::size_t ill_conditioned = 0, others_changed = 0;
};

bool check_random(unsigned seed) {
  std::mt19937 rng(seed);
  const int bones = 24;
  const Skin skin = random_skin(rng, 5000, bones);
  const std::size_t n = skin.positions.size();
  bool ok = true;
  const deform::GpuVertexLayout layouts[] = {{}, {11, 1, 6}};
  deform::GpuSkinning gpu;
  deform::GpuSkinningBind bind;
  bind.positions = skin.positions;
  bind.normals = skin.normals;
  bind.bone_indices = skin.bones;
  bind.bone_weights = skin.weights;
  bind.bone_count = bones;
  if (const deform::Status s = gpu.create(bind); !s) {
    std::printf("FAIL seed %u: create refused: %s %s\n", seed, s.reason(), gpu.shader_log().c_str());
    return false;
  }
  for (const PaletteKind kind : {PaletteKind::rigid, PaletteKind::uniform_scale, PaletteKind::scale_shear}) {
    for (int repeat = 0; repeat < 2; ++repeat) {
      const std::vector<glm::mat4> palette = random_palette(rng, bones, kind);
      for (const deform::SkinningMethod method : {deform::SkinningMethod::lbs, deform::SkinningMethod::dqs}) {
        const bool dqs = method == deform::SkinningMethod::dqs;
        // The CPU.
        std::vector<deform::DualQuat> dq(bones);
        std::vector<glm::mat3> scales(bones);
        bool has_scale = false;
        if (dqs && !deform::compute_dual_quat_palette(palette, dq, scales, has_scale)) {
          std::printf("FAIL seed %u: compute_dual_quat_palette refused\n", seed);
          return false;
        }
        if (!has_scale) scales.clear();
        std::vector<glm::vec3> cpu_p(n), cpu_n(n);
        deform::SkinningJob job;
        job.method = method;
        job.matrices = palette;
        job.dual_quats = dq;
        job.scales = scales;
        job.bone_indices = skin.bones;
        job.bone_weights = skin.weights;
        job.in_positions = deform::as_floats(skin.positions);
        job.out_positions = deform::as_floats(cpu_p);
        job.in_normals = deform::as_floats(skin.normals);
        job.out_normals = deform::as_floats(cpu_n);
        if (!job.validate() || !job.run()) {
          std::printf("FAIL seed %u: SkinningJob refused\n", seed);
          return false;
        }
        const double size = diagonal(cpu_p);
        for (const deform::GpuVertexLayout& layout : layouts) {
          Buffer buffer(n, layout);
          // DQS through both entries: converted by GpuSkinning, and the palette converted here.
          const deform::Status s = dqs && layout.floats_per_vertex != 8
                                       ? gpu.skin_into(dq, scales, buffer.name(), layout)
                                       : gpu.skin_into(method, palette, buffer.name(), layout);
          if (!s) {
            std::printf("FAIL seed %u: skin_into refused: %s\n", seed, s.reason());
            return false;
          }
          const std::vector<float> data = buffer.read();
          Worst worst;
          worst.others_changed = buffer.others_changed(data);
          for (std::size_t i = 0; i < n; ++i) {
            const glm::vec3 p = buffer.position(data, i), nn = buffer.normal(data, i);
            worst.position = std::max(worst.position, double(glm::length(p - cpu_p[i])) / size);
            glm::dvec3 ref_normal;
            double scale2 = 0.0;
            const glm::dvec3 ref = dqs ? reference_dqs(dq, scales, skin.bones[i], skin.weights[i], skin.positions[i],
                                                       skin.normals[i], ref_normal, scale2)
                                       : reference_lbs(palette, skin.bones[i], skin.weights[i], skin.positions[i],
                                                       skin.normals[i], ref_normal, scale2);
            worst.reference = std::max(worst.reference, glm::length(glm::dvec3(p) - ref) / size);
            // Normal directions are compared where the normal map does not nearly collapse: |cof(A)·n| against
            // |A|², or the blended real part's length for DQS. LBS under 180° of twist has such vertices.
            const bool conditioned = dqs ? scale2 > 1e-2 : glm::length(ref_normal) > 1e-2 * scale2;
            if (!conditioned) {
              ++worst.ill_conditioned;
              continue;
            }
            worst.normal = std::max(
                {worst.normal, angle_between(nn, cpu_n[i]), angle_between(nn, glm::vec3(glm::normalize(ref_normal)))});
          }
          const bool pass = worst.position <= position_tolerance && worst.reference <= position_tolerance &&
                            worst.normal <= normal_tolerance && worst.others_changed == 0;
          const char* kinds[] = {"rigid", "uniform scale", "scale+shear"};
          std::printf(
              "%s seed %u %s %-13s layout %2d: position vs CPU %.2e, vs double %.2e (of %.2f); normals "
              "%.2e rad (%zu ill-conditioned skipped); %zu other floats changed\n",
              pass ? "ok  " : "FAIL", seed, dqs ? "DQS" : "LBS", kinds[int(kind)], layout.floats_per_vertex,
              worst.position, worst.reference, size, worst.normal, worst.ill_conditioned, worst.others_changed);
          ok = ok && pass;
        }
      }
    }
  }
  return ok;
}

// ---- The built-in character ----------------------------------------------------------------------------------------

constexpr deform::GpuVertexLayout layout{};  // u v, nx ny nz, x y z

std::vector<glm::vec3> gathered(std::span<const glm::vec3> per_point, const std::vector<std::uint32_t>& vertex_point) {
  std::vector<glm::vec3> out(vertex_point.size());
  for (std::size_t r = 0; r < out.size(); ++r) out[r] = per_point[vertex_point[r]];
  return out;
}

// Compares the buffer's positions with `positions` (per point) and its normals with `normals` (per render vertex).
bool compare(const char* what, const Buffer& buffer, const deform::Mesh& mesh, std::span<const glm::vec3> positions,
             std::span<const glm::vec3> normals, double* moved = nullptr, double turned = -1.0) {
  const std::vector<float> data = buffer.read();
  const double size = diagonal(positions);
  double worst_p = 0.0, worst_n = 0.0;
  for (std::size_t r = 0; r < mesh.vertex_count(); ++r) {
    worst_p = std::max(worst_p, double(glm::length(buffer.position(data, r) - positions[mesh.vertex_point[r]])) / size);
    if (glm::length(normals[r]) > 0.5f) worst_n = std::max(worst_n, angle_between(buffer.normal(data, r), normals[r]));
  }
  const std::size_t others = buffer.others_changed(data);
  const bool pass = worst_p <= position_tolerance && worst_n <= normal_tolerance && others == 0;
  std::printf("%s %s: positions %.2e of the size, normals %.2e rad, %zu other floats changed", pass ? "ok  " : "FAIL",
              what, worst_p, worst_n, others);
  if (moved) std::printf(", lattices moved points by up to %.2e of the size", *moved / size);
  if (turned >= 0.0) std::printf(" and turned normals by up to %.3f rad", turned);
  std::printf("\n");
  return pass;
}

// The largest angle between two normal lists (per render vertex), zero normals left out.
double largest_angle(std::span<const glm::vec3> a, std::span<const glm::vec3> b) {
  double largest = 0.0;
  for (std::size_t r = 0; r < a.size(); ++r)
    if (glm::length(a[r]) > 0.5f && glm::length(b[r]) > 0.5f) largest = std::max(largest, angle_between(a[r], b[r]));
  return largest;
}

deform::GpuSkinningBind character_bind(const deform::Character& character, std::vector<glm::vec3>& normals) {
  const deform::Model& model = character.model();
  normals = gathered(character.bind_normals(), model.mesh.vertex_point);
  deform::GpuSkinningBind bind;
  bind.positions = model.mesh.positions;
  bind.bone_indices = model.weights.bones;
  bind.bone_weights = model.weights.weights;
  bind.vertex_point = model.mesh.vertex_point;
  bind.normals = normals;
  bind.bone_count = model.skeleton.bone_count();
  return bind;
}

// Skinning alone: the character (no lattices) posed by every built-in clip.
bool check_clips() {
  const deform::Model model = deform::builtin_character();
  const std::vector<deform::Animation> clips = deform::builtin_clips(model);
  bool ok = true;
  for (const deform::SkinningMethod method : {deform::SkinningMethod::lbs, deform::SkinningMethod::dqs}) {
    deform::Character cpu(model);
    cpu.settings.skinning = method;
    std::vector<glm::vec3> bind_normals;
    deform::GpuSkinning gpu;
    if (const deform::Status s = gpu.create(character_bind(cpu, bind_normals)); !s) {
      std::printf("FAIL clips: create refused: %s\n", s.reason());
      return false;
    }
    Buffer buffer(model.mesh.vertex_count(), layout);
    for (const deform::Animation& clip : clips) {
      for (const float phase : {0.2f, 0.65f}) {
        deform::Pose pose = cpu.skeleton().bind_pose();
        deform::SamplingJob sampling;
        sampling.animation = &clip;
        sampling.time = phase * clip.duration;
        sampling.rotations = pose.rotations;
        sampling.translations = pose.translations;
        if (!sampling.run() || !cpu.set_pose(pose) || !cpu.update(1.0f / 60.0f)) {
          std::printf("FAIL clips: %s could not be posed\n", clip.name.c_str());
          return false;
        }
        if (const deform::Status s = gpu.skin_into(method, cpu.palette(), buffer.name()); !s) {
          std::printf("FAIL clips: skin_into refused: %s\n", s.reason());
          return false;
        }
        const std::string what = std::string(method == deform::SkinningMethod::dqs ? "DQS" : "LBS") + " clip " +
                                 clip.name + " at " + std::to_string(phase).substr(0, 4);
        ok = compare(what.c_str(), buffer, model.mesh, cpu.positions(), cpu.normals()) && ok;
      }
    }
  }
  return ok;
}

// The whole deformation: skinning, carried points and lattice fields on the GPU, the CPU only posing.
bool check_whole(deform::SkinningMethod method, int degree, bool springs, bool lattice_normals) {
  const deform::Model model = deform::builtin_character();
  deform::Rig rig = deform::builtin_rig(model);
  for (deform::LatticeSpec& spec : rig.lattices) {
    spec.degree = glm::ivec3(degree);
    // Neighbour springs make the fields non-affine (gpu_character_check does the same).
    spec.elastic.springs.structural = spec.elastic.springs.shear = spec.elastic.springs.bend = springs;
    spec.elastic.springs.stiffness = 300.0f;
  }
  deform::Character cpu(model, rig);
  cpu.settings.skinning = method;
  deform::Character skinned = cpu.instance();  // the GPU's normals: skinned, not turned by the lattices
  skinned.settings.lattice_fields = false;
  deform::Character gpu_pose = cpu.instance();
  gpu_pose.settings.deform_on_cpu = false;
  const deform::Mesh& mesh = model.mesh;

  std::vector<glm::vec3> bind_normals;
  deform::GpuSkinning skinning;
  deform::GpuLatticeFields fields;
  if (const deform::Status s = skinning.create(character_bind(gpu_pose, bind_normals)); !s) {
    std::printf("FAIL whole: GpuSkinning::create refused: %s\n", s.reason());
    return false;
  }
  if (const deform::Status s = fields.create(gpu_pose.deformers(), mesh.vertex_point, lattice_normals); !s) {
    std::printf("FAIL whole: GpuLatticeFields::create refused: %s\n", s.reason());
    return false;
  }
  Buffer buffer(mesh.vertex_count(), layout);
  const std::int32_t hand = cpu.skeleton().find("hand_l");
  const glm::vec3 target(1.3f, 1.6f, 0.4f);  // out of the left arm's reach: the lattices stretch
  for (deform::Character* c : {&cpu, &skinned, &gpu_pose})
    if (!c->reach(hand, target).status) {
      std::printf("FAIL whole: reach refused\n");
      return false;
    }
  bool ok = true;
  double largest_field = 0.0, largest_turn = 0.0;
  for (int frame = 1; frame <= 50; ++frame) {
    if (frame == 30)
      for (deform::Character* c : {&cpu, &skinned, &gpu_pose}) c->release();
    for (deform::Character* c : {&cpu, &skinned, &gpu_pose}) c->update(1.0f / 60.0f);
    if (frame != 3 && frame != 12 && frame != 31 && frame != 50) continue;
    if (const deform::Status s = skinning.skin_into(method, gpu_pose.palette(), buffer.name()); !s) {
      std::printf("FAIL whole: skin_into refused: %s\n", s.reason());
      return false;
    }
    if (const deform::Status s = fields.apply_into(gpu_pose.deformers(), buffer.name()); !s) {
      std::printf("FAIL whole: apply_into refused: %s\n", s.reason());
      return false;
    }
    double moved = 0.0;
    for (std::size_t p = 0; p < mesh.point_count(); ++p) {
      // What the lattices add: the full CPU result against the skinned-only one, without carried points either.
      moved = std::max(moved, double(glm::length(cpu.positions()[p] - skinned.positions()[p])));
    }
    largest_field = std::max(largest_field, moved);
    const std::string what = std::string(method == deform::SkinningMethod::dqs ? "DQS" : "LBS") + " degree " +
                             std::to_string(degree) + (springs ? " + springs" : "") + " frame " +
                             std::to_string(frame) + " whole deformation" +
                             (lattice_normals ? ", lattice normals" : "");
    // Positions against the full CPU deformation; normals against its transported ones (turned by the lattices), or
    // without lattice normals, against the skinned surface's.
    const double turned = lattice_normals ? largest_angle(cpu.normals(), skinned.normals()) : -1.0;
    largest_turn = std::max(largest_turn, turned);
    ok = compare(what.c_str(), buffer, mesh, cpu.positions(), lattice_normals ? cpu.normals() : skinned.normals(),
                 &moved, turned) &&
         ok;
  }
  if (!(largest_field > 1e-2 * diagonal(cpu.positions())) || (lattice_normals && !(largest_turn > 1e-2))) {
    std::printf("FAIL whole: the lattices moved or turned nothing, the check proves nothing\n");
    ok = false;
  }
  return ok;
}

// The whole deformation under a clip: the full rig (lattices on every limb, with inertia, so the walk makes them
// jiggle: non-affine fields on both arms and legs at once) and the walk sampled with a lead, every frame.
bool check_walk(deform::SkinningMethod method) {
  const deform::Model model = deform::builtin_character();
  const deform::Rig rig = deform::builtin_full_rig(model);
  const deform::Animation walk = deform::builtin_walk(model);
  deform::Character cpu(model, rig);
  cpu.settings.skinning = method;
  for (std::size_t l = 0; l < cpu.deformers().lattice_count(); ++l) {
    deform::LatticeMotion motion = cpu.deformers().spec(l).motion;
    motion.inertia = 1.0f;
    cpu.deformers().set_motion(l, motion);
  }
  deform::Character skinned = cpu.instance();
  skinned.settings.lattice_fields = false;
  deform::Character gpu_pose = cpu.instance();
  gpu_pose.settings.deform_on_cpu = false;
  const deform::Mesh& mesh = model.mesh;
  std::vector<glm::vec3> bind_normals;
  deform::GpuSkinning skinning;
  deform::GpuLatticeFields fields;
  if (!skinning.create(character_bind(gpu_pose, bind_normals)) ||
      !fields.create(gpu_pose.deformers(), mesh.vertex_point, true)) {
    std::printf("FAIL walk: create refused\n");
    return false;
  }
  Buffer buffer(mesh.vertex_count(), layout);
  deform::Pose pose = cpu.skeleton().bind_pose(), later = pose;
  const auto sample = [&](deform::Pose& p, float t) {
    deform::SamplingJob job;
    job.animation = &walk;
    job.time = t;
    job.rotations = p.rotations;
    job.translations = p.translations;
    return job.run();
  };
  // The clip's first pose as a cut (a zero step), as the viewer starts a clip: the twins made by instance() and the
  // constructed one then start alike, with no jump taken as motion.
  if (!sample(pose, 0.0f) || !sample(later, 1e-3f)) return false;
  for (deform::Character* c : {&cpu, &skinned, &gpu_pose}) {
    c->set_pose(pose, later, 1e-3f);
    c->update(0.0f);
  }
  bool ok = true;
  double largest_field = 0.0, largest_turn = 0.0;
  for (int frame = 1; frame <= 40; ++frame) {
    const float t = float(frame) / 60.0f;
    if (!sample(pose, t) || !sample(later, t + 1e-3f)) return false;
    for (deform::Character* c : {&cpu, &skinned, &gpu_pose}) {
      c->set_pose(pose, later, 1e-3f);
      c->update(1.0f / 60.0f);
    }
    if (frame % 13 != 0) continue;
    if (!skinning.skin_into(method, gpu_pose.palette(), buffer.name()) ||
        !fields.apply_into(gpu_pose.deformers(), buffer.name())) {
      std::printf("FAIL walk: refused\n");
      return false;
    }
    double moved = 0.0;
    for (std::size_t p = 0; p < mesh.point_count(); ++p)
      moved = std::max(moved, double(glm::length(cpu.positions()[p] - skinned.positions()[p])));
    largest_field = std::max(largest_field, moved);
    const std::string what = std::string(method == deform::SkinningMethod::dqs ? "DQS" : "LBS") +
                             " walk, full rig with inertia, frame " + std::to_string(frame);
    const double turned = largest_angle(cpu.normals(), skinned.normals());
    largest_turn = std::max(largest_turn, turned);
    ok = compare(what.c_str(), buffer, mesh, cpu.positions(), cpu.normals(), &moved, turned) && ok;
  }
  if (!(largest_field > 1e-3 * diagonal(cpu.positions())) || !(largest_turn > 1e-2)) {
    std::printf("FAIL walk: the lattices moved or turned nothing, the check proves nothing\n");
    ok = false;
  }
  return ok;
}

// ---- Refusals ------------------------------------------------------------------------------------------------------

bool check_refusals() {
  std::mt19937 rng(99);
  Skin skin = random_skin(rng, 100, 4);
  deform::GpuSkinningBind bind;
  bind.positions = skin.positions;
  bind.normals = skin.normals;
  bind.bone_indices = skin.bones;
  bind.bone_weights = skin.weights;
  bind.bone_count = 4;
  bool ok = true;
  const auto expect = [&](const char* what, const deform::Status& s, const char* reason) {
    const bool pass = !s && std::strcmp(s.reason(), reason) == 0;
    if (!pass) std::printf("FAIL refusal %s: got \"%s\"\n", what, s ? "ok" : s.reason());
    ok = ok && pass;
  };
  deform::GpuSkinning gpu;
  // Bind errors.
  {
    deform::GpuSkinningBind b = bind;
    b.bone_count = 0;
    expect("no bones", gpu.create(b), "palette is empty");
    b.bone_count = 3;  // an index 3 is in the skin
    expect("index out of range", gpu.create(b), "bone index out of range");
    b = bind;
    b.normals = b.normals.first(50);
    expect("short normals", gpu.create(b), "the normals are not one per render vertex");
    b = bind;
    b.bone_weights = b.bone_weights.first(99);
    expect("short weights", gpu.create(b), "bone indices, weights and positions differ in count");
    const std::vector<std::uint32_t> vertex_point = {0, 5, 100};
    b = bind;
    b.vertex_point = vertex_point;
    b.normals = {};
    expect("vertex_point", gpu.create(b), "a vertex_point entry is not a point");
    Skin bad = skin;
    bad.weights[7].y = -0.5f;
    b = bind;
    b.bone_weights = bad.weights;
    expect("negative weight", gpu.create(b), "weight is negative");
    bad.weights[7] = glm::vec4(0.0f);
    expect("zero weight sum", gpu.create(b), "weight sum out of range");
    ok = ok && !gpu.created();
  }
  // Per-frame errors.
  const std::vector<glm::mat4> palette(4, glm::mat4(1.0f)), short_palette(3, glm::mat4(1.0f));
  const std::vector<deform::DualQuat> dq(4);
  const std::vector<glm::mat3> scales(3, glm::mat3(1.0f));
  Buffer big(100, layout), small(99, layout);
  expect("nothing created", gpu.skin_into(deform::SkinningMethod::lbs, palette, big.name()), "nothing was created");
  ok = ok && gpu.create(bind);
  expect("palette size", gpu.skin_into(deform::SkinningMethod::lbs, short_palette, big.name()),
         "the palette size differs from the bind's");
  expect("DQS palette size", gpu.skin_into(deform::SkinningMethod::dqs, short_palette, big.name()),
         "the palette size differs from the bind's");
  expect("buffer too small", gpu.skin_into(deform::SkinningMethod::lbs, palette, small.name()),
         "the vertex buffer is too small");
  expect("no buffer", gpu.skin_into(deform::SkinningMethod::lbs, palette, 0), "no vertex buffer");
  expect("layout", gpu.skin_into(deform::SkinningMethod::lbs, palette, big.name(), {8, 6, 2}),
         "the vertex layout does not fit its stride");
  expect("scales", gpu.skin_into(dq, scales, big.name()), "scales and dual quaternions differ in count");
  std::vector<glm::mat4> singular = palette;
  singular[2] = glm::mat4(0.0f);
  expect("singular DQS", gpu.skin_into(deform::SkinningMethod::dqs, singular, big.name()),
         "palette matrix is singular");
  ok = ok && big.read() == big.initial();  // nothing refused wrote anything
  // A move leaves the source empty and the destination working.
  deform::GpuSkinning moved = std::move(gpu);
  ok = ok && !gpu.created() && moved.created() && moved.skin_into(deform::SkinningMethod::lbs, palette, big.name());
  expect("moved from", gpu.skin_into(deform::SkinningMethod::lbs, palette, big.name()), "nothing was created");
  // The additive lattices with normals take their mapped points through their own overload only.
  {
    const deform::Character hero = deform::make_builtin_character();
    const deform::DeformerHierarchy& h = hero.deformers();
    const deform::Mesh& mesh = hero.model().mesh;
    Buffer vertices(mesh.vertex_count(), layout);
    std::vector<glm::vec3> mapped(h.rest_lattice(0).point_count());
    h.mapped_points(0, mapped);
    deform::GpuBezierLattice with, without;
    ok = ok && with.create_additive(h.binding(0), h.bound_weights(0), mesh.vertex_point, true) && with.has_normals();
    ok = ok && without.create_additive(h.binding(0), h.bound_weights(0), mesh.vertex_point);
    expect("normals, plain call", with.evaluate_into(h.displacements(0), vertices.name()),
           "an additive lattice with normals also takes its mapped points and to_bind");
    expect("mapped count",
           with.evaluate_into(h.displacements(0), std::span(mapped).first(3), glm::mat3(1.0f), vertices.name()),
           "the mapped point count differs from the binding's");
    expect("no normals", without.evaluate_into(h.displacements(0), mapped, glm::mat3(1.0f), vertices.name()),
           "not an additive lattice with normals");
    ok = ok && vertices.read() == vertices.initial();
  }
  std::printf("%s refusals\n", ok ? "ok  " : "FAIL");
  return ok;
}

// An OpenGL ES 3.2 context has compute shaders, but not desktop GL 4.3: supported() is false and create() refuses
// with its reason (what a 3.x desktop context would give; Mesa hands out 4.5 core whatever is asked for).
bool check_es_context() {
  GLFWwindow* const previous = glfwGetCurrentContext();
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_ES_API);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  GLFWwindow* es = glfwCreateWindow(16, 16, "es", nullptr, nullptr);
  if (!es) {
    std::printf("note no OpenGL ES context here: the unsupported-context refusal is not exercised\n");
    return true;
  }
  glfwMakeContextCurrent(es);
  std::mt19937 rng(5);
  const Skin skin = random_skin(rng, 10, 2);
  deform::GpuSkinningBind bind;
  bind.positions = skin.positions;
  bind.bone_indices = skin.bones;
  bind.bone_weights = skin.weights;
  bind.bone_count = 2;
  deform::GpuSkinning gpu;
  const deform::Status s = gpu.create(bind);
  const bool ok = !deform::GpuSkinning::supported() && !s &&
                  std::strcmp(s.reason(), "the current context is not OpenGL 4.3") == 0 && !gpu.created();
  glfwMakeContextCurrent(previous);
  glfwDestroyWindow(es);
  std::printf("%s an OpenGL ES context is refused (%s)\n", ok ? "ok  " : "FAIL", s ? "accepted" : s.reason());
  return ok;
}

// ---- Indicative timings (--bench) ----------------------------------------------------------------------------------

// Mean milliseconds per call of `frame` over about a second.
template <class Frame>
double time_ms(Frame&& frame) {
  using clock = std::chrono::steady_clock;
  int frames = 0;
  const auto start = clock::now();
  double elapsed = 0.0;
  do {
    frame();
    ++frames;
    elapsed = std::chrono::duration<double>(clock::now() - start).count();
  } while (elapsed < 1.0);
  return elapsed / frames * 1e3;
}

// A whole frame of the built-in character with the full rig (lattices on every limb, jiggling under the walk): the CPU
// deforming (Character::update, transported normals) against the CPU posing and the GPU deforming.
void bench_character() {
  const deform::Model model = deform::builtin_character();
  const deform::Animation walk = deform::builtin_walk(model);
  deform::Character cpu(model, deform::builtin_full_rig(model));
  deform::Character gpu_pose = cpu.instance();
  gpu_pose.settings.deform_on_cpu = false;
  std::vector<glm::vec3> bind_normals;
  deform::GpuSkinning skinning;
  deform::GpuLatticeFields fields;
  if (!skinning.create(character_bind(gpu_pose, bind_normals)) ||
      !fields.create(gpu_pose.deformers(), model.mesh.vertex_point, true))
    return;
  Buffer buffer(model.mesh.vertex_count(), layout);
  deform::Pose pose = cpu.skeleton().bind_pose();
  float t = 0.0f;
  const auto pose_next = [&](deform::Character& c) {
    t += 1.0f / 60.0f;
    deform::SamplingJob job;
    job.animation = &walk;
    job.time = t;
    job.rotations = pose.rotations;
    job.translations = pose.translations;
    job.run();
    c.set_pose(pose);
  };
  const double cpu_ms = time_ms([&] {
    pose_next(cpu);
    cpu.update(1.0f / 60.0f);
    cpu.normals();
  });
  const double pose_ms = time_ms([&] {
    pose_next(gpu_pose);
    gpu_pose.update(1.0f / 60.0f);
  });
  const double gpu_ms = time_ms([&] {
    pose_next(gpu_pose);
    gpu_pose.update(1.0f / 60.0f);
    skinning.skin_into(gpu_pose.settings.skinning, gpu_pose.palette(), buffer.name());
    fields.apply_into(gpu_pose.deformers(), buffer.name());
    glFinish();
  });
  std::printf(
      "built-in character, full rig, walk (%zu render vertices): CPU update + normals %.3f ms; CPU posing "
      "only %.3f ms; posing + GPU skinning and lattices + glFinish %.3f ms\n",
      model.mesh.vertex_count(), cpu_ms, pose_ms, gpu_ms);
}

int bench() {
  bench_character();
  std::mt19937 rng(7);
  for (const std::size_t points : {std::size_t{10000}, std::size_t{100000}}) {
    const int bones = 64;
    const Skin skin = random_skin(rng, points, bones);
    const std::vector<glm::mat4> palette = random_palette(rng, bones, PaletteKind::rigid);
    deform::GpuSkinningBind bind;
    bind.positions = skin.positions;
    bind.normals = skin.normals;
    bind.bone_indices = skin.bones;
    bind.bone_weights = skin.weights;
    bind.bone_count = bones;
    deform::GpuSkinning gpu;
    if (!gpu.create(bind)) return 1;
    Buffer buffer(points, layout);
    std::vector<glm::vec3> out_p(points), out_n(points);
    for (const deform::SkinningMethod method : {deform::SkinningMethod::lbs, deform::SkinningMethod::dqs}) {
      std::vector<deform::DualQuat> dq(bones);
      std::vector<glm::mat3> scales(bones);
      const double cpu_ms = time_ms([&] {
        deform::SkinningJob job;
        job.method = method;
        job.matrices = palette;
        bool has_scale = false;
        if (method == deform::SkinningMethod::dqs) deform::compute_dual_quat_palette(palette, dq, scales, has_scale);
        job.dual_quats = dq;
        job.bone_indices = skin.bones;
        job.bone_weights = skin.weights;
        job.in_positions = deform::as_floats(skin.positions);
        job.out_positions = deform::as_floats(out_p);
        job.in_normals = deform::as_floats(skin.normals);
        job.out_normals = deform::as_floats(out_n);
        job.run();
      });
      const double gpu_ms = time_ms([&] {
        gpu.skin_into(method, palette, buffer.name());
        glFinish();
      });
      std::printf("%s %6zu vertices: CPU SkinningJob (1 thread) %.3f ms, GPU skin_into + glFinish %.3f ms\n",
                  method == deform::SkinningMethod::dqs ? "DQS" : "LBS", points, cpu_ms, gpu_ms);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const bool bench_mode = argc > 1 && std::string(argv[1]) == "--bench";
  return gpu_test::run_in_context(
      "gpu_skinning_check",
      [&] {
        if (bench_mode) return bench();
        bool ok = check_refusals();
        for (const unsigned seed : {1u, 2u, 3u}) ok = check_random(seed) && ok;
        ok = check_clips() && ok;
        for (const deform::SkinningMethod method : {deform::SkinningMethod::lbs, deform::SkinningMethod::dqs}) {
          ok = check_whole(method, 3, false, true) && ok;
          ok = check_whole(method, 5, true, true) && ok;
          ok = check_whole(method, 3, false, false) && ok;
          ok = check_walk(method) && ok;
        }
        ok = check_es_context() && ok;
        return ok ? 0 : 1;
      },
      !bench_mode);
}
