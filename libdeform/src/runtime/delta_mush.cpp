// DeltaMushJob: Laplacian smoothing passes over the point one-rings, then each point's rest delta added back in the
// frame of the smoothed deformed surface (Mancewicz et al. 2014). Compiled with -ffp-contract=off (CMakeLists.txt), so
// that the binder, which runs these same passes on the rest points, and the job round every sum alike.
#include "deform/runtime/delta_mush.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "deform/runtime/parallel.hpp"
#include "deform/runtime/portable.hpp"
#include "finite.hpp"

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace deform {
namespace {

// The O(1) checks of run(): the binding's per-point arrays sized for its point count, so that no per-point read or
// write leaves them (the indices inside the rings and fans are validate()'s).
Status shape_ok(const DeltaMushJob& job) noexcept {
  const DeltaMushBinding* b = job.binding;
  if (b == nullptr) return Status::failure("no binding");
  const std::size_t n = b->point_count();
  if (b->iterations > max_delta_mush_iterations) return Status::failure("iterations out of range");
  if (!(b->step > 0.0f && b->step <= 1.0f)) return Status::failure("step is not within (0, 1]");
  if (b->ring_offsets.size() != n + 1 || b->smoothing.size() != n || b->fan_offsets.size() != n + 1 ||
      b->tangent_neighbour.size() != n || b->pinned.size() != n)
    return Status::failure("binding is malformed: per-point arrays differ in size");
  if (b->ring_offsets.back() != b->rings.size() || b->fan_offsets.back() * std::size_t{2} != b->fans.size())
    return Status::failure("binding is malformed: offsets do not end at their arrays' sizes");
  if (job.in_positions.size() != n || job.out_positions.size() != n)
    return Status::failure("positions are not one per point");
  if (job.scratch.size() < DeltaMushJob::scratch_size(*b)) return Status::failure("scratch is too small");
  return {};
}

glm::vec3 xyz(const glm::vec4& p) noexcept { return glm::vec3(p); }

// One smoothing step over points [begin, end): out[i] = keep · in[i] + pull · Σ in[ring]. The padded source (vec4)
// sums all four components, which GCC and Clang turn into one vector add per neighbour (the w of the scratch is 0).
void smooth(const DeltaMushBinding& b, const glm::vec3* in, glm::vec4* out, std::size_t begin,
            std::size_t end) noexcept {
  const std::uint32_t* offsets = b.ring_offsets.data();
  const std::uint32_t* rings = b.rings.data();
  const glm::vec2* smoothing = b.smoothing.data();
  for (std::size_t i = begin; i < end; ++i) {
    float x = 0.0f, y = 0.0f, z = 0.0f;
    for (std::uint32_t r = offsets[i], last = offsets[i + 1]; r < last; ++r) {
      const glm::vec3 p = in[rings[r]];
      x += p.x, y += p.y, z += p.z;
    }
    const glm::vec2 k = smoothing[i];
    const glm::vec3 p = in[i];
    out[i] = glm::vec4(k.x * p.x + k.y * x, k.x * p.y + k.y * y, k.x * p.z + k.y * z, 0.0f);
  }
}
// Four floats added lane by lane: SSE2 (every x86-64) or NEON (every aarch64), else scalar — the same IEEE sums in
// the same order on every path, so every path gives the same bits (GCC does not vectorise the scalar form itself).
#if defined(__SSE2__) || defined(_M_X64)
struct Four {
  __m128 v;
  static Four zero() noexcept { return {_mm_setzero_ps()}; }
  static Four splat(float x) noexcept { return {_mm_set1_ps(x)}; }
  static Four load(const float* p) noexcept { return {_mm_loadu_ps(p)}; }
  void add(Four o) noexcept { v = _mm_add_ps(v, o.v); }
  Four times(Four o) const noexcept { return {_mm_mul_ps(v, o.v)}; }
  void store(float* p) const noexcept { _mm_storeu_ps(p, v); }
};
#elif defined(__ARM_NEON)
struct Four {
  float32x4_t v;
  static Four zero() noexcept { return {vdupq_n_f32(0.0f)}; }
  static Four splat(float x) noexcept { return {vdupq_n_f32(x)}; }
  static Four load(const float* p) noexcept { return {vld1q_f32(p)}; }
  void add(Four o) noexcept { v = vaddq_f32(v, o.v); }
  Four times(Four o) const noexcept { return {vmulq_f32(v, o.v)}; }
  void store(float* p) const noexcept { vst1q_f32(p, v); }
};
#else
struct Four {
  float v[4];
  static Four zero() noexcept { return {{0.0f, 0.0f, 0.0f, 0.0f}}; }
  static Four splat(float x) noexcept { return {{x, x, x, x}}; }
  static Four load(const float* p) noexcept { return {{p[0], p[1], p[2], p[3]}}; }
  void add(Four o) noexcept {
    for (int c = 0; c < 4; ++c) v[c] += o.v[c];
  }
  Four times(Four o) const noexcept { return {{v[0] * o.v[0], v[1] * o.v[1], v[2] * o.v[2], v[3] * o.v[3]}}; }
  void store(float* p) const noexcept {
    for (int c = 0; c < 4; ++c) p[c] = v[c];
  }
};
#endif

// The passes after the first: four floats a neighbour (the scratch's w is 0), summed in the same order as the first
// pass's loop and scaled as it scales, each product and sum rounded alone, so that the result is the same bits. The
// ring is walked four at a time (fewer loop instructions per neighbour: the loop was bound by them), then one at a
// time; padding the rings to whole groups instead cost more in the neighbours it added than the exits it saved.
void smooth(const DeltaMushBinding& b, const glm::vec4* in, glm::vec4* out, std::size_t begin,
            std::size_t end) noexcept {
  const std::uint32_t* offsets = b.ring_offsets.data();
  const std::uint32_t* rings = b.rings.data();
  const glm::vec2* smoothing = b.smoothing.data();
  for (std::size_t i = begin; i < end; ++i) {
    Four sum = Four::zero();
    std::uint32_t r = offsets[i];
    const std::uint32_t last = offsets[i + 1];
    for (; r + 4 <= last; r += 4) {
      DEFORM_UNROLL
      for (std::uint32_t u = 0; u < 4; ++u) sum.add(Four::load(&in[rings[r + u]].x));
    }
    for (; r < last; ++r) sum.add(Four::load(&in[rings[r]].x));
    const glm::vec2 k = smoothing[i];
    Four result = Four::splat(k.x).times(Four::load(&in[i].x));
    result.add(Four::splat(k.y).times(sum));
    result.store(&out[i].x);
  }
}

// The frame of point i over the smoothed points s (see delta_mush_frame). The thresholds only keep the division and
// normalisation meaningful (a normal at least 1e-6 of the squared tangent edge, a tangent at least 1e-6 of that
// edge); the binder holds the rest frames to a much stricter conditioning.
DEFORM_ALWAYS_INLINE inline bool frame_of(const DeltaMushBinding& b, const glm::vec4* s, std::uint32_t i,
                                          glm::vec3& tangent, glm::vec3& bitangent, glm::vec3& normal) noexcept {
  const std::uint32_t t = b.tangent_neighbour[i];
  if (t == DeltaMushBinding::no_frame) return false;
  const glm::vec3 c = xyz(s[i]);
  const std::uint32_t* fans = b.fans.data();
#if defined(__SSE2__) || defined(_M_X64)
  // The same products and sums as glm::cross lane by lane (x = a.y·b.z − a.z·b.y, ...), four lanes at once; w stays 0.
  const __m128 center = _mm_loadu_ps(&s[i].x);
  __m128 sum = _mm_setzero_ps();
  for (std::uint32_t f = b.fan_offsets[i], last = b.fan_offsets[i + 1]; f < last; ++f) {
    const __m128 a = _mm_sub_ps(_mm_loadu_ps(&s[fans[2 * f]].x), center);
    const __m128 d = _mm_sub_ps(_mm_loadu_ps(&s[fans[2 * f + 1]].x), center);
    const __m128 a_yzx = _mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 0, 2, 1));
    const __m128 a_zxy = _mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 1, 0, 2));
    const __m128 d_yzx = _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1));
    const __m128 d_zxy = _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 1, 0, 2));
    sum = _mm_add_ps(sum, _mm_sub_ps(_mm_mul_ps(a_yzx, d_zxy), _mm_mul_ps(a_zxy, d_yzx)));
  }
  float lanes[4];
  _mm_storeu_ps(lanes, sum);
  const glm::vec3 n(lanes[0], lanes[1], lanes[2]);
#else
  glm::vec3 n(0.0f);
  for (std::uint32_t f = b.fan_offsets[i]; f < b.fan_offsets[i + 1]; ++f)
    n += glm::cross(xyz(s[fans[2 * f]]) - c, xyz(s[fans[2 * f + 1]]) - c);
#endif
  const glm::vec3 e = xyz(s[t]) - c;
  const float ee = glm::dot(e, e), nn = glm::dot(n, n);
  if (!(nn > 1e-12f * ee * ee && nn <= std::numeric_limits<float>::max())) return false;
  normal = n * (1.0f / std::sqrt(nn));
  const glm::vec3 in_plane = e - normal * glm::dot(normal, e);
  const float tt = glm::dot(in_plane, in_plane);
  if (!(tt > 1e-12f * ee)) return false;
  tangent = in_plane * (1.0f / std::sqrt(tt));
  bitangent = glm::cross(normal, tangent);
  return true;
}

// The last pass over [begin, end): out = smoothed + frame · delta; pinned points, points without a frame and
// collapsed neighbourhoods keep the input.
void finish(const DeltaMushBinding& b, const glm::vec4* s, const glm::vec3* in, glm::vec3* out, std::size_t begin,
            std::size_t end) noexcept {
  for (std::size_t i = begin; i < end; ++i) {
    if (b.pinned[i]) {
      out[i] = in[i];
      continue;
    }
    const glm::vec3 d = b.deltas[i];
    glm::vec3 t, bt, n;
    if (frame_of(b, s, std::uint32_t(i), t, bt, n)) {
      out[i] = xyz(s[i]) + t * d.x + bt * d.y + n * d.z;
    } else {
      out[i] = in[i];
    }
  }
}

// Scratch halves: pass p writes buffer p % 2 and reads buffer (p - 1) % 2.
glm::vec4* buffer(const DeltaMushJob& job, std::size_t which) noexcept {
  return job.scratch.data() + which * job.binding->point_count();
}

}  // namespace

Status DeltaMushJob::validate() const noexcept {
  if (const Status status = shape_ok(*this); !status) return status;
  const DeltaMushBinding& b = *binding;
  const std::size_t n = b.point_count();
  if (n >= std::size_t{0xffffffffu}) return Status::failure("binding is malformed: too many points");
  const auto offsets_ok = [n](const std::vector<std::uint32_t>& offsets) {
    if (offsets[0] != 0) return false;
    for (std::size_t i = 0; i < n; ++i)
      if (offsets[i + 1] < offsets[i]) return false;
    return true;
  };
  if (!offsets_ok(b.ring_offsets) || !offsets_ok(b.fan_offsets))
    return Status::failure("binding is malformed: offsets do not ascend from 0");
  for (const std::uint32_t p : b.rings)
    if (p >= n) return Status::failure("binding is malformed: ring point out of range");
  for (const std::uint32_t p : b.fans)
    if (p >= n) return Status::failure("binding is malformed: fan point out of range");
  for (const std::uint32_t p : b.tangent_neighbour)
    if (p >= n && p != DeltaMushBinding::no_frame)
      return Status::failure("binding is malformed: tangent neighbour out of range");
  for (std::size_t i = 0; i < n; ++i)
    if (!finite(b.smoothing[i]) || !finite(b.deltas[i])) return Status::failure("binding is not finite");
  return {};
}

Status DeltaMushJob::run_pass(std::size_t pass, std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = shape_ok(*this); !status) return status;
  if (pass >= passes()) return Status::failure("pass out of range");
  if (begin > end || end > count()) return Status::failure("range outside the job");
  const DeltaMushBinding& b = *binding;
  const std::size_t k = b.iterations;
  if (k == 0) {
    // No smoothing: the rest deltas are 0 and the mush is the input itself.
    if (in_positions.data() != out_positions.data())
      std::copy(in_positions.begin() + std::ptrdiff_t(begin), in_positions.begin() + std::ptrdiff_t(end),
                out_positions.begin() + std::ptrdiff_t(begin));
    return {};
  }
  if (pass == 0) {
    smooth(b, in_positions.data(), buffer(*this, 0), begin, end);
  } else if (pass < k) {
    smooth(b, static_cast<const glm::vec4*>(buffer(*this, (pass - 1) % 2)), buffer(*this, pass % 2), begin, end);
  } else {
    finish(b, buffer(*this, (k - 1) % 2), in_positions.data(), out_positions.data(), begin, end);
  }
  return {};
}

Status DeltaMushJob::run() const noexcept {
  if (const Status status = shape_ok(*this); !status) return status;
  for (std::size_t pass = 0; pass < passes(); ++pass) (void)run_pass(pass, 0, count());
  return {};
}

Status DeltaMushJob::run(ThreadPool& pool, std::size_t min_chunk) const noexcept {
  if (const Status status = shape_ok(*this); !status) return status;
  struct Split {
    const DeltaMushJob* job;
    std::size_t pass;
  };
  const std::size_t units = (count() + split_multiple - 1) / split_multiple;
  const std::size_t min_units = std::max<std::size_t>(1, (min_chunk + split_multiple - 1) / split_multiple);
  for (std::size_t pass = 0; pass < passes(); ++pass) {
    const Split split{this, pass};
    const Split* context = &split;  // one pointer: the std::function stores it without allocating
    pool.parallel_for(units, min_units, [context](std::size_t begin, std::size_t end) {
      const std::size_t n = context->job->count();
      (void)context->job->run_pass(context->pass, std::min(begin * split_multiple, n),
                                   std::min(end * split_multiple, n));
    });
  }
  return {};
}

std::span<const glm::vec4> DeltaMushJob::smoothed() const noexcept {
  if (!shape_ok(*this) || binding->iterations == 0) return {};
  return {buffer(*this, (binding->iterations - 1) % 2), binding->point_count()};
}

bool delta_mush_frame(const DeltaMushBinding& binding, std::span<const glm::vec4> smoothed, std::uint32_t point,
                      glm::mat3& frame) noexcept {
  const std::size_t n = binding.point_count();
  if (point >= n || smoothed.size() != n || binding.tangent_neighbour.size() != n ||
      binding.fan_offsets.size() != n + 1)
    return false;
  glm::vec3 tangent, bitangent, normal;
  if (!frame_of(binding, smoothed.data(), point, tangent, bitangent, normal)) return false;
  frame = glm::mat3(tangent, bitangent, normal);
  return true;
}

}  // namespace deform
