// MorphJob: rest + Σ w·Δ over sparse targets.
#include "deform/runtime/morph.hpp"
#include <algorithm>
#include <cmath>
#include "finite.hpp"

namespace deform {
namespace {

// Empty when the target is valid for `point_count` points, else what is wrong.
const char* target_problem(const MorphTarget& t, std::size_t point_count) noexcept {
  if (t.position_deltas.size() != t.points.size()) return "position deltas and points differ in count";
  if (!t.normal_deltas.empty() && t.normal_deltas.size() != t.points.size())
    return "normal deltas and points differ in count";
  for (std::size_t i = 0; i < t.points.size(); ++i) {
    if (t.points[i] >= point_count) return "point out of range";
    if (i > 0 && !(t.points[i] > t.points[i - 1])) return "points not strictly ascending";
    if (!finite(t.position_deltas[i])) return "position delta is not finite";
    if (!t.normal_deltas.empty() && !finite(t.normal_deltas[i])) return "normal delta is not finite";
  }
  return nullptr;
}

Status sizes_ok(const MorphJob& job) noexcept {
  if (job.weights.size() != job.targets.size()) return Status::failure("weights and targets differ in count");
  const std::size_t n = job.rest_positions.size();
  if (job.out_positions.size() != n) return Status::failure("out_positions and rest_positions differ in count");
  if (job.rest_normals.empty() != job.out_normals.empty())
    return Status::failure("rest_normals and out_normals: both or neither");
  if (!job.rest_normals.empty() && (job.rest_normals.size() != n || job.out_normals.size() != n))
    return Status::failure("normals and positions differ in count");
  return {};
}

}  // namespace

void require_valid_morph_targets(std::span<const MorphTarget> targets, std::size_t point_count,
                                 const std::string& source) {
  for (std::size_t k = 0; k < targets.size(); ++k)
    if (const char* problem = target_problem(targets[k], point_count))
      throw Error::in_file(source, "morph target " + std::to_string(k) + " '" + targets[k].name + "'", problem);
}

Status MorphJob::validate() const noexcept {
  if (Status s = sizes_ok(*this); !s) return s;
  for (const float w : weights)
    if (!std::isfinite(w)) return Status::failure("weight is not finite");
  for (const MorphTarget& t : targets)
    if (target_problem(t, rest_positions.size()) != nullptr) return Status::failure("target is malformed");
  return {};
}

Status MorphJob::run() const noexcept { return run(0, count()); }

Status MorphJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (Status s = sizes_ok(*this); !s) return s;
  if (begin > end || end > count()) return Status::failure("range outside the job");
  for (const float w : weights)
    if (!std::isfinite(w)) return Status::failure("weight is not finite");
  const bool normals = !rest_normals.empty();
  std::copy(rest_positions.begin() + std::ptrdiff_t(begin), rest_positions.begin() + std::ptrdiff_t(end),
            out_positions.begin() + std::ptrdiff_t(begin));
  if (normals)
    std::copy(rest_normals.begin() + std::ptrdiff_t(begin), rest_normals.begin() + std::ptrdiff_t(end),
              out_normals.begin() + std::ptrdiff_t(begin));
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const float w = weights[k];
    if (w == 0.0f) continue;
    const MorphTarget& t = targets[k];
    const auto first = std::lower_bound(t.points.begin(), t.points.end(), begin);
    const bool with_normals = normals && !t.normal_deltas.empty();
    for (auto i = static_cast<std::size_t>(first - t.points.begin()); i < t.points.size() && t.points[i] < end; ++i) {
      out_positions[t.points[i]] += w * t.position_deltas[i];
      if (with_normals) out_normals[t.points[i]] += w * t.normal_deltas[i];
    }
  }
  return {};
}

std::int32_t find_morph_target(std::span<const MorphTarget> targets, std::string_view name) noexcept {
  for (std::size_t k = 0; k < targets.size(); ++k)
    if (targets[k].name == name) return static_cast<std::int32_t>(k);
  return -1;
}

}  // namespace deform
