// Skinning: every kernel (scalar, AVX2, AVX-512 where this CPU has them) against plain double-precision reference
// implementations written here, plus the properties of the issue: bind pose, rigid rotation, renormalised weights,
// candy-wrapper, DQS == LBS for one bone, the DQS palette, validate().
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/parallel.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
#include "deform/runtime/skinning.hpp"
using namespace deform;

namespace {

// ---------------------------------------------------------------------------------------------------------------
// Plain reference implementations (double precision, written from the definitions, no shared code with the kernels).

// LBS: M = Σ wₖ Mₖ / Σ wₖ; p' = M p; n' = normalise(det(A) · A⁻ᵀ n) with A the 3×3 of M.
void reference_lbs(std::span<const glm::mat4> palette, glm::u16vec4 b, glm::vec4 w, glm::vec3 p, glm::vec3 n,
                   glm::dvec3& out_p, glm::dvec3& out_n) {
  glm::dmat4 m(0.0);
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) m += double(w[k]) * glm::dmat4(palette[b[k]]), sum += w[k];
  m /= sum;
  out_p = glm::dvec3(m * glm::dvec4(glm::dvec3(p), 1.0));
  const glm::dmat3 a(m);
  const glm::dvec3 mapped = glm::determinant(a) * (glm::transpose(glm::inverse(a)) * glm::dvec3(n));
  out_n = glm::length(mapped) > 0.0 ? glm::normalize(mapped) : mapped;
}

// DQS (Kavan et al. 2007): b = Σ ±wₖ q̂ₖ with the sign of each real part's dot with the first; b / |b.real|; then the
// rigid transform of b as a matrix (R from the unit real part, t = 2 · dual · conj(real)). With `scales`, the blended
// S = Σ wₖ Sₖ / Σ wₖ is applied first (its cofactor for the normal).
void reference_dqs(std::span<const DualQuat> palette, std::span<const glm::mat3> scales, glm::u16vec4 b, glm::vec4 w,
                   glm::vec3 p, glm::vec3 n, glm::dvec3& out_p, glm::dvec3& out_n) {
  const glm::dquat pivot(palette[b[0]].real);
  glm::dquat real(0.0, 0.0, 0.0, 0.0), dual(0.0, 0.0, 0.0, 0.0);
  glm::dmat3 s(0.0);
  double sum = 0.0;
  for (int k = 0; k < 4; ++k) {
    const glm::dquat r(palette[b[k]].real), d(palette[b[k]].dual);
    const double weight = glm::dot(r, pivot) < 0.0 ? -double(w[k]) : double(w[k]);
    real = real + weight * r;
    dual = dual + weight * d;
    if (!scales.empty()) s += double(w[k]) * glm::dmat3(scales[b[k]]);
    sum += w[k];
  }
  const double length = glm::length(real);
  real = real / length, dual = dual / length;
  const glm::dquat t = 2.0 * dual * glm::conjugate(real);
  const glm::dmat3 rotation = glm::mat3_cast(real);
  glm::dvec3 ps(p), ns(n);
  if (!scales.empty()) {
    s /= sum;
    ps = s * ps;
    ns = glm::determinant(s) * (glm::transpose(glm::inverse(s)) * ns);
  }
  out_p = rotation * ps + glm::dvec3(t.x, t.y, t.z);
  const glm::dvec3 mapped = rotation * ns;
  out_n = glm::length(mapped) > 0.0 ? glm::normalize(mapped) : mapped;
}

// ---------------------------------------------------------------------------------------------------------------

std::vector<Isa> available_isas() {
  std::vector<Isa> isas;
  for (Isa isa : {Isa::portable, Isa::avx2, Isa::avx512, Isa::neon, Isa::simd128})
    if (isa_available(isa)) isas.push_back(isa);
  return isas;
}

glm::quat random_rotation(std::mt19937& rng, float max_degrees) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  glm::vec3 axis{u(rng), u(rng), u(rng)};
  if (glm::length(axis) < 1e-3f) axis = glm::vec3(0, 0, 1);
  return glm::angleAxis(glm::radians(max_degrees * u(rng)), glm::normalize(axis));
}

// Palette of `bones` affine matrices: rotation up to `max_degrees`, translation in [-1, 1]³, and when `scale` a
// non-uniform scale in [0.6, 1.6] applied first.
std::vector<glm::mat4> random_palette(std::mt19937& rng, int bones, float max_degrees, bool scale) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(0.6f, 1.6f);
  std::vector<glm::mat4> palette;
  for (int i = 0; i < bones; ++i) {
    glm::mat4 m = glm::mat4_cast(random_rotation(rng, max_degrees));
    m[3] = glm::vec4{u(rng), u(rng), u(rng), 1.0f};
    if (scale) m = m * glm::scale(glm::mat4(1.0f), glm::vec3{s(rng), s(rng), s(rng)});
    palette.push_back(m);
  }
  return palette;
}

// A mesh-like vertex set: positions in [-2, 2]³, unit normals, 1 to 4 influences (strongest first, unused slots
// weight 0), weights summing to one except every 7th vertex (sum in [0.5, 2]: the kernels renormalise).
struct Vertices {
  std::vector<glm::vec3> positions, normals;
  std::vector<glm::u16vec4> bones;
  std::vector<glm::vec4> weights;
};

Vertices random_vertices(std::mt19937& rng, std::size_t count, int bone_count) {
  std::uniform_real_distribution<float> u(-2.0f, 2.0f), unit(0.0f, 1.0f), scale(0.5f, 2.0f);
  std::uniform_int_distribution<int> bone(0, bone_count - 1), influences(1, 4);
  Vertices v;
  for (std::size_t i = 0; i < count; ++i) {
    v.positions.push_back({u(rng), u(rng), u(rng)});
    glm::vec3 n{u(rng), u(rng), u(rng)};
    v.normals.push_back(glm::length(n) > 1e-3f ? glm::normalize(n) : glm::vec3(0, 1, 0));
    glm::u16vec4 b(0);
    glm::vec4 w(0.0f);
    const int used = influences(rng);
    float sum = 0.0f;
    for (int k = 0; k < used; ++k) b[k] = static_cast<std::uint16_t>(bone(rng)), w[k] = 0.05f + unit(rng), sum += w[k];
    w /= sum;
    if (i % 7 == 3) w *= scale(rng);
    v.bones.push_back(b);
    v.weights.push_back(w);
  }
  return v;
}

double error_3(glm::dvec3 reference, const float* got) {
  const double scale = std::max(1.0, glm::length(reference));
  return glm::length(reference - glm::dvec3(got[0], got[1], got[2])) / scale;
}

enum class Layout { separate, interleaved };

// Runs `job` (palettes set) over `v` in the given layout and compares every vertex with the reference.
// Interleaved: one float buffer of 10 floats per vertex (position at 0, padding, normal at 5: stride 40 bytes).
double max_error_vs_reference(SkinningJob job, const Vertices& v, Layout layout, bool normals,
                              std::span<const glm::mat4> matrices, std::span<const DualQuat> dual_quats,
                              std::span<const glm::mat3> scales) {
  const std::size_t count = v.positions.size();
  job.bone_indices = v.bones;
  job.bone_weights = v.weights;
  std::vector<float> in, out;
  std::size_t position_offset = 0, normal_offset = 0, stride = 12;
  if (layout == Layout::separate) {
    in.resize(count * 6), out.assign(count * 6, -7.0f);
    for (std::size_t i = 0; i < count; ++i)
      for (int c = 0; c < 3; ++c) in[3 * i + c] = v.positions[i][c], in[3 * count + 3 * i + c] = v.normals[i][c];
    normal_offset = 3 * count;
  } else {
    stride = 40, normal_offset = 5;
    in.assign(count * 10, 99.0f), out.assign(count * 10, -7.0f);
    for (std::size_t i = 0; i < count; ++i)
      for (int c = 0; c < 3; ++c) in[10 * i + c] = v.positions[i][c], in[10 * i + 5 + c] = v.normals[i][c];
  }
  const std::size_t stream_floats = (count - 1) * stride / 4 + 3;
  job.in_positions = std::span<const float>(in.data() + position_offset, stream_floats);
  job.out_positions = std::span<float>(out.data() + position_offset, stream_floats);
  job.in_positions_stride = job.out_positions_stride = stride;
  if (normals) {
    job.in_normals = std::span<const float>(in.data() + normal_offset, stream_floats);
    job.out_normals = std::span<float>(out.data() + normal_offset, stream_floats);
    job.in_normals_stride = job.out_normals_stride = stride;
  }
  REQUIRE(job.validate());
  REQUIRE(job.run());
  double worst = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    glm::dvec3 p, n;
    if (job.method == SkinningMethod::lbs)
      reference_lbs(matrices, v.bones[i], v.weights[i], v.positions[i], v.normals[i], p, n);
    else reference_dqs(dual_quats, scales, v.bones[i], v.weights[i], v.positions[i], v.normals[i], p, n);
    worst = std::max(worst, error_3(p, job.out_positions.data() + i * stride / 4));
    if (normals) worst = std::max(worst, error_3(n, job.out_normals.data() + i * stride / 4));
  }
  // Bytes between the streams (interleaved padding) are never written.
  if (layout == Layout::interleaved)
    for (std::size_t i = 0; i < count; ++i) {
      CHECK(out[10 * i + 3] == -7.0f);
      CHECK(out[10 * i + 9] == -7.0f);
      if (!normals) CHECK(out[10 * i + 5] == -7.0f);
    }
  return worst;
}

struct DqsPalette {
  std::vector<DualQuat> dual_quats;
  std::vector<glm::mat3> scales;
  bool has_scale = false;
};

DqsPalette dqs_palette(std::span<const glm::mat4> matrices) {
  DqsPalette p;
  p.dual_quats.resize(matrices.size());
  p.scales.resize(matrices.size());
  REQUIRE(compute_dual_quat_palette(matrices, p.dual_quats, p.scales, p.has_scale));
  return p;
}

}  // namespace

TEST_CASE("every kernel equals the reference to 1e-5: random palettes, weights, tails and layouts") {
  std::mt19937 rng(20240611);
  const std::size_t counts[] = {1, 5, 15, 16, 17, 33, 1000, 4099};
  for (Isa isa : available_isas())
    for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs})
      for (bool scaled : {false, true})
        for (Layout layout : {Layout::separate, Layout::interleaved})
          for (bool normals : {true, false})
            for (std::size_t count : counts)
              for (int palette_size : {0, 1, 2}) {  // AVX-512: tables for <= 32 and <= 64 bones, a general path above
                CAPTURE(isa_name(isa));
                CAPTURE(int(method));
                CAPTURE(scaled);
                CAPTURE(int(layout));
                CAPTURE(normals);
                CAPTURE(count);
                CAPTURE(palette_size);
                const int bones = palette_size == 0   ? 1 + int(count % 32)
                                  : palette_size == 1 ? 33 + int(count % 32)
                                                      : 65 + int(count % 40);
                const std::vector<glm::mat4> matrices = random_palette(rng, bones, 150.0f, scaled);
                const DqsPalette dq = dqs_palette(matrices);
                CHECK(dq.has_scale == scaled);
                Vertices v = random_vertices(rng, count, bones);
                // 33 to 64 bones: runs of 24 vertices (not block-aligned) on bones below 32 alone, so that blocks all
                // below 32 (the narrow lookups), all mixed and partly mixed occur.
                if (palette_size == 1)
                  for (std::size_t i = 0; i < count; ++i)
                    if ((i / 24) % 2 == 0) v.bones[i] %= glm::u16vec4(32);
                SkinningJob job;
                job.method = method;
                job.isa = isa;
                job.matrices = matrices;
                job.dual_quats = dq.dual_quats;
                if (dq.has_scale) job.scales = dq.scales;
                CHECK(max_error_vs_reference(job, v, layout, normals, matrices, dq.dual_quats, job.scales) <= 1e-5);
              }
}

TEST_CASE("isa: the automatic path is the best available one; names; forced paths report availability") {
  CHECK(isa_available(Isa::automatic));
  CHECK(isa_available(Isa::portable));
  CHECK(isa_available(isa_best()));
  CHECK(isa_best() != Isa::automatic);
  if (isa_available(Isa::neon)) {  // aarch64 builds: always, and never an x86 copy
    CHECK(isa_best() == Isa::neon);
    CHECK_FALSE(isa_available(Isa::avx2));
  } else if (isa_available(Isa::simd128)) {  // WebAssembly builds with DEFORM_WASM_SIMD128: chosen by the build
    CHECK(isa_best() == Isa::simd128);
    CHECK_FALSE(isa_available(Isa::avx2));
    CHECK_FALSE(isa_available(Isa::neon));
  } else if (isa_available(Isa::avx512)) {
    CHECK(isa_best() == Isa::avx512);
    CHECK(isa_available(Isa::avx2));  // the AVX-512 copies use AVX2 and FMA too
  } else if (isa_available(Isa::avx2)) {
    CHECK(isa_best() == Isa::avx2);
  } else {
    CHECK(isa_best() == Isa::portable);
  }
  CHECK(std::string(isa_name(Isa::automatic)) == "automatic");
  CHECK(std::string(isa_name(Isa::portable)) == "portable");
  CHECK(std::string(isa_name(Isa::avx2)) == "avx2");
  CHECK(std::string(isa_name(Isa::avx512)) == "avx512");
  CHECK(std::string(isa_name(Isa::neon)) == "neon");
  CHECK(std::string(isa_name(Isa::simd128)) == "simd128");
  CHECK(std::string(isa_name(static_cast<Isa>(9))) == "unknown");
  CHECK_FALSE(isa_available(static_cast<Isa>(9)));
  MESSAGE("best kernel copy here: " << isa_name(isa_best()));
}

TEST_CASE("the bind pose reproduces the mesh to 1e-6") {
  // A small chain with non-trivial bind rotations: palette = world(bind) · inverse(bind world) ≈ identity.
  std::vector<Bone> bones(4);
  bones[0] = Bone{"root", -1, {1}, {0.1f, 0.2f, 0.3f}, {10.0f, 20.0f, 30.0f}, {}};
  bones[1] = Bone{"a", 0, {2, 3}, {0.0f, 1.0f, 0.0f}, {-45.0f, 0.0f, 90.0f}, {}};
  bones[2] = Bone{"b", 1, {}, {0.0f, 1.0f, 0.0f}, {0.0f, 60.0f, 0.0f}, {}};
  bones[3] = Bone{"c", 1, {}, {0.5f, 0.0f, 0.0f}, {170.0f, -80.0f, 5.0f}, {}};
  const Skeleton skeleton(bones);
  std::vector<glm::mat4> world(4), palette(4);
  const Pose bind = skeleton.bind_pose();
  LocalToWorldJob fk;
  fk.skeleton = &skeleton;
  fk.rotations = bind.rotations;
  fk.translations = bind.translations;
  fk.world = world;
  fk.palette = palette;
  REQUIRE(fk.run());
  std::mt19937 rng(7);
  Vertices v = random_vertices(rng, 1001, 4);
  for (glm::vec3& p : v.positions) p *= 0.5f;  // unit-scale positions: the 1e-6 bound is absolute
  const DqsPalette dq = dqs_palette(palette);
  CHECK_FALSE(dq.has_scale);
  for (Isa isa : available_isas())
    for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs}) {
      CAPTURE(isa_name(isa));
      CAPTURE(int(method));
      std::vector<glm::vec3> out_p(v.positions.size()), out_n(v.positions.size());
      SkinningJob job;
      job.method = method, job.isa = isa, job.matrices = palette, job.dual_quats = dq.dual_quats;
      job.bone_indices = v.bones, job.bone_weights = v.weights;
      job.in_positions = as_floats((v.positions)), job.out_positions = as_floats(out_p);
      job.in_normals = as_floats((v.normals)), job.out_normals = as_floats(out_n);
      REQUIRE(job.run());
      float worst_p = 0.0f, worst_n = 0.0f;
      for (std::size_t i = 0; i < out_p.size(); ++i) {
        worst_p = std::max(worst_p, glm::length(out_p[i] - v.positions[i]));
        worst_n = std::max(worst_n, glm::length(out_n[i] - v.normals[i]));
      }
      CHECK(worst_p <= 1e-6f);
      CHECK(worst_n <= 1e-6f);
    }
}

TEST_CASE("a single-bone rigid rotation is exact, and DQS equals LBS when all influences share one bone") {
  std::mt19937 rng(11);
  const std::vector<glm::mat4> palette = random_palette(rng, 5, 180.0f, false);
  const DqsPalette dq = dqs_palette(palette);
  Vertices v = random_vertices(rng, 999, 5);
  for (std::size_t i = 0; i < v.bones.size(); ++i) {
    const std::uint16_t b = v.bones[i][0];
    v.bones[i] = glm::u16vec4(b);  // four slots, one bone, arbitrary positive weights
  }
  for (Isa isa : available_isas()) {
    CAPTURE(isa_name(isa));
    std::vector<glm::vec3> lbs_p(v.positions.size()), lbs_n(lbs_p.size()), dqs_p(lbs_p.size()), dqs_n(lbs_p.size());
    SkinningJob job;
    job.isa = isa, job.matrices = palette, job.dual_quats = dq.dual_quats;
    job.bone_indices = v.bones, job.bone_weights = v.weights;
    job.in_positions = as_floats((v.positions));
    job.in_normals = as_floats((v.normals));
    job.out_positions = as_floats(lbs_p), job.out_normals = as_floats(lbs_n);
    REQUIRE(job.run());
    job.method = SkinningMethod::dqs, job.out_positions = as_floats(dqs_p), job.out_normals = as_floats(dqs_n);
    REQUIRE(job.run());
    float worst_rigid = 0.0f, worst_agree = 0.0f;
    for (std::size_t i = 0; i < lbs_p.size(); ++i) {
      const glm::mat4& m = palette[v.bones[i][0]];
      const glm::vec3 expected_p(m * glm::vec4(v.positions[i], 1.0f));
      const glm::vec3 expected_n = glm::mat3(m) * v.normals[i];
      worst_rigid = std::max({worst_rigid, glm::length(lbs_p[i] - expected_p), glm::length(dqs_p[i] - expected_p),
                              glm::length(lbs_n[i] - expected_n), glm::length(dqs_n[i] - expected_n)});
      worst_agree = std::max({worst_agree, glm::length(lbs_p[i] - dqs_p[i]), glm::length(lbs_n[i] - dqs_n[i])});
    }
    CHECK(worst_rigid <= 4e-6f);  // |p| ≤ 3.5, |t| ≤ 1.7: a few float roundings of a 5-unit result
    CHECK(worst_agree <= 4e-6f);
  }
}

TEST_CASE("weights that do not sum to one are renormalised") {
  std::mt19937 rng(3);
  const std::vector<glm::mat4> palette = random_palette(rng, 3, 120.0f, true);
  const DqsPalette dq = dqs_palette(palette);
  Vertices v = random_vertices(rng, 64, 3);
  std::vector<glm::vec4> scaled_weights = v.weights;
  for (std::size_t i = 0; i < scaled_weights.size(); ++i) scaled_weights[i] *= 0.25f + 0.1f * float(i % 30);
  for (Isa isa : available_isas())
    for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs}) {
      std::vector<glm::vec3> a(64), b(64);
      SkinningJob job;
      job.isa = isa, job.method = method, job.matrices = palette, job.dual_quats = dq.dual_quats,
      job.scales = dq.scales;
      job.bone_indices = v.bones, job.bone_weights = v.weights;
      job.in_positions = as_floats((v.positions)), job.out_positions = as_floats(a);
      REQUIRE(job.run());
      job.bone_weights = scaled_weights, job.out_positions = as_floats(b);
      REQUIRE(job.run());
      for (std::size_t i = 0; i < a.size(); ++i) CHECK(glm::length(a[i] - b[i]) <= 1e-5f);
    }
}

TEST_CASE("candy-wrapper: a twist collapses an LBS cylinder, DQS keeps its radius within 2%") {
  // Cylinder of radius 1 along x from 0 to 2; bone 0 holds x < 0.5, bone 1 holds x > 1.5, linear blend between.
  Vertices v;
  std::vector<float> ring_x;
  for (int ring = 0; ring <= 20; ++ring)
    for (int s = 0; s < 24; ++s) {
      const float x = 0.1f * float(ring), angle = 2.0f * 3.14159265f * float(s) / 24.0f;
      v.positions.emplace_back(x, std::cos(angle), std::sin(angle));
      v.normals.emplace_back(0.0f, std::cos(angle), std::sin(angle));
      const float t = std::clamp(x - 0.5f, 0.0f, 1.0f);
      v.bones.emplace_back(0, 1, 0, 0);
      v.weights.emplace_back(1.0f - t, t, 0.0f, 0.0f);
    }
  for (float twist : {90.0f, 135.0f, 180.0f}) {
    CAPTURE(twist);
    const std::vector<glm::mat4> palette = {glm::mat4(1.0f),
                                            glm::rotate(glm::mat4(1.0f), glm::radians(twist), glm::vec3(1, 0, 0))};
    const DqsPalette dq = dqs_palette(palette);
    for (Isa isa : available_isas()) {
      CAPTURE(isa_name(isa));
      std::vector<glm::vec3> lbs(v.positions.size()), dqs(v.positions.size());
      SkinningJob job;
      job.isa = isa, job.matrices = palette, job.dual_quats = dq.dual_quats;
      job.bone_indices = v.bones, job.bone_weights = v.weights;
      job.in_positions = as_floats((v.positions)), job.out_positions = as_floats(lbs);
      REQUIRE(job.run());
      job.method = SkinningMethod::dqs, job.out_positions = as_floats(dqs);
      REQUIRE(job.run());
      float lbs_min = 10.0f, dqs_min = 10.0f, dqs_max = 0.0f;
      for (std::size_t i = 0; i < lbs.size(); ++i) {
        const float lbs_radius = std::hypot(lbs[i].y, lbs[i].z), dqs_radius = std::hypot(dqs[i].y, dqs[i].z);
        lbs_min = std::min(lbs_min, lbs_radius);
        dqs_min = std::min(dqs_min, dqs_radius), dqs_max = std::max(dqs_max, dqs_radius);
        CHECK(std::abs(dqs[i].x - v.positions[i].x) <= 1e-5f);  // a twist about the axis moves nothing along it
      }
      // LBS at the middle ring: radius |cos(twist / 2)| (0.707 at 90°, 0 at 180°).
      CHECK(lbs_min <= std::abs(std::cos(glm::radians(twist) / 2.0f)) + 1e-4f);
      CHECK(lbs_min < 0.75f);
      CHECK(dqs_min >= 0.98f);
      CHECK(dqs_max <= 1.02f);
    }
  }
}

TEST_CASE("compute_dual_quat_palette: rigid, scaled and mirrored matrices recompose; bad input writes nothing") {
  std::mt19937 rng(5);
  std::vector<glm::mat4> matrices = random_palette(rng, 6, 180.0f, true);
  matrices.push_back(glm::scale(glm::mat4(1.0f), glm::vec3(-1.0f, 2.0f, 0.5f)));  // mirroring
  matrices.push_back(glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)));        // rigid
  const DqsPalette dq = dqs_palette(matrices);
  CHECK(dq.has_scale);
  for (std::size_t i = 0; i < matrices.size(); ++i) {
    CAPTURE(i);
    const glm::quat r = dq.dual_quats[i].real;
    CHECK(std::abs(glm::length(r) - 1.0f) <= 1e-6f);
    const glm::quat t = 2.0f * dq.dual_quats[i].dual * glm::conjugate(r);
    const glm::mat3 recomposed = glm::mat3_cast(r) * dq.scales[i];
    for (int c = 0; c < 3; ++c) CHECK(glm::length(recomposed[c] - glm::vec3(matrices[i][c])) <= 1e-5f);
    CHECK(glm::length(glm::vec3(t.x, t.y, t.z) - glm::vec3(matrices[i][3])) <= 1e-5f);
    // S is symmetric (polar decomposition).
    CHECK(std::abs(dq.scales[i][0][1] - dq.scales[i][1][0]) <= 1e-5f);
  }
  CHECK(glm::length(dq.scales.back()[0] - glm::vec3(1, 0, 0)) <= 1e-6f);

  std::vector<DualQuat> out(2);
  std::vector<glm::mat3> scales(2, glm::mat3(7.0f));
  bool has_scale = true;
  const std::vector<glm::mat4> singular = {glm::mat4(1.0f), glm::scale(glm::mat4(1.0f), glm::vec3(1, 0, 1))};
  CHECK(std::string(compute_dual_quat_palette(singular, out, scales, has_scale).reason()) ==
        "palette matrix is singular");
  CHECK(scales[0] == glm::mat3(7.0f));
  CHECK(std::string(compute_dual_quat_palette(std::span<const glm::mat4>(singular).first(1), out, scales, has_scale)
                        .reason()) == "palette sizes differ");
  std::vector<glm::mat4> not_finite = {glm::mat4(1.0f), glm::mat4(1.0f)};
  not_finite[1][3][0] = std::numeric_limits<float>::infinity();
  CHECK(std::string(compute_dual_quat_palette(not_finite, out, scales, has_scale).reason()) ==
        "palette matrix is not finite");
  CHECK(scales[0] == glm::mat3(7.0f));
  const std::vector<glm::mat4> rigid = {glm::mat4(1.0f), glm::rotate(glm::mat4(1.0f), 1.0f, glm::vec3(0, 1, 0))};
  CHECK(compute_dual_quat_palette(rigid, out, scales, has_scale));
  CHECK_FALSE(has_scale);
}

TEST_CASE("the thread-pool split and in-place skinning give the single-thread result") {
  std::mt19937 rng(9);
  const std::vector<glm::mat4> palette = random_palette(rng, 20, 170.0f, true);
  const DqsPalette dq = dqs_palette(palette);
  const Vertices v = random_vertices(rng, 50'003, 20);
  ThreadPool pool(4);
  for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs}) {
    std::vector<glm::vec3> serial_p(v.positions.size()), serial_n(serial_p.size());
    std::vector<glm::vec3> inplace_p = v.positions, inplace_n = v.normals;
    std::vector<glm::vec3> parallel_p(serial_p.size()), parallel_n(serial_p.size());
    SkinningJob job;
    job.method = method, job.matrices = palette, job.dual_quats = dq.dual_quats;
    job.bone_indices = v.bones, job.bone_weights = v.weights;
    job.in_positions = as_floats((v.positions));
    job.in_normals = as_floats((v.normals));
    job.out_positions = as_floats(serial_p), job.out_normals = as_floats(serial_n);
    REQUIRE(job.run());
    job.out_positions = as_floats(parallel_p), job.out_normals = as_floats(parallel_n);
    REQUIRE(run_parallel(job, pool, 1000));
    CHECK(parallel_p == serial_p);
    CHECK(parallel_n == serial_n);
    job.in_positions = as_floats((inplace_p)), job.out_positions = as_floats(inplace_p);
    job.in_normals = as_floats((inplace_n)), job.out_normals = as_floats(inplace_n);
    REQUIRE(job.validate());
    REQUIRE(run_parallel(job, pool, 1000));
    CHECK(inplace_p == serial_p);
    CHECK(inplace_n == serial_n);
  }
}

TEST_CASE("a vertex's result does not depend on where its range begins, nor on streaming stores") {
  // Every path, both methods, both palette kinds of the AVX-512 kernel: run(begin, end) over seeded random ranges
  // gives bit for bit the vertices of run() (partial blocks at either end run the block code), and so do streaming
  // stores with the outputs at every 4-byte offset of a 64-byte line (the head up to the first aligned vertex is a
  // partial block too) and in place.
  std::mt19937 rng(77);
  for (Isa isa : available_isas())
    for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs})
      for (int bones : {20, 40}) {
        CAPTURE(isa_name(isa));
        CAPTURE(int(method));
        CAPTURE(bones);
        const std::vector<glm::mat4> palette = random_palette(rng, bones, 170.0f, false);
        const DqsPalette dq = dqs_palette(palette);
        const Vertices v = random_vertices(rng, 1000, bones);
        SkinningJob job;
        job.method = method, job.isa = isa, job.matrices = palette, job.dual_quats = dq.dual_quats;
        job.bone_indices = v.bones, job.bone_weights = v.weights;
        job.in_positions = as_floats(v.positions), job.in_normals = as_floats(v.normals);
        std::vector<glm::vec3> whole_p(v.positions.size()), whole_n(v.positions.size());
        job.out_positions = as_floats(whole_p), job.out_normals = as_floats(whole_n);
        REQUIRE(job.run());

        std::vector<glm::vec3> part_p(whole_p.size()), part_n(whole_p.size());
        job.out_positions = as_floats(part_p), job.out_normals = as_floats(part_n);
        std::uniform_int_distribution<std::size_t> cut(0, v.positions.size());
        for (int range = 0; range < 50; ++range) {
          std::size_t begin = cut(rng), end = cut(rng);
          if (begin > end) std::swap(begin, end);
          REQUIRE(job.run(begin, end));
          bool same = true;
          for (std::size_t i = begin; i < end; ++i) same = same && part_p[i] == whole_p[i] && part_n[i] == whole_n[i];
          CHECK(same);
        }

        // Streaming: outputs placed at each offset within a 64-byte line (the same for both streams).
        std::vector<glm::vec4> storage_p(v.positions.size() + 16), storage_n(v.positions.size() + 16);
        job.stream_outputs = true;
        for (std::size_t offset = 0; offset < 64; offset += 4) {
          const auto at = [&](std::vector<glm::vec4>& storage) {
            const auto base = reinterpret_cast<std::uintptr_t>(storage.data());
            return reinterpret_cast<float*>(((base + 63) & ~std::uintptr_t{63}) + offset);
          };
          job.out_positions = {at(storage_p), 3 * v.positions.size()};
          job.out_normals = {at(storage_n), 3 * v.positions.size()};
          for (const auto& [begin, end] : {std::pair<std::size_t, std::size_t>{0, 1000}, {3, 997}, {5, 12}}) {
            REQUIRE(job.run(begin, end));
            bool same = true;
            for (std::size_t i = begin; i < end; ++i)
              for (std::size_t c = 0; c < 3; ++c)
                same = same && job.out_positions[3 * i + c] == whole_p[i][int(c)] &&
                       job.out_normals[3 * i + c] == whole_n[i][int(c)];
            CHECK(same);
          }
        }
        std::vector<glm::vec3> inplace_p = v.positions, inplace_n = v.normals;
        job.in_positions = as_floats(inplace_p), job.out_positions = as_floats(inplace_p);
        job.in_normals = as_floats(inplace_n), job.out_normals = as_floats(inplace_n);
        REQUIRE(job.run());
        CHECK(inplace_p == whole_p);
        CHECK(inplace_n == whole_n);
      }
}

TEST_CASE("validate() rejects malformed jobs and says why; run() refuses the O(1) ones and writes nothing") {
  const std::vector<glm::mat4> palette(3, glm::mat4(1.0f));
  std::vector<DualQuat> dual_quats(3);
  const std::vector<glm::mat3> scales(3, glm::mat3(1.0f));
  std::vector<glm::u16vec4> bones(10, glm::u16vec4(0, 1, 2, 0));
  std::vector<glm::vec4> weights(10, glm::vec4(0.5f, 0.25f, 0.25f, 0.0f));
  const std::vector<glm::vec3> in(10, glm::vec3(1.0f));
  std::vector<glm::vec3> out(10, glm::vec3(-1.0f)), out_n(10, glm::vec3(-1.0f));
  SkinningJob good;
  good.matrices = palette, good.dual_quats = dual_quats;
  good.bone_indices = bones, good.bone_weights = weights;
  good.in_positions = as_floats((in)), good.out_positions = as_floats(out);
  REQUIRE(good.validate());
  CHECK(good.count() == 10);
  SkinningJob dqs = good;
  dqs.method = SkinningMethod::dqs;
  REQUIRE(dqs.validate());
  dqs.scales = scales;
  REQUIRE(dqs.validate());

  const auto reason = [](Status status) { return std::string(status.reason()); };
  // O(1) failures: validate() and run() give the same reason, and run() writes nothing.
  auto rejected = [&](const SkinningJob& job, const char* why) {
    CHECK(reason(job.validate()) == why);
    CHECK(reason(job.run()) == why);
    CHECK(reason(job.run(0, 1)) == why);
    CHECK(out[0] == glm::vec3(-1.0f));
  };
  SkinningJob job = good;
  job.matrices = {};
  rejected(job, "palette is empty");
  job = dqs, job.dual_quats = {};
  rejected(job, "palette is empty");
  job = dqs, job.scales = std::span<const glm::mat3>(scales).first(2);
  rejected(job, "scales and dual quaternions differ in count");
  job = good, job.bone_weights = std::span<const glm::vec4>(weights).first(9);
  rejected(job, "bone weights and bone indices differ in count");
  job = good, job.in_positions = job.in_positions.first(29);
  rejected(job, "in_positions too short");
  job = good, job.out_positions = job.out_positions.first(27);
  rejected(job, "out_positions too short");
  job = good, job.in_positions_stride = 14;
  rejected(job, "in_positions stride invalid");  // not a multiple of 4
  job = good, job.out_positions_stride = 8;
  rejected(job, "out_positions stride invalid");  // below 12
  job = good, job.in_positions_stride = max_skinning_stride + 4;
  rejected(job, "in_positions stride invalid");  // too large
  job = good, job.in_normals = job.in_positions;
  rejected(job, "in_normals and out_normals: both or neither");
  job = good, job.in_normals = job.in_positions, job.out_normals = as_floats(out_n), job.out_normals_stride = 13;
  rejected(job, "out_normals stride invalid");
  job = good, job.in_normals = job.in_positions.first(12), job.out_normals = as_floats(out_n);
  rejected(job, "in_normals too short");
  job = good, job.method = static_cast<SkinningMethod>(7);
  rejected(job, "unknown skinning method");
  const std::vector<glm::mat4> huge(65537, glm::mat4(1.0f));
  job = good, job.matrices = huge;
  rejected(job, "palette has more than 65536 bones");
  // A forced path this CPU lacks is refused, never run.
  for (Isa isa : {Isa::avx2, Isa::avx512, Isa::neon, Isa::simd128})
    if (!isa_available(isa)) {
      job = good, job.isa = isa;
      rejected(job, "instruction set not available");
    }

  // Per-vertex and per-bone data: validate() only (run() trusts it).
  bones[4][2] = 3;
  CHECK(reason(good.validate()) == "bone index out of range");
  CHECK(reason(dqs.validate()) == "bone index out of range");
  bones[4][2] = 2;
  REQUIRE(good.validate());
  const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
  const std::pair<glm::vec4, const char*> bad_weights[] = {
      {glm::vec4(0.5f, 0.5f, 0.0f, -0.1f), "weight is negative"},
      {glm::vec4(0.5f, 0.5f, 0.0f, nan), "weight is not finite"},
      {glm::vec4(inf, 0.0f, 0.0f, 0.0f), "weight is not finite"},
      {glm::vec4(0.0f), "weight sum out of range"},
      // A denormal weight alone gave NaN positions: its sum's reciprocal overflows.
      {glm::vec4(1e-45f, 0.0f, 0.0f, 0.0f), "weight is denormal"},
      {glm::vec4(1.0f, 1e-40f, 0.0f, 0.0f), "weight is denormal"},
      {glm::vec4(1e-6f, 0.0f, 0.0f, 0.0f), "weight sum out of range"},
      {glm::vec4(3e38f, 3e38f, 0.0f, 0.0f), "weight sum out of range"},
      {glm::vec4(70000.0f, 0.0f, 0.0f, 0.0f), "weight sum out of range"}};
  for (const auto& bad : bad_weights) {
    const std::string why = bad.second;
    CAPTURE(why);
    weights[9] = bad.first;
    CHECK(reason(good.validate()) == why);
    CHECK(reason(dqs.validate()) == why);
  }
  // The ends of the accepted sums, and a tiny but normal weight beside a large one.
  for (const glm::vec4 w :
       {glm::vec4(min_skin_weight_sum, 0.0f, 0.0f, 0.0f), glm::vec4(0.0f, max_skin_weight_sum, 0.0f, 0.0f),
        glm::vec4(1.0f, 1e-30f, 0.0f, 0.0f), glm::vec4(255.0f, 0.0f, 0.0f, 0.0f)}) {
    weights[9] = w;
    CHECK(good.validate());
    CHECK(dqs.validate());
  }
  weights[9] = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
  REQUIRE(good.validate());
  // Each accepted extreme gives finite positions and unit normals on every path.
  for (const glm::vec4 w :
       {glm::vec4(min_skin_weight_sum, 0.0f, 0.0f, 0.0f), glm::vec4(max_skin_weight_sum, 0.0f, 0.0f, 0.0f),
        glm::vec4(0.0f, min_skin_weight_sum, 0.0f, 0.0f)}) {
    std::vector<glm::vec4> extreme(10, w);
    const std::vector<glm::vec3> normals_in(10, glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)));
    for (Isa isa : available_isas())
      for (const SkinningJob* base : {&good, &dqs}) {
        CAPTURE(isa_name(isa));
        std::vector<glm::vec3> p(10), n(10);
        job = *base, job.isa = isa, job.bone_weights = extreme;
        job.out_positions = as_floats(p), job.in_normals = as_floats(normals_in), job.out_normals = as_floats(n);
        REQUIRE(job.validate());
        REQUIRE(job.run());
        for (std::size_t i = 0; i < 10; ++i) {
          CHECK(glm::length(p[i] - in[i]) < 1e-4f);  // identity palette
          CHECK(std::abs(glm::length(n[i]) - 1.0f) < 1e-5f);
        }
      }
  }

  // Palettes: every entry finite.
  std::vector<glm::mat4> bad_palette = palette;
  bad_palette[1][3][2] = nan;
  job = good, job.matrices = bad_palette;
  CHECK(reason(job.validate()) == "palette matrix is not finite");
  bad_palette[1][3][2] = inf;
  CHECK(reason(job.validate()) == "palette matrix is not finite");
  std::vector<glm::vec3> scratch_out(10);
  job.out_positions = as_floats(scratch_out);
  CHECK(job.run());  // run() does not read the palette to check it
  std::vector<DualQuat> bad_dual_quats = dual_quats;
  bad_dual_quats[2].dual.y = nan;
  job = dqs, job.dual_quats = bad_dual_quats;
  CHECK(reason(job.validate()) == "dual quaternion is not finite");
  bad_dual_quats[2].dual.y = 0.0f, bad_dual_quats[0].real.w = inf;
  CHECK(reason(job.validate()) == "dual quaternion is not finite");
  std::vector<glm::mat3> bad_scales = scales;
  bad_scales[0][2][2] = nan;
  job = dqs, job.scales = bad_scales;
  CHECK(reason(job.validate()) == "scale matrix is not finite");

  // An empty mesh is valid and does nothing; run(begin, end) checks its range.
  job = good, job.bone_indices = {}, job.bone_weights = {}, job.in_positions = {}, job.out_positions = {};
  CHECK(job.validate());
  CHECK(job.run());
  CHECK(job.count() == 0);
  CHECK(reason(good.run(5, 11)) == "range outside the job");
  CHECK(reason(good.run(6, 5)) == "range outside the job");
  CHECK(good.run(2, 5));
  CHECK(out[1] == glm::vec3(-1.0f));
  CHECK(out[2] == glm::vec3(1.0f));
  CHECK(out[5] == glm::vec3(-1.0f));
}
