// bind_direct_delta_mush: the per-bone moment fields of the rest points smoothed by p implicit Laplacian steps (one
// sparse Cholesky factorisation, Eigen's), pruned, moved to each point's own origin, spread (the regularisation) and
// stored as compressed rows of floats.
#include <Eigen/Sparse>
#include <algorithm>
#include <stdexcept>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "deform/offline/direct_delta_mush.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/error.hpp"

namespace deform {
namespace {

constexpr const char* element = "direct delta mush";
// Bones per batch of solves is chosen so that a batch's right-hand sides stay about this many doubles (32 MB, twice:
// the fields and the substitution's copy).
constexpr std::size_t batch_doubles = std::size_t{4} << 20;

using Sparse = Eigen::SparseMatrix<double>;
// Right-hand sides row-major: the substitutions below update every column of a row at once.
using Dense = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The smoothing x ← (I + λ D⁻¹(D − A))⁻¹ x, solved as (D + λ (D − A)) x' = D x: symmetric positive definite with D the
// degree (1 for a point without neighbours, which then keeps its value).
struct Smoother {
  Eigen::SimplicialLDLT<Sparse> solver;
  Eigen::VectorXd mass;
  int iterations = 0;

  Smoother(const PointTopology& topology, double step, int steps) : iterations(steps) {
    const std::size_t n = topology.neighbour_offsets.size() - 1;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(n + topology.neighbours.size());
    mass.resize(Eigen::Index(n));
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t degree = topology.neighbour_offsets[i + 1] - topology.neighbour_offsets[i];
      mass[Eigen::Index(i)] = degree == 0 ? 1.0 : double(degree);
      entries.emplace_back(int(i), int(i), mass[Eigen::Index(i)] + step * double(degree));
      for (std::uint32_t r = topology.neighbour_offsets[i]; r < topology.neighbour_offsets[i + 1]; ++r)
        entries.emplace_back(int(i), int(topology.neighbours[r]), -step);
    }
    Sparse k{Eigen::Index(n), Eigen::Index(n)};
    k.setFromTriplets(entries.begin(), entries.end());
    solver.compute(k);
    if (solver.info() != Eigen::Success)
      throw Error::invalid_argument(element, "the smoothing system could not be factorised");
  }
  // x ← B x, B = ((I + λ D⁻¹(D − A))⁻¹)ᵖ. Eigen's factors P K Pᵀ = L D' Lᵀ applied by substitution a row at a time to
  // all the columns together (Eigen's own solve goes column by column, reading the whole factor once per column:
  // with 10 columns per bone that was 90% of a bind).
  void smooth(Dense& x) const {
    const Sparse& l = solver.matrixL().nestedExpression();
    const Eigen::VectorXd& d = solver.vectorD();
    const Eigen::Index n = x.rows();
    const auto& order = solver.permutationP().indices();
    const auto to = [&](Eigen::Index i) { return order.size() > 0 ? Eigen::Index(order[i]) : i; };
    Dense y(n, x.cols());
    for (int s = 0; s < iterations; ++s) {
      for (Eigen::Index i = 0; i < n; ++i) y.row(to(i)) = mass[i] * x.row(i);
      for (Eigen::Index j = 0; j < n; ++j)  // L z = y
        for (Sparse::InnerIterator it(l, j); it; ++it)
          if (it.row() > j) y.row(it.row()) -= it.value() * y.row(j);
      for (Eigen::Index j = 0; j < n; ++j) y.row(j) /= d[j];
      for (Eigen::Index j = n - 1; j >= 0; --j)  // Lᵀ x' = z
        for (Sparse::InnerIterator it(l, j); it; ++it)
          if (it.row() > j) y.row(j) -= it.value() * y.row(it.row());
      for (Eigen::Index i = 0; i < n; ++i) x.row(i) = y.row(to(i));
    }
  }
};

// The ten moments of point y with weight w: y yᵀ (upper triangle, row by row), y, 1.
void moments(const glm::dvec3& y, double w, double* out) {
  out[0] = w * y.x * y.x, out[1] = w * y.x * y.y, out[2] = w * y.x * y.z;
  out[3] = w * y.y * y.y, out[4] = w * y.y * y.z, out[5] = w * y.z * y.z;
  out[6] = w * y.x, out[7] = w * y.y, out[8] = w * y.z, out[9] = w;
}

struct Entry {
  std::uint16_t bone;
  std::array<double, 10> m;
};

}  // namespace

DirectDeltaMushBinding bind_direct_delta_mush(const Mesh& mesh, const SkinWeights& weights,
                                              const DirectDeltaMushSettings& settings) {
  if (settings.iterations < 1 || settings.iterations > 100)
    throw Error::invalid_argument(element, "iterations must be within [1, 100]");
  if (!(settings.step > 0.0f && std::isfinite(settings.step)))
    throw Error::invalid_argument(element, "step must be positive and finite");
  if (!(settings.translation_blend >= 0.0f && settings.translation_blend < 1.0f))
    throw Error::invalid_argument(element, "translation_blend must be within [0, 1)");
  if (!(settings.translation_step > 0.0f && std::isfinite(settings.translation_step)))
    throw Error::invalid_argument(element, "translation_step must be positive and finite");
  if (!(settings.regularization >= 0.0f && settings.regularization <= 1.0f))
    throw Error::invalid_argument(element, "regularization must be within [0, 1]");
  if (!(settings.prune >= 0.0f && settings.prune < 0.5f))
    throw Error::invalid_argument(element, "prune must be within [0, 0.5)");
  const std::size_t n = mesh.point_count();
  if (n == 0 && weights.size() == 0) {
    DirectDeltaMushBinding empty;
    empty.offsets = {0};
    (void)pack_direct_delta_mush(empty);  // consistent: no points
    return empty;
  }
  if (n >= std::size_t{0x7fffffff}) throw Error::invalid_argument(element, "2^31 - 1 points or more");
  if (weights.size() != n)
    throw Error::invalid_argument(
        element, "weights have " + std::to_string(weights.size()) + " entries for " + std::to_string(n) + " points");
  const bool extras_ok = !weights.has_extra() || (weights.extra_offsets.size() == weights.extra_points.size() + 1 &&
                                                  weights.extra_offsets.back() == weights.extra_bones.size() &&
                                                  weights.extra_bones.size() == weights.extra_weights.size());
  if (!extras_ok || weights.weights.size() != n) throw Error::invalid_argument(element, "weights are malformed");

  const auto point_error = [](std::size_t i, const std::string& what) {
    return Error::invalid_argument(element, "point " + std::to_string(i) + ": " + what);
  };
  // Each point's influences, normalised to sum 1 (all zero stays zero).
  std::vector<std::vector<std::pair<std::uint16_t, double>>> influences(n);
  std::uint32_t bone_count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 p = mesh.positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw point_error(i, "rest position is not finite");
    const auto add = [&](std::uint16_t bone, float w) {
      if (!(std::isfinite(w) && w >= 0.0f)) throw point_error(i, "weight is not finite and >= 0");
      if (w == 0.0f) return;
      auto& list = influences[i];
      const auto same = std::find_if(list.begin(), list.end(), [&](const auto& e) { return e.first == bone; });
      if (same != list.end()) same->second += w;
      else list.emplace_back(bone, double(w));
      bone_count = std::max(bone_count, std::uint32_t(bone) + 1);
    };
    for (int s = 0; s < 4; ++s) add(weights.bones[i][s], weights.weights[i][s]);
    const auto extra = std::lower_bound(weights.extra_points.begin(), weights.extra_points.end(), std::uint32_t(i));
    if (extra != weights.extra_points.end() && *extra == i) {
      const std::size_t row = std::size_t(extra - weights.extra_points.begin());
      for (std::uint32_t e = weights.extra_offsets[row]; e < weights.extra_offsets[row + 1]; ++e)
        add(weights.extra_bones[e], weights.extra_weights[e]);
    }
    double sum = 0.0;
    for (const auto& e : influences[i]) sum += e.second;
    for (auto& e : influences[i]) e.second /= sum;
  }

  // Rest points relative to the bounding box's centre (moments of far-off models stay well scaled).
  const Bounds bounds = compute_bounds(mesh.positions);
  const glm::dvec3 origin = (glm::dvec3(bounds.min) + glm::dvec3(bounds.max)) * 0.5;
  const double size = glm::length(glm::dvec3(bounds.max) - glm::dvec3(bounds.min));
  std::vector<glm::dvec3> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = glm::dvec3(mesh.positions[i]) - origin;

  const PointTopology topology = build_point_topology(mesh);
  const Smoother rotation(topology, settings.step, settings.iterations);
  const double alpha = settings.translation_blend;

  // The totals: ψ (the smoothed weight sum), and for α > 0 the smoothed centroid and the κ-smoothed weight sum.
  Dense totals = Dense::Zero(Eigen::Index(n), 4);
  for (std::size_t i = 0; i < n; ++i) {
    const double w = influences[i].empty() ? 0.0 : 1.0;
    totals.row(Eigen::Index(i)) << w * y[i].x, w * y[i].y, w * y[i].z, w;
  }
  Dense translation_totals;
  std::unique_ptr<Smoother> translation;
  if (alpha > 0.0) {
    translation = std::make_unique<Smoother>(topology, settings.translation_step, settings.iterations);
    translation_totals = totals.col(3);
    translation->smooth(translation_totals);
  }
  rotation.smooth(totals);
  std::vector<double> total(n);
  std::vector<glm::dvec3> centroid(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double psi = totals(Eigen::Index(i), 3);
    total[i] = (1.0 - alpha) * psi + (alpha > 0.0 ? alpha * translation_totals(Eigen::Index(i), 0) : 0.0);
    if (!(psi > 1e-280 && total[i] > 1e-280))
      throw point_error(i, "no bone influences it or any point connected to it");
    centroid[i] = glm::dvec3(totals(Eigen::Index(i), 0), totals(Eigen::Index(i), 1), totals(Eigen::Index(i), 2)) / psi;
  }

  // The bones in use, in batches: each batch's moment fields smoothed together.
  std::vector<std::uint16_t> used;
  {
    std::vector<bool> seen(bone_count, false);
    for (const auto& list : influences)
      for (const auto& e : list) seen[e.first] = true;
    for (std::uint32_t j = 0; j < bone_count; ++j)
      if (seen[j]) used.push_back(std::uint16_t(j));
  }
  const std::size_t per_batch = std::max<std::size_t>(1, batch_doubles / (10 * std::max<std::size_t>(n, 1)));
  std::vector<std::vector<Entry>> kept(n);
  const double prune = settings.prune;
  for (std::size_t first = 0; first < used.size(); first += per_batch) {
    const std::size_t count = std::min(per_batch, used.size() - first);
    std::vector<int> column(bone_count, -1);
    for (std::size_t b = 0; b < count; ++b) column[used[first + b]] = int(b);
    Dense fields = Dense::Zero(Eigen::Index(n), Eigen::Index(10 * count));
    Dense smoothed_weights;
    if (alpha > 0.0) smoothed_weights = Dense::Zero(Eigen::Index(n), Eigen::Index(count));
    for (std::size_t k = 0; k < n; ++k)
      for (const auto& [bone, w] : influences[k]) {
        if (column[bone] < 0) continue;
        double m[10];
        moments(y[k], w, m);
        for (int c = 0; c < 10; ++c) fields(Eigen::Index(k), 10 * column[bone] + c) = m[c];
        if (alpha > 0.0) smoothed_weights(Eigen::Index(k), column[bone]) = w;
      }
    rotation.smooth(fields);
    if (alpha > 0.0) translation->smooth(smoothed_weights);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t b = 0; b < count; ++b) {
        Entry e{used[first + b], {}};
        for (int c = 0; c < 10; ++c) e.m[std::size_t(c)] = fields(Eigen::Index(i), Eigen::Index(10 * b) + c);
        if (alpha > 0.0) {
          // (1 − α) Ωᵢⱼ + α ψ'ᵢⱼ Ω̄ᵢ, Ω̄ᵢ the smoothed centroid's moments.
          double bar[10];
          moments(centroid[i], smoothed_weights(Eigen::Index(i), Eigen::Index(b)), bar);
          for (int c = 0; c < 10; ++c) e.m[std::size_t(c)] = (1.0 - alpha) * e.m[std::size_t(c)] + alpha * bar[c];
        }
        // Normalised so that the point's smoothed weights sum to about 1 (the job divides by the sum anyway).
        for (double& v : e.m) v /= total[i];
        if (!(e.m[9] > 0.0) || e.m[9] < prune) continue;
        // To point i's own origin: with y → y − yᵢ, P − p yᵢᵀ − yᵢ pᵀ + ψ yᵢ yᵢᵀ and p − ψ yᵢ.
        const glm::dvec3 o = y[i];
        const double psi = e.m[9];
        const glm::dvec3 p(e.m[6], e.m[7], e.m[8]);
        e.m[0] += -2.0 * p.x * o.x + psi * o.x * o.x;
        e.m[1] += -p.x * o.y - o.x * p.y + psi * o.x * o.y;
        e.m[2] += -p.x * o.z - o.x * p.z + psi * o.x * o.z;
        e.m[3] += -2.0 * p.y * o.y + psi * o.y * o.y;
        e.m[4] += -p.y * o.z - o.y * p.z + psi * o.y * o.z;
        e.m[5] += -2.0 * p.z * o.z + psi * o.z * o.z;
        e.m[6] -= psi * o.x, e.m[7] -= psi * o.y, e.m[8] -= psi * o.z;
        kept[i].push_back(e);
      }
  }

  DirectDeltaMushBinding binding;
  binding.bone_count = bone_count;
  binding.rest = mesh.positions;
  binding.offsets.assign(n + 1, 0);
  const double floor = 1e-8 * size * size;  // (1e-4 of the diagonal)²
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<Entry>& list = kept[i];
    // The strongest first (the job starts its rotation from that bone's); ties by bone.
    std::sort(list.begin(), list.end(),
              [](const Entry& a, const Entry& b) { return a.m[9] != b.m[9] ? a.m[9] > b.m[9] : a.bone < b.bone; });
    // The spread: σ² = regularization · (variance per axis of the rest neighbourhood) + floor, added as ψᵢⱼ σ² I.
    double s[10] = {};
    for (const Entry& e : list)
      for (int c = 0; c < 10; ++c) s[c] += e.m[std::size_t(c)];
    const double trace = s[9] > 0.0 ? s[0] + s[3] + s[5] - (s[6] * s[6] + s[7] * s[7] + s[8] * s[8]) / s[9] : 0.0;
    const double spread = settings.regularization * std::max(trace, 0.0) / (3.0 * std::max(s[9], 1e-300)) + floor;
    for (const Entry& e : list) {
      for (const double v : e.m)
        if (!(std::abs(v) + spread * e.m[9] < 1e38))
          throw point_error(i, "its moments overflow float (the model's scale is too large)");
      DirectDeltaMushMoments m;
      const double grow = spread * e.m[9];
      m.xx = float(e.m[0] + grow), m.xy = float(e.m[1]), m.xz = float(e.m[2]);
      m.yy = float(e.m[3] + grow), m.yz = float(e.m[4]), m.zz = float(e.m[5] + grow);
      m.x = float(e.m[6]), m.y = float(e.m[7]), m.z = float(e.m[8]), m.w = float(e.m[9]);
      binding.bones.push_back(e.bone);
      binding.moments.push_back(m);
    }
    binding.offsets[i + 1] = std::uint32_t(binding.bones.size());
    std::vector<Entry>().swap(list);
  }
  // The rows are consistent by construction; the kernel's layout of them.
  if (!pack_direct_delta_mush(binding)) throw std::logic_error("bind_direct_delta_mush: rows built inconsistent");
  return binding;
}

}  // namespace deform
