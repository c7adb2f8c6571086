// DirectDeltaMushJob: per point, the bones' matrices applied to the point's smoothed moments, the rotation nearest the
// cross-covariance that gives, and the point carried by it (Le and Lewis 2019). Sums are taken relative to where the
// point's strongest bone carries its rest point, so that no float sum cancels the model's distance from the origin.
// run() hands its range to the lane kernel (simd/ddm_kernel.inl), in the copy its Isa picks (the widest by default);
// nearest_rotation below is the same step for one point, for callers and the tests. The reduced job
// (DirectDeltaMushReducedJob) runs a second kernel in the same files over lanes packed by the same packer.
#include "deform/runtime/direct_delta_mush.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "deform/runtime/parallel.hpp"
#include "deform/runtime/isa.hpp"
#include "finite.hpp"
#include "simd/ddm_kernel.hpp"

namespace deform {
namespace {

constexpr std::size_t width = DirectDeltaMushLanes::width;
constexpr std::size_t moment_floats = sizeof(DirectDeltaMushMoments) / sizeof(float);
static_assert(sizeof(DirectDeltaMushMoments) == 10 * sizeof(float));
constexpr std::size_t reduced_moment_floats = sizeof(glm::vec4) / sizeof(float);  // p̃ (x, y, z) and ψ
static_assert(sizeof(glm::vec4) == 4 * sizeof(float));

// A binding's rows as the lanes see them, for either form: the lanes copy each influence's moments, the full form's
// 10 floats or the reduced form's 4.
struct Rows {
  std::size_t n;                 // points
  const std::uint32_t* offsets;  // n + 1, ascending from 0
  const std::uint16_t* bones;    // offsets[n]
  std::uint32_t bone_count;      // the binding's
  const float* moments;          // `floats` per influence, or null when floats is 0
  std::size_t floats;            // the moment floats each slot of the lanes copies
};

Rows rows_of(const DirectDeltaMushBinding& b) noexcept {
  return {
      b.point_count(), b.offsets.data(), b.bones.data(), b.bone_count, reinterpret_cast<const float*>(b.moments.data()),
      moment_floats};
}

Rows rows_of(const DirectDeltaMushReducedBinding& b) noexcept {
  return {b.point_count(),
          b.offsets.data(),
          b.bones.data(),
          b.bone_count,
          reinterpret_cast<const float*>(b.moments.data()),
          reduced_moment_floats};
}

// The lanes' arrays sized for the rows' point count (O(1)): what the kernel relies on to read within them.
bool lanes_shape_ok(const DirectDeltaMushLanes& l, std::size_t n, std::size_t floats) noexcept {
  const std::size_t blocks = (n + width - 1) / width;
  if (l.point_count != n || l.rounds.size() != blocks + 1 || l.shared.size() != blocks ||
      l.start.size() != blocks * width)
    return false;
  const std::size_t slots = std::size_t(l.rounds.back()) * width;
  return l.rounds[0] == 0 && l.influence.size() == slots && l.bones.size() == slots &&
         l.moments.size() == slots * floats;
}

// The lanes hold exactly the rows (O(influences)): each lane's slots name each of its point's influences once, with
// its bone and its moments' bits, the empty slots zero moments, the shared rounds one bone; the rounds ascend. The
// rows are checked (offsets ascending, bones in range) before.
bool lanes_match_rows(const DirectDeltaMushLanes& l, const Rows& b) noexcept {
  const std::size_t n = b.n, floats = b.floats;
  for (std::size_t k = 0; k + 1 < l.rounds.size(); ++k) {
    const std::uint32_t r0 = l.rounds[k], r1 = l.rounds[k + 1];
    if (r1 < r0 || l.shared[k] > r1 - r0) return false;
    for (std::size_t lane = 0; lane < width; ++lane) {
      const std::size_t i = k * width + lane;
      const std::uint32_t first = i < n ? b.offsets[i] : 0, last = i < n ? b.offsets[i + 1] : 0;
      // Its strongest bone (the row's first) from a shared round that has it, or none.
      const std::uint32_t start = l.start[k * width + lane];
      if (start != DirectDeltaMushLanes::none &&
          (start >= l.shared[k] || first == last || l.bones[std::size_t(r0 + start) * width] != b.bones[first]))
        return false;
      std::size_t found = 0;
      std::uint64_t sum = 0;  // of the influences named: with the count, a slot naming one twice shows
      for (std::uint32_t r = r0; r < r1; ++r) {
        const std::size_t slot = std::size_t(r) * width + lane;
        const float* m = l.moments.data() + std::size_t(r) * width * floats + lane;
        const std::uint32_t e = l.influence[slot];
        if (r - r0 < l.shared[k] && l.bones[slot] != l.bones[std::size_t(r) * width]) return false;
        if (e == DirectDeltaMushLanes::none) {
          if (l.bones[slot] >= b.bone_count) return false;
          for (std::size_t c = 0; c < floats; ++c)
            if (m[c * width] != 0.0f) return false;
          continue;
        }
        if (e < first || e >= last || l.bones[slot] != b.bones[e]) return false;
        const float* row = b.moments + std::size_t(e) * floats;
        for (std::size_t c = 0; c < floats; ++c)
          if (std::memcmp(&m[c * width], &row[c], sizeof(float)) != 0) return false;
        ++found, sum += e;
      }
      const std::uint64_t count = last - first;
      if (found != count || sum != (std::uint64_t(first) + last - 1) * count / 2) return false;
    }
  }
  return true;
}

// The O(1) checks of both jobs' run(): the binding's arrays sized consistently, its lanes packed from its rows
// (`moment_floats_per_slot` a slot: the full form's 10, the reduced form's 4), the palette (and the reduced form's
// quaternions) covering its bones and the spans one per point.
template <class Job>
Status shape_ok(const Job& job, std::size_t moment_floats_per_slot) noexcept {
  const auto* b = job.binding;
  if (b == nullptr) return Status::failure("no binding");
  const std::size_t n = b->point_count();
  if (b->offsets.size() != n + 1 || b->moments.size() != b->bones.size())
    return Status::failure("binding is malformed: arrays differ in size");
  if (b->offsets.back() != b->bones.size())
    return Status::failure("binding is malformed: offsets do not end at the end");
  if (!lanes_shape_ok(b->lanes, n, moment_floats_per_slot))
    return Status::failure("binding is malformed: lanes not packed from its rows");
  if (job.matrices.size() < b->bone_count) return Status::failure("palette is too small");
  if constexpr (requires { job.dual_quats; })
    if (job.dual_quats.size() < b->bone_count) return Status::failure("palette is too small");
  if (job.out_positions.size() != n || (!job.in_positions.empty() && job.in_positions.size() != n))
    return Status::failure("positions are not one per point");
  if (job.in_normals.size() != job.out_normals.size() || (!job.in_normals.empty() && job.in_normals.size() != n))
    return Status::failure("normals are not one per point");
  if (!job.out_rotations.empty() && job.out_rotations.size() != n)
    return Status::failure("rotations are not one per point");
  if (!isa_available(job.isa)) return Status::failure("instruction set not available");
  return {};
}

using KernelEntry = void (*)(const detail::DdmKernelArgs&) noexcept;

// The copy for `isa`, which isa_available() has accepted.
KernelEntry kernel_for(Isa isa) noexcept {
  if (isa == Isa::automatic) isa = isa_best();
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return detail::direct_delta_mush_avx512;
  if (isa == Isa::avx2) return detail::direct_delta_mush_avx2;
#endif
#if defined(DEFORM_NEON_KERNELS)
  if (isa == Isa::neon) return detail::direct_delta_mush_neon;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  if (isa == Isa::simd128) return detail::direct_delta_mush_simd128;
#endif
  return detail::direct_delta_mush_portable;
}

}  // namespace

glm::quat nearest_rotation(const glm::mat3& c, glm::quat q) noexcept {
  // Newton's method on f(R) = trace(Rᵀ C) over rotations R · exp([ω]×): with S = Rᵀ C, f grows by g · ω − ½ ωᵀ H ω,
  // g = (S₂₁ − S₁₂, S₀₂ − S₂₀, S₁₀ − S₀₁) and H = trace(S) I − (S + Sᵀ) / 2, positive definite near the maximum
  // (its eigenvalues are sums of two of C's singular values there). Where H is not (far from the maximum), a gradient
  // step of size |g| / |trace S| instead. Quadratic near the answer: from a bone's rotation, 2 to 4 steps.
  for (int iteration = 0; iteration < 16; ++iteration) {
    const glm::mat3 s = glm::transpose(glm::mat3_cast(q)) * c;
    const glm::vec3 g(s[1][2] - s[2][1], s[2][0] - s[0][2], s[0][1] - s[1][0]);
    const float trace = s[0][0] + s[1][1] + s[2][2];
    // H = trace(S) I − (S + Sᵀ) / 2, symmetric: its six entries, and its cofactors (H⁻¹ = cofactors / det).
    const float h00 = trace - s[0][0], h11 = trace - s[1][1], h22 = trace - s[2][2];
    const float h01 = -0.5f * (s[0][1] + s[1][0]), h02 = -0.5f * (s[0][2] + s[2][0]), h12 = -0.5f * (s[1][2] + s[2][1]);
    const float k00 = h11 * h22 - h12 * h12, k01 = h02 * h12 - h01 * h22, k02 = h01 * h12 - h02 * h11;
    const float k11 = h00 * h22 - h02 * h02, k12 = h01 * h02 - h00 * h12, k22 = h00 * h11 - h01 * h01;
    const float det = h00 * k00 + h01 * k01 + h02 * k02;
    glm::vec3 omega;
    // H positive definite (its leading minors positive): the Newton step; else a gradient step.
    if (h00 > 0.0f && k22 > 0.0f && det > 0.0f) {
      omega = glm::vec3(k00 * g.x + k01 * g.y + k02 * g.z, k01 * g.x + k11 * g.y + k12 * g.z,
                        k02 * g.x + k12 * g.y + k22 * g.z) /
              det;
    } else {
      const float scale = std::abs(trace);
      if (!(scale > 0.0f)) break;
      omega = g / scale;
    }
    const float angle2 = glm::dot(omega, omega);
    if (!(angle2 > 0.0f) || !std::isfinite(angle2)) break;
    // At most a radian a step; turned by the quaternion (1, ω/2) normalised (a turn of 2 atan(|ω|/2), |ω| to third
    // order: no trigonometry, and Newton's convergence kept).
    if (angle2 > 1.0f) omega /= std::sqrt(angle2);
    q = glm::normalize(q * glm::quat(1.0f, 0.5f * omega.x, 0.5f * omega.y, 0.5f * omega.z));
    // Quadratic convergence: after a step of 1e-4 the turn left is about 1e-8, below float rounding of the sums.
    if (angle2 < 1e-8f) break;
  }
  return q;
}

Status DirectDeltaMushJob::validate() const noexcept {
  if (const Status status = shape_ok(*this, moment_floats); !status) return status;
  const DirectDeltaMushBinding& b = *binding;
  if (b.offsets[0] != 0) return Status::failure("binding is malformed: offsets do not ascend from 0");
  for (std::size_t i = 0; i < b.point_count(); ++i) {
    if (b.offsets[i + 1] < b.offsets[i]) return Status::failure("binding is malformed: offsets do not ascend from 0");
    if (!finite(b.rest[i])) return Status::failure("binding is not finite");
    float weight = 0.0f;
    for (std::uint32_t e = b.offsets[i]; e < b.offsets[i + 1]; ++e) weight += b.moments[e].w;
    if (b.offsets[i + 1] > b.offsets[i] && !(weight > 0.0f))
      return Status::failure("binding is malformed: a point's smoothed weights do not sum above 0");
  }
  for (std::size_t e = 0; e < b.influence_count(); ++e) {
    if (b.bones[e] >= b.bone_count) return Status::failure("binding is malformed: bone out of range");
    const DirectDeltaMushMoments& m = b.moments[e];
    for (const float v : {m.xx, m.xy, m.xz, m.yy, m.yz, m.zz, m.x, m.y, m.z, m.w})
      if (!std::isfinite(v)) return Status::failure("binding is not finite");
  }
  for (std::size_t j = 0; j < b.bone_count; ++j)
    if (!finite(matrices[j])) return Status::failure("palette matrix is not finite");
  if (!lanes_match_rows(b.lanes, rows_of(b)))
    return Status::failure("binding is malformed: lanes not packed from its rows");
  return {};
}

namespace {

// The rows' lanes (DirectDeltaMushLanes), which pack_direct_delta_mush's checks have found consistent.
DirectDeltaMushLanes pack_rows(const Rows& b) {
  const std::size_t n = b.n, floats = b.floats;
  // The cost of a round with a bone per lane, in shared rounds: it copies 16 matrices into the lanes (16 × 12 scalar
  // loads and stores) besides the same products; an estimate from the instruction counts, not tuned: on the
  // benchmark's models nearly every round is shared whatever it is (docs/performance.md, 2026-11-28 04:45 UTC).
  constexpr std::size_t gathered_cost = 4;
  const std::size_t blocks = (n + width - 1) / width;
  DirectDeltaMushLanes l;
  l.point_count = n;
  l.rounds.assign(1, 0);
  l.shared.reserve(blocks);
  l.start.reserve(blocks * width);
  std::vector<std::pair<std::uint32_t, std::uint16_t>> coverage;  // (lanes with the bone, bone)
  std::vector<std::uint32_t> rows[width];                         // per lane: its influences left for gathered rounds
  std::vector<std::uint32_t> shared_slots;                        // per shared round and lane: influence or none
  for (std::size_t k = 0; k < blocks; ++k) {
    coverage.clear();
    for (std::size_t lane = 0; lane < width; ++lane) {
      rows[lane].clear();
      const std::size_t i = k * width + lane;
      if (i >= n) continue;
      for (std::uint32_t e = b.offsets[i]; e < b.offsets[i + 1]; ++e) {
        rows[lane].push_back(e);
        // Count a bone once per lane.
        bool seen = false;
        for (std::uint32_t f = b.offsets[i]; f < e; ++f) seen |= b.bones[f] == b.bones[e];
        if (seen) continue;
        auto it = std::find_if(coverage.begin(), coverage.end(), [&](const auto& c) { return c.second == b.bones[e]; });
        if (it == coverage.end()) coverage.emplace_back(1, b.bones[e]);
        else ++it->first;
      }
    }
    // The bones covering most lanes first (then the lower bone, for a layout that does not depend on anything else).
    std::sort(coverage.begin(), coverage.end(), [](const auto& x, const auto& y) {
      return x.first != y.first ? x.first > y.first : x.second < y.second;
    });
    // Sharing the first s bones leaves each lane its other influences for the gathered rounds: pick s of least cost.
    std::size_t left[width];
    std::size_t most = 0;
    for (std::size_t lane = 0; lane < width; ++lane) left[lane] = rows[lane].size(), most = std::max(most, left[lane]);
    std::size_t best = 0, best_cost = most * gathered_cost;
    for (std::size_t s = 1; s <= coverage.size(); ++s) {
      most = 0;
      for (std::size_t lane = 0; lane < width; ++lane) {
        for (const std::uint32_t e : rows[lane])
          if (b.bones[e] == coverage[s - 1].second) {
            --left[lane];
            break;
          }
        most = std::max(most, left[lane]);
      }
      if (s + most * gathered_cost < best_cost) best = s, best_cost = s + most * gathered_cost;
    }
    // The shared rounds take each lane's first influence of their bone out of its row.
    shared_slots.assign(best * width, DirectDeltaMushLanes::none);
    for (std::size_t s = 0; s < best; ++s)
      for (std::size_t lane = 0; lane < width; ++lane) {
        std::vector<std::uint32_t>& row = rows[lane];
        auto it =
            std::find_if(row.begin(), row.end(), [&](std::uint32_t e) { return b.bones[e] == coverage[s].second; });
        if (it == row.end()) continue;
        shared_slots[s * width + lane] = *it;
        row.erase(it);
      }
    std::size_t gathered = 0;
    for (std::size_t lane = 0; lane < width; ++lane) gathered = std::max(gathered, rows[lane].size());
    const auto slot = [&](std::uint32_t e, std::uint16_t bone) {
      l.influence.push_back(e);
      l.bones.push_back(bone);
    };
    const std::size_t start = l.moments.size();
    l.moments.resize(start + (best + gathered) * width * floats, 0.0f);
    for (std::size_t r = 0; r < best + gathered; ++r)
      for (std::size_t lane = 0; lane < width; ++lane) {
        const std::uint32_t e = r < best                       ? shared_slots[r * width + lane]
                                : r - best < rows[lane].size() ? rows[lane][r - best]
                                                               : DirectDeltaMushLanes::none;
        slot(e, r < best ? coverage[r].second : e != DirectDeltaMushLanes::none ? b.bones[e] : 0);
        if (e == DirectDeltaMushLanes::none) continue;
        const float* row = b.moments + std::size_t(e) * floats;
        for (std::size_t c = 0; c < floats; ++c) l.moments[start + (r * floats + c) * width + lane] = row[c];
      }
    l.shared.push_back(std::uint32_t(best));
    for (std::size_t lane = 0; lane < width; ++lane) {
      const std::size_t i = k * width + lane;
      std::uint32_t strongest = DirectDeltaMushLanes::none;
      for (std::size_t r = 0; r < best && i < n && b.offsets[i] < b.offsets[i + 1]; ++r)
        if (coverage[r].second == b.bones[b.offsets[i]]) strongest = std::uint32_t(r);
      l.start.push_back(strongest);
    }
    l.rounds.push_back(l.rounds.back() + std::uint32_t(best + gathered));
  }
  return l;
}

}  // namespace

Status pack_direct_delta_mush(DirectDeltaMushBinding& b) {
  b.lanes = {};
  const std::size_t n = b.point_count();
  if (b.offsets.size() != n + 1 || b.moments.size() != b.bones.size() || b.offsets[0] != 0 ||
      b.offsets.back() != b.bones.size())
    return Status::failure("binding is malformed: arrays differ in size");
  for (std::size_t i = 0; i < n; ++i)
    if (b.offsets[i + 1] < b.offsets[i]) return Status::failure("binding is malformed: offsets do not ascend from 0");
  b.lanes = pack_rows(rows_of(b));
  return {};
}

Status pack_direct_delta_mush(DirectDeltaMushReducedBinding& b) {
  b.lanes = {};
  const std::size_t n = b.point_count();
  if (b.offsets.size() != n + 1 || b.moments.size() != b.bones.size() || b.offsets[0] != 0 ||
      b.offsets.back() != b.bones.size())
    return Status::failure("binding is malformed: arrays differ in size");
  for (std::size_t i = 0; i < n; ++i)
    if (b.offsets[i + 1] < b.offsets[i]) return Status::failure("binding is malformed: offsets do not ascend from 0");
  b.lanes = pack_rows(rows_of(b));
  return {};
}

Status DirectDeltaMushJob::run() const noexcept { return run(0, count()); }

Status DirectDeltaMushJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = shape_ok(*this, moment_floats); !status) return status;
  if (begin > end || end > count()) return Status::failure("range outside the job");
  if (begin == end) return {};
  kernel_for(isa)({binding, matrices.data(), in_positions.empty() ? nullptr : in_positions.data(),
                   in_normals.empty() ? nullptr : in_normals.data(), out_positions.data(),
                   out_normals.empty() ? nullptr : out_normals.data(),
                   out_rotations.empty() ? nullptr : out_rotations.data(), begin, end});
  return {};
}

Status DirectDeltaMushJob::run(ThreadPool& pool, std::size_t min_chunk) const noexcept {
  return run_parallel(*this, pool, min_chunk);
}

// --- the reduced form: ψ and first moments, the rotation blended from the bones' quaternions ---

namespace {

using ReducedKernelEntry = void (*)(const detail::DdmReducedKernelArgs&) noexcept;

// The reduced kernel's copy for `isa`, which isa_available() has accepted.
ReducedKernelEntry reduced_kernel_for(Isa isa) noexcept {
  if (isa == Isa::automatic) isa = isa_best();
#if defined(DEFORM_X86_KERNELS)
  if (isa == Isa::avx512) return detail::direct_delta_mush_reduced_avx512;
  if (isa == Isa::avx2) return detail::direct_delta_mush_reduced_avx2;
#endif
#if defined(DEFORM_NEON_KERNELS)
  if (isa == Isa::neon) return detail::direct_delta_mush_reduced_neon;
#endif
#if defined(DEFORM_SIMD128_KERNELS)
  if (isa == Isa::simd128) return detail::direct_delta_mush_reduced_simd128;
#endif
  return detail::direct_delta_mush_reduced_portable;
}

}  // namespace

Status reduce_direct_delta_mush(const DirectDeltaMushBinding& full, DirectDeltaMushReducedBinding& out) {
  out = {};
  const std::size_t n = full.point_count();
  if (full.offsets.size() != n + 1 || full.moments.size() != full.bones.size() || full.offsets[0] != 0 ||
      full.offsets.back() != full.bones.size())
    return Status::failure("binding is malformed: arrays differ in size");
  DirectDeltaMushReducedBinding r;
  r.rest = full.rest;
  r.offsets = full.offsets;
  r.bones = full.bones;
  r.bone_count = full.bone_count;
  r.moments.reserve(full.influence_count());
  for (std::size_t i = 0; i < n; ++i) {
    if (full.offsets[i + 1] < full.offsets[i])
      return Status::failure("binding is malformed: offsets do not ascend from 0");
    double sum = 0.0;
    for (std::uint32_t e = full.offsets[i]; e < full.offsets[i + 1]; ++e) sum += double(full.moments[e].w);
    if (full.offsets[i + 1] > full.offsets[i] && !(sum > 0.0))
      return Status::failure("binding is malformed: a point's smoothed weights do not sum above 0");
    for (std::uint32_t e = full.offsets[i]; e < full.offsets[i + 1]; ++e) {
      const DirectDeltaMushMoments& m = full.moments[e];
      const glm::vec4 v(float(double(m.x) / sum), float(double(m.y) / sum), float(double(m.z) / sum),
                        float(double(m.w) / sum));
      if (!finite(v)) return Status::failure("binding is not finite");
      r.moments.push_back(v);
    }
  }
  if (const Status status = pack_direct_delta_mush(r); !status) return status;
  out = std::move(r);
  return {};
}

Status DirectDeltaMushReducedJob::validate() const noexcept {
  if (const Status status = shape_ok(*this, reduced_moment_floats); !status) return status;
  const DirectDeltaMushReducedBinding& b = *binding;
  if (b.offsets[0] != 0) return Status::failure("binding is malformed: offsets do not ascend from 0");
  for (std::size_t i = 0; i < b.point_count(); ++i) {
    if (b.offsets[i + 1] < b.offsets[i]) return Status::failure("binding is malformed: offsets do not ascend from 0");
    if (!finite(b.rest[i])) return Status::failure("binding is not finite");
    float weight = 0.0f;
    for (std::uint32_t e = b.offsets[i]; e < b.offsets[i + 1]; ++e) {
      if (!finite(b.moments[e])) return Status::failure("binding is not finite");
      weight += b.moments[e].w;
    }
    // The first ψ positive keeps the blended quaternion away from zero (its part along q₀ is at least that ψ).
    if (b.offsets[i + 1] > b.offsets[i] && (!(weight > 0.0f) || !(b.moments[b.offsets[i]].w > 0.0f)))
      return Status::failure("binding is malformed: a point's smoothed weights do not sum above 0");
  }
  for (std::size_t e = 0; e < b.influence_count(); ++e)
    if (b.bones[e] >= b.bone_count) return Status::failure("binding is malformed: bone out of range");
  for (std::size_t j = 0; j < b.bone_count; ++j) {
    if (!finite(matrices[j])) return Status::failure("palette matrix is not finite");
    if (!finite(dual_quats[j].real)) return Status::failure("dual quaternion is not finite");
  }
  if (!lanes_match_rows(b.lanes, rows_of(b)))
    return Status::failure("binding is malformed: lanes not packed from its rows");
  return {};
}

Status DirectDeltaMushReducedJob::run() const noexcept { return run(0, count()); }

Status DirectDeltaMushReducedJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = shape_ok(*this, reduced_moment_floats); !status) return status;
  if (begin > end || end > count()) return Status::failure("range outside the job");
  if (begin == end) return {};
  reduced_kernel_for(isa)({binding, matrices.data(), dual_quats.data(),
                           in_positions.empty() ? nullptr : in_positions.data(),
                           in_normals.empty() ? nullptr : in_normals.data(), out_positions.data(),
                           out_normals.empty() ? nullptr : out_normals.data(),
                           out_rotations.empty() ? nullptr : out_rotations.data(), begin, end});
  return {};
}

Status DirectDeltaMushReducedJob::run(ThreadPool& pool, std::size_t min_chunk) const noexcept {
  return run_parallel(*this, pool, min_chunk);
}

}  // namespace deform
