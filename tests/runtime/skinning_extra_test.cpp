// Skinning with more than four influences per vertex: the general path (SkinningJob::extra_*) against a plain
// double-precision reference over any number of influences, on every instruction set, LBS and DQS (rigid and
// scaled), positions and normals, in place and not, whole and in ranges; SkinWeights' helpers; validate().
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
using namespace deform;

namespace {

// One vertex's influences, as listed (strongest first after append_influences; any order for the reference).
struct Influence {
  std::uint16_t bone;
  double weight;
};

// LBS over any number of influences: M = Σ wₖ Mₖ / Σ wₖ; p' = M p; n' = normalise(cofactor(A) n).
void reference_lbs(std::span<const glm::mat4> palette, const std::vector<Influence>& in, glm::vec3 p, glm::vec3 n,
                   glm::dvec3& out_p, glm::dvec3& out_n) {
  glm::dmat4 m(0.0);
  double sum = 0.0;
  for (const Influence& i : in) m += i.weight * glm::dmat4(palette[i.bone]), sum += i.weight;
  m /= sum;
  out_p = glm::dvec3(m * glm::dvec4(glm::dvec3(p), 1.0));
  const glm::dmat3 a(m);
  const glm::dvec3 mapped = glm::determinant(a) * (glm::transpose(glm::inverse(a)) * glm::dvec3(n));
  out_n = glm::length(mapped) > 0.0 ? glm::normalize(mapped) : mapped;
}

// DQS over any number of influences, the first influence's real part the antipodality pivot (Kavan et al. 2007);
// with scales, S = Σ wₖ Sₖ / Σ wₖ first.
void reference_dqs(std::span<const DualQuat> palette, std::span<const glm::mat3> scales,
                   const std::vector<Influence>& in, glm::vec3 p, glm::vec3 n, glm::dvec3& out_p, glm::dvec3& out_n) {
  const glm::dquat pivot(palette[in[0].bone].real);
  glm::dquat real(0.0, 0.0, 0.0, 0.0), dual(0.0, 0.0, 0.0, 0.0);
  glm::dmat3 s(0.0);
  double sum = 0.0;
  for (const Influence& i : in) {
    const glm::dquat r(palette[i.bone].real), d(palette[i.bone].dual);
    const double w = glm::dot(r, pivot) < 0.0 ? -i.weight : i.weight;
    real = real + w * r;
    dual = dual + w * d;
    if (!scales.empty()) s += i.weight * glm::dmat3(scales[i.bone]);
    sum += i.weight;
  }
  const double length = glm::length(real);
  real = real / length, dual = dual / length;
  const glm::dquat t = 2.0 * dual * glm::conjugate(real);
  glm::dvec3 ps(p), ns(n);
  if (!scales.empty()) {
    s /= sum;
    ps = s * ps;
    ns = glm::determinant(s) * (glm::transpose(glm::inverse(s)) * ns);
  }
  const glm::dmat3 rotation = glm::mat3_cast(real);
  out_p = rotation * ps + glm::dvec3(t.x, t.y, t.z);
  const glm::dvec3 mapped = rotation * ns;
  out_n = glm::length(mapped) > 0.0 ? glm::normalize(mapped) : mapped;
}

std::vector<glm::mat4> random_palette(std::mt19937& rng, int bones, bool scale) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), s(0.6f, 1.6f);
  std::vector<glm::mat4> palette;
  for (int i = 0; i < bones; ++i) {
    glm::vec3 axis{u(rng), u(rng), u(rng)};
    if (glm::length(axis) < 1e-3f) axis = glm::vec3(0, 0, 1);
    glm::mat4 m = glm::mat4_cast(glm::angleAxis(glm::radians(150.0f * u(rng)), glm::normalize(axis)));
    m[3] = glm::vec4{u(rng), u(rng), u(rng), 1.0f};
    if (scale) m = m * glm::scale(glm::mat4(1.0f), glm::vec3{s(rng), s(rng), s(rng)});
    palette.push_back(m);
  }
  return palette;
}

struct Case {
  std::vector<glm::vec3> positions, normals;
  std::vector<std::vector<Influence>> influences;  // as SkinWeights holds them (strongest first, normalised)
  SkinWeights weights;
};

// `count` vertices, each with 1 to `max_influences` influences over distinct bones (some vertices use the same bone
// twice in the input, which append_influences merges); every 5th vertex's weights are then scaled by a factor in
// [0.5, 2] (not normalised: the kernels divide by the sum).
Case random_case(std::mt19937& rng, std::size_t count, int bones, int max_influences, bool scale_sums = true) {
  std::uniform_real_distribution<float> u(-2.0f, 2.0f), unit(0.0f, 1.0f), factor(0.5f, 2.0f);
  std::uniform_int_distribution<int> bone(0, bones - 1), many(1, max_influences);
  Case c;
  for (std::size_t i = 0; i < count; ++i) {
    c.positions.push_back({u(rng), u(rng), u(rng)});
    glm::vec3 n{u(rng), u(rng), u(rng)};
    c.normals.push_back(glm::length(n) > 1e-3f ? glm::normalize(n) : glm::vec3(0, 1, 0));
    const int used = std::min(many(rng), bones);
    std::vector<std::uint16_t> b;
    std::vector<float> w;
    for (int k = 0; k < used; ++k) b.push_back(std::uint16_t(bone(rng))), w.push_back(0.05f + unit(rng));
    append_influences(c.weights, b, w);
    const float f = scale_sums && i % 5 == 2 ? factor(rng) : 1.0f;
    c.weights.weights.back() *= f;
    std::vector<Influence> list;
    for (int k = 0; k < 4; ++k)
      if (c.weights.weights.back()[k] > 0.0f) list.push_back({c.weights.bones.back()[k], c.weights.weights.back()[k]});
    if (!c.weights.extra_points.empty() && c.weights.extra_points.back() == i) {
      for (std::uint32_t e = c.weights.extra_offsets[c.weights.extra_offsets.size() - 2];
           e < c.weights.extra_offsets.back(); ++e) {
        c.weights.extra_weights[e] *= f;
        list.push_back({c.weights.extra_bones[e], c.weights.extra_weights[e]});
      }
    }
    c.influences.push_back(list);
  }
  return c;
}

std::vector<Isa> available_isas() {
  std::vector<Isa> isas;
  for (Isa isa : {Isa::portable, Isa::avx2, Isa::avx512, Isa::neon, Isa::simd128})
    if (isa_available(isa)) isas.push_back(isa);
  return isas;
}

void attach(SkinningJob& job, const SkinWeights& w) {
  job.bone_indices = w.bones;
  job.bone_weights = w.weights;
  job.extra_vertices = w.extra_points;
  job.extra_offsets = w.extra_offsets;
  job.extra_bones = w.extra_bones;
  job.extra_weights = w.extra_weights;
}

double error_3(glm::dvec3 reference, glm::vec3 got) {
  return glm::length(reference - glm::dvec3(got)) / std::max(1.0, glm::length(reference));
}

}  // namespace

TEST_CASE("append_influences sorts, merges, normalises and spills past four; drop_extra_influences folds back") {
  SkinWeights w;
  const std::uint16_t b0[] = {3, 1, 3, 7, 2, 9, 5};
  const float v0[] = {0.1f, 0.4f, 0.2f, 0.05f, 0.6f, 0.0f, 0.25f};
  CHECK(append_influences(w, b0, v0) == 5);  // bone 3 merged (0.3), bone 9's zero dropped
  const std::uint16_t b1[] = {4};
  const float v1[] = {0.0f};
  CHECK(append_influences(w, b1, v1, 6) == 1);  // nothing positive: the fallback bone
  REQUIRE(w.size() == 2);
  CHECK(w.bones[0] == glm::u16vec4(2, 1, 3, 5));
  const double total = 0.6 + 0.4 + 0.3 + 0.25 + 0.05;
  CHECK(w.weights[0].x == doctest::Approx(0.6 / total));
  CHECK(w.weights[0].z == doctest::Approx(0.3 / total));
  REQUIRE(w.extra_points == std::vector<std::uint32_t>{0});
  CHECK(w.extra_offsets == std::vector<std::uint32_t>{0, 1});
  CHECK(w.extra_bones == std::vector<std::uint16_t>{7});
  CHECK(w.extra_weights[0] == doctest::Approx(0.05 / total));
  CHECK(w.bones[1] == glm::u16vec4(6, 0, 0, 0));
  CHECK(w.weights[1] == glm::vec4(1, 0, 0, 0));
  CHECK(influence_count(w, 0) == 5);
  CHECK(influence_count(w, 1) == 1);
  float largest = 0.0f;
  CHECK(drop_extra_influences(w, &largest) == 1);
  CHECK(largest == doctest::Approx(0.05 / total));
  CHECK_FALSE(w.has_extra());
  CHECK(w.weights[0].x + w.weights[0].y + w.weights[0].z + w.weights[0].w == doctest::Approx(1.0));
  CHECK(w.weights[0].x == doctest::Approx(0.6 / (total - 0.05)));
}

TEST_CASE("up to 16 influences: the general path equals the double reference on every kernel, in place and not") {
  std::mt19937 rng(20261124);
  std::size_t cases = 0;
  for (Isa isa : available_isas())
    for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs})
      for (bool scaled : {false, true})
        for (bool in_place : {false, true})
          for (std::size_t count : {1u, 7u, 17u, 40u, 300u}) {
            CAPTURE(isa_name(isa));
            CAPTURE(int(method));
            CAPTURE(scaled);
            CAPTURE(in_place);
            CAPTURE(count);
            const int bones = 1 + int(rng() % 40);
            const std::vector<glm::mat4> matrices = random_palette(rng, bones, scaled);
            std::vector<DualQuat> dq(matrices.size());
            std::vector<glm::mat3> scales(matrices.size());
            bool has_scale = false;
            REQUIRE(compute_dual_quat_palette(matrices, dq, scales, has_scale));
            const Case c = random_case(rng, count, bones, 16);
            SkinningJob job;
            job.method = method;
            job.isa = isa;
            job.matrices = matrices;
            job.dual_quats = dq;
            if (has_scale) job.scales = scales;
            attach(job, c.weights);
            std::vector<glm::vec3> in_p = c.positions, in_n = c.normals;
            std::vector<glm::vec3> out_p(count, glm::vec3(-7.0f)), out_n(count, glm::vec3(-7.0f));
            job.in_positions = as_floats(in_p);
            job.in_normals = as_floats(in_n);
            job.out_positions = in_place ? as_floats(in_p) : as_floats(out_p);
            job.out_normals = in_place ? as_floats(in_n) : as_floats(out_n);
            REQUIRE(job.validate());
            REQUIRE(job.run());
            const std::vector<glm::vec3>& got_p = in_place ? in_p : out_p;
            const std::vector<glm::vec3>& got_n = in_place ? in_n : out_n;
            double worst = 0.0;
            for (std::size_t i = 0; i < count; ++i) {
              glm::dvec3 p, n;
              if (method == SkinningMethod::lbs)
                reference_lbs(matrices, c.influences[i], c.positions[i], c.normals[i], p, n);
              else reference_dqs(dq, job.scales, c.influences[i], c.positions[i], c.normals[i], p, n);
              worst = std::max({worst, error_3(p, got_p[i]), error_3(n, got_n[i])});
              ++cases;
            }
            CHECK(worst <= 1e-5);
          }
  CHECK(cases > 5000);
}

TEST_CASE("with extra influences a vertex's result does not depend on the range it is run in, nor on in place") {
  std::mt19937 rng(77);
  for (Isa isa : available_isas())
    for (SkinningMethod method : {SkinningMethod::lbs, SkinningMethod::dqs}) {
      const std::size_t count = 517;
      const std::vector<glm::mat4> matrices = random_palette(rng, 24, false);
      std::vector<DualQuat> dq(matrices.size());
      std::vector<glm::mat3> scales(matrices.size());
      bool has_scale = false;
      REQUIRE(compute_dual_quat_palette(matrices, dq, scales, has_scale));
      const Case c = random_case(rng, count, 24, 9);
      SkinningJob job;
      job.method = method;
      job.isa = isa;
      job.matrices = matrices;
      job.dual_quats = dq;
      attach(job, c.weights);
      job.in_positions = as_floats(c.positions);
      job.in_normals = as_floats(c.normals);
      std::vector<glm::vec3> whole_p(count), whole_n(count), parts_p(count, glm::vec3(9.0f)), parts_n(count);
      job.out_positions = as_floats(whole_p);
      job.out_normals = as_floats(whole_n);
      REQUIRE(job.validate());
      REQUIRE(job.run());
      job.out_positions = as_floats(parts_p);
      job.out_normals = as_floats(parts_n);
      std::size_t at = 0;
      while (at < count) {
        const std::size_t next = std::min(count, at + 1 + rng() % 40);
        REQUIRE(job.run(at, next));
        at = next;
      }
      CHECK(parts_p == whole_p);
      CHECK(parts_n == whole_n);
      // In place, ranges split at the listed vertices: the same bits again.
      std::vector<glm::vec3> place_p = c.positions, place_n = c.normals;
      job.in_positions = as_floats(place_p);
      job.in_normals = as_floats(place_n);
      job.out_positions = as_floats(place_p);
      job.out_normals = as_floats(place_n);
      for (at = 0; at < count;) {
        const std::size_t next = std::min(count, at + 1 + rng() % 40);
        REQUIRE(job.run(at, next));
        at = next;
      }
      CHECK(place_p == whole_p);
      CHECK(place_n == whole_n);
    }
}

TEST_CASE("validate() checks the extra influences and says why") {
  std::mt19937 rng(5);
  const std::vector<glm::mat4> matrices = random_palette(rng, 10, false);
  Case c = random_case(rng, 50, 10, 8, false);
  REQUIRE(c.weights.has_extra());
  std::vector<glm::vec3> out(50);
  auto job_for = [&](const SkinWeights& w) {
    SkinningJob job;
    job.matrices = matrices;
    attach(job, w);
    job.in_positions = as_floats(c.positions);
    job.out_positions = as_floats(out);
    return job;
  };
  CHECK(job_for(c.weights).validate());
  auto reason = [&](SkinWeights w) { return std::string(job_for(w).validate().reason()); };
  {
    SkinWeights w = c.weights;
    w.extra_bones[0] = 10;
    CHECK(reason(w) == "bone index out of range");
  }
  {
    SkinWeights w = c.weights;
    w.extra_weights[0] = -0.1f;
    CHECK(reason(w) == "weight is negative");
  }
  {
    SkinWeights w = c.weights;
    w.extra_weights[0] = std::nanf("");
    CHECK(reason(w) == "weight is not finite");
  }
  {
    SkinWeights w = c.weights;
    w.extra_weights[0] = 1e-40f;
    CHECK(reason(w) == "weight is denormal");
  }
  {
    SkinWeights w = c.weights;
    w.extra_weights[0] = 1e6f;
    CHECK(reason(w) == "weight sum out of range");
  }
  {
    SkinWeights w = c.weights;
    w.extra_offsets.pop_back();
    CHECK(reason(w) == "extra influences are inconsistent");
    CHECK_FALSE(job_for(w).run());  // an O(1) inconsistency: run() refuses too
  }
  if (c.weights.extra_points.size() >= 2) {
    SkinWeights w = c.weights;
    std::swap(w.extra_points[0], w.extra_points[1]);
    CHECK(reason(w) == "extra influences are inconsistent");
  }
  {
    SkinWeights w = c.weights;
    w.extra_points.back() = 50;
    CHECK(reason(w) == "extra influences are inconsistent");
  }
  {
    SkinWeights w = c.weights;
    w.extra_points.clear();
    CHECK(reason(w) == "extra influences are inconsistent");  // bones without vertices
  }
}
