// Skinning decomposition (skinning_decomposition.hpp): Le & Deng's alternation of a rigid bone step and a
// non-negative weight step, over the points that the artist's skinning does not explain.
#include "deform/offline/skinning_decomposition.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/Dense>
#include <glm/gtc/quaternion.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/parallel.hpp"
#include "finite.hpp"

namespace deform {
namespace {

constexpr int max_own_bones = 8;     // a moved point's own bones that stay candidates (its strongest)
constexpr int extra_candidates = 8;  // and its nearest extra bones
constexpr int max_candidates = max_own_bones + extra_candidates;
constexpr std::size_t min_points_per_bone = 4;
constexpr int kmeans_rounds = 10;
constexpr int kmeans_refills = 4;

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 32, 32>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 32, 1>;

glm::vec3 transform(const glm::mat4& m, glm::vec3 p) noexcept { return glm::vec3(m * glm::vec4(p, 1.0f)); }

// One influence of a point: a bone of the combined skeleton (body bones first, then the extra bones) and its weight.
struct Influence {
  std::uint32_t bone = 0;
  float weight = 0.0f;
};

// Everything the steps share. Frame-major arrays: [t * count + k].
// A clip's frames within the problem's: [begin, end).
struct ClipRange {
  const DecompositionFrames* frames = nullptr;
  std::size_t begin = 0, end = 0;
};

struct Problem {
  const Model* model = nullptr;
  std::vector<ClipRange> clips;
  std::vector<const glm::vec3*> goals;     // per frame (the clips' one after the other): its positions
  std::vector<const glm::mat4*> world_in;  // per frame: its bones' matrices
  std::size_t points = 0, frame_count = 0, body = 0;
  float diagonal = 0.0f;
  std::vector<Pose> body_pose;          // per frame: the body's rigid local transforms, as the file will hold them
  std::vector<glm::mat4> body_world;    // [t * body + b], from body_pose by forward kinematics
  std::vector<glm::mat4> body_palette;  // [t * body + b]: body_world · inverse bind
  std::vector<std::uint32_t> moved;     // points to fit, ascending
  std::vector<double> unmoved_sse;      // per frame: squared error of the points that keep the artist's weights
  std::vector<float> unmoved_max;       // per frame: their largest error
  // The extra bones.
  std::size_t extras = 0;
  std::vector<std::uint32_t> parent;     // body bone of each
  std::vector<glm::vec3> centre;         // rest-space centre (bind translation) of each
  std::vector<glm::mat4> extra_palette;  // [t * extras + e]: rest space to frame t, rigid
  // Per moved point (index m into `moved`): its own bones and its current influences.
  std::vector<std::array<std::uint32_t, max_own_bones>> own;
  std::vector<std::uint8_t> own_count;
  std::vector<std::array<Influence, 8>> fit;
  std::vector<std::uint8_t> fit_count;
  std::vector<glm::vec3> reconstruction;  // [t * moved + m]: the current skinning of moved point m
};

const glm::mat4& bone_palette(const Problem& pb, std::size_t t, std::uint32_t bone) {
  return bone < pb.body ? pb.body_palette[t * pb.body + bone] : pb.extra_palette[t * pb.extras + (bone - pb.body)];
}

glm::vec3 target(const Problem& pb, std::size_t t, std::uint32_t point) { return pb.goals[t][point]; }

void require_valid(const Model& model, const DecompositionFrames& frames) {
  const std::size_t n = frames.times.size(), points = model.mesh.point_count();
  const std::string clip = "clip '" + frames.name + "'";
  if (n == 0) throw Error::invalid_argument(clip, "there are no frames");
  if (frames.bone_world.size() != n || frames.positions.size() != n)
    throw Error::invalid_argument(clip, "times, bone_world and positions must have one entry per frame");
  for (std::size_t t = 0; t < n; ++t) {
    const std::string frame = clip + " frame " + std::to_string(t);
    if (!std::isfinite(frames.times[t]) || frames.times[t] < 0.0f ||
        (t > 0 && !(frames.times[t] > frames.times[t - 1])))
      throw Error::invalid_argument(frame, "times must be finite, >= 0 and strictly increasing");
    if (frames.bone_world[t].size() != model.skeleton.bone_count())
      throw Error::invalid_argument(frame, "bone_world must have one matrix per bone");
    if (frames.positions[t].size() != points)
      throw Error::invalid_argument(frame, "positions must have one entry per mesh point");
    for (const glm::mat4& m : frames.bone_world[t])
      if (!finite(m)) throw Error::invalid_argument(frame, "a bone matrix is not finite");
    for (const glm::vec3& p : frames.positions[t])
      if (!finite(p)) throw Error::invalid_argument(frame, "a position is not finite");
  }
}

void require_valid(const Model& model, std::span<const DecompositionFrames> clips,
                   const DecompositionOptions& options) {
  if (options.max_bones > 1000) throw Error::invalid_argument("max_bones", "must be in [0, 1000]");
  if (options.influences < 1 || options.influences > 8)
    throw Error::invalid_argument("influences", "must be in [1, 8]");
  if (options.iterations < 1 || options.iterations > 1000)
    throw Error::invalid_argument("iterations", "must be in [1, 1000]");
  if (!(options.moved_tolerance >= 0.0f && options.moved_tolerance <= 1.0f))
    throw Error::invalid_argument("moved_tolerance", "must be in [0, 1]");
  for (const glm::vec3& s : options.seeds)
    if (!finite(s)) throw Error::invalid_argument("seeds", "a seed is not finite");
  if (model.weights.size() != model.mesh.point_count())
    throw Error::invalid_argument("model", "the weights do not have one entry per mesh point");
  if (clips.empty()) throw Error::invalid_argument("clips", "there are no clips");
  for (const DecompositionFrames& frames : clips) require_valid(model, frames);
}

// The rotation of a matrix whose columns may carry a scale: the columns normalised, then the nearest quaternion.
glm::quat rotation_of(const glm::mat4& m) {
  glm::mat3 r(m);
  for (int c = 0; c < 3; ++c) {
    const float length = glm::length(r[c]);
    r[c] = length > 0.0f ? r[c] / length : glm::vec3(0.0f);
  }
  const glm::quat q = glm::quat_cast(r);
  const float length = glm::length(q);
  return length > 0.0f && std::isfinite(length) ? q / length : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
}

// The body's motion as the file will play it: each frame's bone matrices made into rigid local transforms, then
// forward kinematics again, so that the skinning the fit works against is the engine's.
void prepare_body(Problem& pb) {
  const Skeleton& skeleton = pb.model->skeleton;
  pb.body_pose.resize(pb.frame_count);
  pb.body_world.resize(pb.frame_count * pb.body);
  pb.body_palette.resize(pb.frame_count * pb.body);
  for (std::size_t t = 0; t < pb.frame_count; ++t) {
    const glm::mat4* world = pb.world_in[t];
    Pose& pose = pb.body_pose[t];
    pose.rotations.resize(pb.body);
    pose.translations.resize(pb.body);
    for (std::size_t b = 0; b < pb.body; ++b) {
      const std::int32_t parent = skeleton.bones()[b].parent;
      const glm::mat4 local = parent < 0 ? world[b] : glm::inverse(world[std::size_t(parent)]) * world[b];
      pose.rotations[b] = rotation_of(local);
      pose.translations[b] = glm::vec3(local[3]);
      if (!finite(pose.translations[b])) pose.translations[b] = glm::vec3(0.0f);
    }
    LocalToWorldJob fk;
    fk.skeleton = &skeleton;
    fk.rotations = pose.rotations;
    fk.translations = pose.translations;
    fk.world = std::span<glm::mat4>(pb.body_world).subspan(t * pb.body, pb.body);
    fk.palette = std::span<glm::mat4>(pb.body_palette).subspan(t * pb.body, pb.body);
    if (const Status status = fk.run(); !status)
      throw Error::invalid_argument("frame " + std::to_string(t), std::string("the bones' pose: ") + status.reason());
  }
}

// The artist's influences of point p: its four slots and its extras, positive weights only.
std::vector<Influence> artist_influences(const SkinWeights& weights, std::size_t p) {
  std::vector<Influence> list;
  for (int k = 0; k < 4; ++k)
    if (weights.weights[p][k] > 0.0f) list.push_back({weights.bones[p][k], weights.weights[p][k]});
  if (weights.has_extra()) {
    const auto it = std::lower_bound(weights.extra_points.begin(), weights.extra_points.end(), std::uint32_t(p));
    if (it != weights.extra_points.end() && *it == p) {
      const std::size_t j = static_cast<std::size_t>(it - weights.extra_points.begin());
      for (std::uint32_t e = weights.extra_offsets[j]; e < weights.extra_offsets[j + 1]; ++e)
        if (weights.extra_weights[e] > 0.0f) list.push_back({weights.extra_bones[e], weights.extra_weights[e]});
    }
  }
  return list;
}

// Which points the artist's skinning does not explain, and the error of those it does, per frame.
void find_moved_points(Problem& pb, float tolerance) {
  const SkinWeights& weights = pb.model->weights;
  const std::span<const glm::vec3> rest = pb.model->mesh.positions;
  const float limit = tolerance * pb.diagonal;
  pb.unmoved_sse.assign(pb.frame_count, 0.0);
  pb.unmoved_max.assign(pb.frame_count, 0.0f);
  std::vector<float> error(pb.frame_count);
  for (std::size_t p = 0; p < pb.points; ++p) {
    const std::vector<Influence> influences = artist_influences(weights, p);
    float largest = 0.0f;
    for (std::size_t t = 0; t < pb.frame_count; ++t) {
      glm::vec3 skinned(0.0f);
      for (const Influence& in : influences) skinned += in.weight * transform(bone_palette(pb, t, in.bone), rest[p]);
      error[t] = glm::length(target(pb, t, std::uint32_t(p)) - skinned);
      largest = std::max(largest, error[t]);
    }
    if (largest > limit) {
      pb.moved.push_back(std::uint32_t(p));
      continue;
    }
    for (std::size_t t = 0; t < pb.frame_count; ++t) {
      pb.unmoved_sse[t] += double(error[t]) * error[t];
      pb.unmoved_max[t] = std::max(pb.unmoved_max[t], error[t]);
    }
  }
}

std::size_t nearest(std::span<const glm::vec3> centres, glm::vec3 p) {
  std::size_t best = 0;
  float best_distance = std::numeric_limits<float>::infinity();
  for (std::size_t c = 0; c < centres.size(); ++c)
    if (const float d = glm::dot(p - centres[c], p - centres[c]); d < best_distance) {
      best_distance = d;
      best = c;
    }
  return best;
}

// A moved point's path, for clustering: its rest position and its goal at up to `path_frames` frames spread over
// the clip, flattened. Two points of one rigid piece stay as far apart on every frame as at rest; points that move
// differently drift apart, so the distance between paths groups the points that one rigid bone can carry.
constexpr std::size_t path_frames = 16;

struct Paths {
  std::size_t dimension = 0;
  std::vector<float> values;  // [m * dimension + k]
  std::span<const float> of(std::size_t m) const { return std::span(values).subspan(m * dimension, dimension); }
};

Paths moved_paths(const Problem& pb) {
  const std::size_t samples = std::min(path_frames, pb.frame_count);
  Paths paths;
  paths.dimension = 3 * (1 + samples);
  paths.values.reserve(pb.moved.size() * paths.dimension);
  for (const std::uint32_t p : pb.moved) {
    const glm::vec3 rest = pb.model->mesh.positions[p];
    paths.values.insert(paths.values.end(), {rest.x, rest.y, rest.z});
    for (std::size_t s = 0; s < samples; ++s) {
      const std::size_t t = samples == 1 ? 0 : s * (pb.frame_count - 1) / (samples - 1);
      const glm::vec3 goal = target(pb, t, p);
      paths.values.insert(paths.values.end(), {goal.x, goal.y, goal.z});
    }
  }
  return paths;
}

float path_distance(std::span<const float> a, std::span<const float> b) {
  float sum = 0.0f;
  for (std::size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  return sum;
}

std::size_t nearest_path(const std::vector<float>& centres, std::size_t dimension, std::span<const float> path) {
  std::size_t best = 0;
  float best_distance = std::numeric_limits<float>::infinity();
  for (std::size_t c = 0; c * dimension < centres.size(); ++c)
    if (const float d = path_distance(std::span(centres).subspan(c * dimension, dimension), path); d < best_distance) {
      best_distance = d;
      best = c;
    }
  return best;
}

// The moved points' clusters: first the seeds that points gather around (by rest position), then the moved points
// whose paths are farthest from every centre until the budget is spent, then Lloyd's rounds on the paths. Sets the
// extra bones' count and rest centres; returns each moved point's cluster.
std::vector<std::uint32_t> cluster_moved_points(Problem& pb, const DecompositionOptions& options) {
  const std::span<const glm::vec3> rest = pb.model->mesh.positions;
  const std::size_t budget = std::min(options.max_bones, pb.moved.size() / min_points_per_bone);
  if (budget == 0) return {};
  const Paths paths = moved_paths(pb);
  const std::size_t dim = paths.dimension, n = pb.moved.size();
  std::vector<float> centres;  // [c * dim + k]
  std::vector<std::uint32_t> cluster(n);
  std::vector<double> sum;
  std::vector<std::size_t> count;
  // Each centre the mean path of its cluster's points; a cluster left empty is dropped.
  const auto recentre = [&](std::size_t clusters) {
    sum.assign(clusters * dim, 0.0);
    count.assign(clusters, 0);
    for (std::size_t m = 0; m < n; ++m) {
      ++count[cluster[m]];
      for (std::size_t k = 0; k < dim; ++k) sum[cluster[m] * dim + k] += paths.of(m)[k];
    }
    std::vector<std::uint32_t> renumber(clusters, 0);
    centres.clear();
    for (std::size_t c = 0; c < clusters; ++c) {
      if (count[c] == 0) continue;
      renumber[c] = std::uint32_t(centres.size() / dim);
      for (std::size_t k = 0; k < dim; ++k) centres.push_back(float(sum[c * dim + k] / double(count[c])));
    }
    for (std::uint32_t& c : cluster) c = renumber[c];
  };
  if (!options.seeds.empty()) {
    std::vector<std::size_t> gathered(options.seeds.size(), 0);
    for (std::size_t m = 0; m < n; ++m)
      ++gathered[cluster[m] = std::uint32_t(nearest(options.seeds, rest[pb.moved[m]]))];
    // Seeds with too few points give them to the nearest kept seed.
    std::vector<glm::vec3> kept;
    for (std::size_t s = 0; s < options.seeds.size() && kept.size() < budget; ++s)
      if (gathered[s] >= min_points_per_bone) kept.push_back(options.seeds[s]);
    if (!kept.empty()) {
      for (std::size_t m = 0; m < n; ++m) cluster[m] = std::uint32_t(nearest(kept, rest[pb.moved[m]]));
      recentre(kept.size());
    }
  }
  if (centres.empty()) centres.assign(paths.of(0).begin(), paths.of(0).end());
  // Up to the budget by farthest paths, then Lloyd's rounds; a cluster they empty is dropped, and its bone given
  // again to the farthest path, a few times over.
  for (int refill = 0; refill < kmeans_refills; ++refill) {
    std::vector<float> distance(n, std::numeric_limits<float>::infinity());
    const std::size_t before = centres.size() / dim;
    for (std::size_t from = 0; centres.size() / dim <= budget; from = centres.size() / dim - 1) {
      for (std::size_t m = 0; m < n; ++m)
        for (std::size_t c = from; c < centres.size() / dim; ++c)
          distance[m] = std::min(distance[m], path_distance(std::span(centres).subspan(c * dim, dim), paths.of(m)));
      if (centres.size() / dim == budget) break;
      const std::size_t far = std::size_t(std::max_element(distance.begin(), distance.end()) - distance.begin());
      if (!(distance[far] > 0.0f)) break;
      centres.insert(centres.end(), paths.of(far).begin(), paths.of(far).end());
    }
    if (refill > 0 && centres.size() / dim == before) break;  // nothing was added: the previous rounds stand
    for (int round = 0; round < kmeans_rounds; ++round) {
      for (std::size_t m = 0; m < n; ++m) cluster[m] = std::uint32_t(nearest_path(centres, dim, paths.of(m)));
      recentre(centres.size() / dim);
    }
    if (centres.size() / dim == budget) break;
  }
  pb.extras = centres.size() / dim;
  pb.centre.resize(pb.extras);
  for (std::size_t e = 0; e < pb.extras; ++e)
    pb.centre[e] = {centres[e * dim], centres[e * dim + 1], centres[e * dim + 2]};
  return cluster;
}

// The body bone each extra bone hangs from: the one with the largest summed artist weight over its cluster.
void choose_parents(Problem& pb, const std::vector<std::uint32_t>& cluster) {
  std::vector<std::vector<double>> total(pb.extras, std::vector<double>(pb.body, 0.0));
  for (std::size_t m = 0; m < pb.moved.size(); ++m)
    for (const Influence& in : artist_influences(pb.model->weights, pb.moved[m]))
      total[cluster[m]][in.bone] += in.weight;
  pb.parent.resize(pb.extras);
  for (std::size_t e = 0; e < pb.extras; ++e)
    pb.parent[e] = std::uint32_t(std::max_element(total[e].begin(), total[e].end()) - total[e].begin());
}

// The rigid transform (rotation R, translation T) minimising Σ |q_i − w_i (R p_i + T)|² over weighted pairs: the
// centroids p* = Σ w² p / Σ w² and q* = Σ w q / Σ w², then R from the SVD of Σ (q_i − w_i q*) (w_i (p_i − p*))ᵀ with
// its determinant made +1, and T = q* − R p*. Returns false (and leaves `out`) when the weights are all zero.
struct WeightedPair {
  glm::vec3 rest;
  glm::vec3 goal;
  float weight;
};
bool fit_rigid(std::span<const WeightedPair> pairs, glm::mat4& out) {
  double w2 = 0.0;
  glm::dvec3 p_sum(0.0), q_sum(0.0);
  for (const WeightedPair& pair : pairs) {
    const double w = pair.weight;
    w2 += w * w;
    p_sum += w * w * glm::dvec3(pair.rest);
    q_sum += w * glm::dvec3(pair.goal);
  }
  if (!(w2 > 1e-20)) return false;
  const glm::dvec3 p_star = p_sum / w2, q_star = q_sum / w2;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const WeightedPair& pair : pairs) {
    const double w = pair.weight;
    const glm::dvec3 a = w * (glm::dvec3(pair.rest) - p_star), b = glm::dvec3(pair.goal) - w * q_star;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) covariance(r, c) += b[r] * a[c];
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix3d rotation = svd.matrixU() * d * svd.matrixV().transpose();
  glm::dmat3 r;
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 3; ++c) r[c][row] = rotation(row, c);
  const glm::dvec3 translation = q_star - r * p_star;
  out = glm::mat4(glm::mat3(r));
  out[3] = glm::vec4(glm::vec3(translation), 1.0f);
  return true;
}

// Each extra bone's start: the rigid motion of its cluster's points, each point's weight 1 on its cluster's bone.
void start_extra_bones(Problem& pb, const std::vector<std::uint32_t>& cluster, ThreadPool& pool) {
  const std::span<const glm::vec3> rest = pb.model->mesh.positions;
  pb.extra_palette.assign(pb.frame_count * pb.extras, glm::mat4(1.0f));
  pb.fit.assign(pb.moved.size(), {});
  pb.fit_count.assign(pb.moved.size(), 1);
  for (std::size_t m = 0; m < pb.moved.size(); ++m) pb.fit[m][0] = {std::uint32_t(pb.body + cluster[m]), 1.0f};
  std::vector<std::vector<std::uint32_t>> members(pb.extras);
  for (std::size_t m = 0; m < pb.moved.size(); ++m) members[cluster[m]].push_back(std::uint32_t(m));
  pool.parallel_for(pb.frame_count, 1, [&](std::size_t begin, std::size_t end) {
    std::vector<WeightedPair> pairs;
    for (std::size_t t = begin; t < end; ++t)
      for (std::size_t e = 0; e < pb.extras; ++e) {
        pairs.clear();
        for (const std::uint32_t m : members[e]) pairs.push_back({rest[pb.moved[m]], target(pb, t, pb.moved[m]), 1.0f});
        fit_rigid(pairs, pb.extra_palette[t * pb.extras + e]);
      }
  });
}

// The current skinning of every moved point at every frame, from its influences.
void reconstruct(Problem& pb, ThreadPool& pool) {
  const std::span<const glm::vec3> rest = pb.model->mesh.positions;
  const std::size_t n = pb.moved.size();
  pb.reconstruction.resize(pb.frame_count * n);
  pool.parallel_for(pb.frame_count, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t)
      for (std::size_t m = 0; m < n; ++m) {
        glm::vec3 sum(0.0f);
        for (int k = 0; k < pb.fit_count[m]; ++k)
          sum += pb.fit[m][k].weight * transform(bone_palette(pb, t, pb.fit[m][k].bone), rest[pb.moved[m]]);
        pb.reconstruction[t * n + m] = sum;
      }
  });
}

// The candidates of moved point m: its own bones (the artist's, strongest first), the extra bones it uses now (so
// that its current weights stay within reach and the weight step never does worse), then its nearest extra bones.
std::size_t candidates_of(const Problem& pb, std::size_t m, std::array<std::uint32_t, max_candidates>& out) {
  std::size_t n = 0;
  for (int k = 0; k < pb.own_count[m]; ++k) out[n++] = pb.own[m][k];
  const auto listed = [&](std::uint32_t bone) {
    return std::find(out.begin(), out.begin() + n, bone) != out.begin() + n;
  };
  for (int k = 0; k < pb.fit_count[m]; ++k)
    if (!listed(pb.fit[m][k].bone)) out[n++] = pb.fit[m][k].bone;
  const glm::vec3 p = pb.model->mesh.positions[pb.moved[m]];
  // The nearest few, kept sorted by insertion (distance, then the lower bone).
  std::array<std::pair<float, std::uint32_t>, extra_candidates> best;
  std::size_t kept = 0;
  for (std::size_t e = 0; e < pb.extras; ++e) {
    const std::pair<float, std::uint32_t> entry{glm::dot(p - pb.centre[e], p - pb.centre[e]), std::uint32_t(e)};
    if (kept == best.size() && !(entry < best[kept - 1])) continue;
    std::size_t at = std::min(kept, best.size() - 1);
    kept = std::min(kept + 1, best.size());
    for (; at > 0 && entry < best[at - 1]; --at) best[at] = best[at - 1];
    best[at] = entry;
  }
  for (std::size_t k = 0; k < kept && n < max_candidates; ++k)
    if (const std::uint32_t bone = std::uint32_t(pb.body + best[k].second); !listed(bone)) out[n++] = bone;
  return n;
}

// Non-negative least squares over the candidates `use` (indices into the system), the others held at zero.
void solve_subset(const Small& gram, const SmallVector& rhs, std::span<const int> use, SmallVector& x) {
  const int n = int(use.size());
  std::array<double, 32 * 32> g{};
  std::array<double, 32> h{}, sub{};
  for (int a = 0; a < n; ++a) {
    h[std::size_t(a)] = rhs(use[std::size_t(a)]);
    for (int b = 0; b < n; ++b) g[std::size_t(a * n + b)] = gram(use[std::size_t(a)], use[std::size_t(b)]);
  }
  nonnegative_least_squares(std::span<const double>(g.data(), std::size_t(n * n)),
                            std::span<const double>(h.data(), std::size_t(n)),
                            std::span<double>(sub.data(), std::size_t(n)));
  x.setZero();
  for (int a = 0; a < n; ++a) x(use[std::size_t(a)]) = sub[std::size_t(a)];
}

// One moved point's weights: non-negative least squares over its candidates, the sum held to one by a heavy
// penalty (as the paper does), then its `influences` strongest solved again alone, then normalised. The system is
// written in the offsets d_c = X_c p − v of each candidate's skinning from the goal, so that under Σ w = 1 the
// residual is Σ w_c d_c: well scaled whatever the model's distance from its origin.
void fit_point_weights(Problem& pb, std::size_t m, int influences) {
  std::array<std::uint32_t, max_candidates> candidates;
  const std::size_t n = candidates_of(pb, m, candidates);
  const glm::vec3 p = pb.model->mesh.positions[pb.moved[m]];
  Small gram = Small::Zero(Eigen::Index(n), Eigen::Index(n));
  std::array<glm::dvec3, max_candidates> d;
  for (std::size_t t = 0; t < pb.frame_count; ++t) {
    const glm::dvec3 goal(target(pb, t, pb.moved[m]));
    for (std::size_t c = 0; c < n; ++c) d[c] = glm::dvec3(transform(bone_palette(pb, t, candidates[c]), p)) - goal;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a; b < n; ++b) gram(Eigen::Index(a), Eigen::Index(b)) += glm::dot(d[a], d[b]);
  }
  const Small plain = gram.selfadjointView<Eigen::Upper>();  // Σ_t |Σ w_c d_c|² = wᵀ plain w when Σ w = 1
  const double scale = gram.trace() / double(n) + 1e-30;
  const double penalty = 1e6 * scale;
  for (std::size_t a = 0; a < n; ++a) {
    gram(Eigen::Index(a), Eigen::Index(a)) += 1e-9 * scale;  // a ridge, for candidates that move alike
    for (std::size_t b = a; b < n; ++b) {
      gram(Eigen::Index(a), Eigen::Index(b)) += penalty;
      gram(Eigen::Index(b), Eigen::Index(a)) = gram(Eigen::Index(a), Eigen::Index(b));
    }
  }
  const SmallVector rhs = SmallVector::Constant(Eigen::Index(n), penalty);
  SmallVector x = SmallVector::Zero(Eigen::Index(n));
  std::array<int, max_candidates> use;
  std::iota(use.begin(), use.begin() + std::ptrdiff_t(n), 0);
  solve_subset(gram, rhs, std::span<const int>(use.data(), n), x);
  std::size_t nonzero = 0;
  for (std::size_t c = 0; c < n; ++c) nonzero += x(Eigen::Index(c)) > 0.0 ? 1 : 0;
  if (nonzero > std::size_t(influences)) {
    // The strongest `influences` (the lower candidate on a tie), solved again without the others.
    std::sort(use.begin(), use.begin() + std::ptrdiff_t(n),
              [&](int a, int b) { return x(a) != x(b) ? x(a) > x(b) : a < b; });
    std::sort(use.begin(), use.begin() + influences);
    solve_subset(gram, rhs, std::span<const int>(use.data(), std::size_t(influences)), x);
  }
  double total = 0.0;
  for (std::size_t c = 0; c < n; ++c) total += x(Eigen::Index(c));
  if (!(total > 0.0) || !std::isfinite(total)) return;  // a degenerate system: the point keeps its weights
  SmallVector now = SmallVector::Zero(Eigen::Index(n)), before = SmallVector::Zero(Eigen::Index(n));
  for (std::size_t c = 0; c < n; ++c) now(Eigen::Index(c)) = double(float(x(Eigen::Index(c)) / total));
  for (int k = 0; k < pb.fit_count[m]; ++k)
    before(Eigen::Index(std::find(candidates.begin(), candidates.begin() + n, pb.fit[m][k].bone) -
                        candidates.begin())) = pb.fit[m][k].weight;
  // The truncation to `influences` and the penalty can lose a little: the weights change only when they gain.
  if (!(now.dot(plain * now) < before.dot(plain * before))) return;
  std::uint8_t count = 0;
  for (std::size_t c = 0; c < n; ++c)
    if (now(Eigen::Index(c)) > 0.0 && count < influences)
      pb.fit[m][count++] = {candidates[c], float(now(Eigen::Index(c)))};
  pb.fit_count[m] = count;
}

// Each extra bone's members: the moved points with a weight on it, and that weight.
struct Member {
  std::uint32_t moved;
  float weight;
};
std::vector<std::vector<Member>> members_of(const Problem& pb) {
  std::vector<std::vector<Member>> members(pb.extras);
  for (std::size_t m = 0; m < pb.moved.size(); ++m)
    for (int k = 0; k < pb.fit_count[m]; ++k)
      if (pb.fit[m][k].bone >= pb.body)
        members[pb.fit[m][k].bone - pb.body].push_back({std::uint32_t(m), pb.fit[m][k].weight});
  return members;
}

// The bone step: frame by frame, each extra bone in turn fitted to what the other bones leave of its members'
// goals, the reconstruction updated at once (the paper's block coordinate descent). Frames are independent.
void fit_extra_bones(Problem& pb, const std::vector<std::vector<Member>>& members, ThreadPool& pool) {
  const std::span<const glm::vec3> rest = pb.model->mesh.positions;
  const std::size_t n = pb.moved.size();
  pool.parallel_for(pb.frame_count, 1, [&](std::size_t begin, std::size_t end) {
    std::vector<WeightedPair> pairs;
    for (std::size_t t = begin; t < end; ++t)
      for (std::size_t e = 0; e < pb.extras; ++e) {
        glm::mat4& bone = pb.extra_palette[t * pb.extras + e];
        pairs.clear();
        for (const Member& member : members[e]) {
          const glm::vec3 p = rest[pb.moved[member.moved]];
          const glm::vec3 others = pb.reconstruction[t * n + member.moved] - member.weight * transform(bone, p);
          pairs.push_back({p, target(pb, t, pb.moved[member.moved]) - others, member.weight});
        }
        glm::mat4 fitted = bone;
        if (!fit_rigid(pairs, fitted)) continue;
        for (const Member& member : members[e]) {
          const glm::vec3 p = rest[pb.moved[member.moved]];
          pb.reconstruction[t * n + member.moved] += member.weight * (transform(fitted, p) - transform(bone, p));
        }
        bone = fitted;
      }
  });
}

// The squared error of each moved point over the frames, and the error per frame (all points).
struct Errors {
  std::vector<double> point_sse;  // per moved point
  std::vector<double> frame_sse;  // per frame, every point
  std::vector<float> frame_max;
  double total = 0.0;
};
Errors measure(const Problem& pb) {
  const std::size_t n = pb.moved.size();
  Errors errors;
  errors.point_sse.assign(n, 0.0);
  errors.frame_sse = pb.unmoved_sse;
  errors.frame_max = pb.unmoved_max;
  for (std::size_t t = 0; t < pb.frame_count; ++t) {
    for (std::size_t m = 0; m < n; ++m) {
      const float e = glm::length(target(pb, t, pb.moved[m]) - pb.reconstruction[t * n + m]);
      errors.point_sse[m] += double(e) * e;
      errors.frame_sse[t] += double(e) * e;
      errors.frame_max[t] = std::max(errors.frame_max[t], e);
    }
    errors.total += errors.frame_sse[t];
  }
  return errors;
}

// An extra bone no point uses any more starts again where the fit is worst: at the moved point with the largest
// error, moving as rigidly as its neighbourhood (its share of the moved points, nearest first) does.
void restart_unused_bones(Problem& pb, const std::vector<std::vector<Member>>& members, const Errors& errors) {
  const std::span<const glm::vec3> rest = pb.model->mesh.positions;
  std::vector<double> sse = errors.point_sse;
  for (std::size_t e = 0; e < pb.extras; ++e) {
    if (!members[e].empty()) continue;
    const std::size_t worst = std::size_t(std::max_element(sse.begin(), sse.end()) - sse.begin());
    if (!(sse[worst] > 0.0)) return;
    const glm::vec3 centre = rest[pb.moved[worst]];
    std::vector<std::pair<float, std::uint32_t>> by_distance;
    for (std::size_t m = 0; m < pb.moved.size(); ++m)
      by_distance.push_back({glm::length(rest[pb.moved[m]] - centre), std::uint32_t(m)});
    const std::size_t share = std::max(min_points_per_bone, pb.moved.size() / std::max<std::size_t>(pb.extras, 1));
    std::partial_sort(by_distance.begin(), by_distance.begin() + std::ptrdiff_t(std::min(share, by_distance.size())),
                      by_distance.end());
    by_distance.resize(std::min(share, by_distance.size()));
    std::vector<std::uint32_t> cluster;
    std::vector<WeightedPair> pairs;
    std::vector<double> weight_on(pb.body, 0.0);
    for (const auto& [distance, m] : by_distance) {
      sse[m] = 0.0;  // the next unused bone goes elsewhere
      for (const Influence& in : artist_influences(pb.model->weights, pb.moved[m])) weight_on[in.bone] += in.weight;
    }
    pb.centre[e] = centre;
    pb.parent[e] = std::uint32_t(std::max_element(weight_on.begin(), weight_on.end()) - weight_on.begin());
    for (std::size_t t = 0; t < pb.frame_count; ++t) {
      pairs.clear();
      for (const auto& [distance, m] : by_distance)
        pairs.push_back({rest[pb.moved[m]], target(pb, t, pb.moved[m]), 1.0f});
      fit_rigid(pairs, pb.extra_palette[t * pb.extras + e]);
    }
  }
}

// Appends one track's keys, or one key when every value is the first, or none when every value is `rest`.
template <class T, class Same>
void write_track(Track<T>& track, std::span<const float> times, std::vector<T> values, T rest, Same same) {
  const bool moves = std::any_of(values.begin(), values.end(), [&](const T& v) { return !same(v, rest); });
  if (!moves) return;
  const bool constant = std::all_of(values.begin(), values.end(), [&](const T& v) { return same(v, values[0]); });
  track.interpolation = Interpolation::linear;
  if (constant) {
    track.times = {times[0]};
    track.values = {values[0]};
    return;
  }
  track.times.assign(times.begin(), times.end());
  track.values = std::move(values);
}

void write_channel(Animation& clip, std::int32_t bone, std::span<const float> times, std::vector<glm::quat> rotations,
                   std::vector<glm::vec3> translations, glm::quat rest_rotation, glm::vec3 rest_translation) {
  // Neighbouring keys on the same side of the quaternion sphere, so that no viewer takes the long way round.
  for (std::size_t k = 1; k < rotations.size(); ++k)
    if (glm::dot(rotations[k], rotations[k - 1]) < 0.0f) rotations[k] = -rotations[k];
  Channel channel;
  channel.bone = bone;
  write_track(channel.rotation, times, std::move(rotations), rest_rotation,
              [](glm::quat a, glm::quat b) { return std::abs(glm::dot(a, b)) >= 1.0f - 1e-7f; });
  write_track(channel.translation, times, std::move(translations), rest_translation,
              [](glm::vec3 a, glm::vec3 b) { return glm::length(a - b) <= 1e-7f * std::max(1.0f, glm::length(b)); });
  if (!channel.rotation.empty() || !channel.translation.empty()) clip.channels.push_back(std::move(channel));
}

// The skeleton with the extra bones appended, each bound at its centre with its parent's bind orientation.
Skeleton extended_skeleton(const Problem& pb) {
  const Skeleton& body = pb.model->skeleton;
  std::vector<Bone> bones(body.bones().begin(), body.bones().end());
  for (std::size_t e = 0; e < pb.extras; ++e) {
    Bone bone;
    const std::int32_t parent = std::int32_t(pb.parent[e]);
    bone.name = body.key(parent) + ".bake" + std::to_string(e);
    while (body.find(bone.name) >= 0) bone.name += "_";
    bone.parent = parent;
    bone.bind_translation = transform(body.inverse_bind_world()[std::size_t(parent)], pb.centre[e]);
    bones[std::size_t(parent)].children.push_back(std::int32_t(bones.size()));
    bones.push_back(std::move(bone));
  }
  return Skeleton(std::move(bones), "<skinning decomposition>");
}

// The artist's rows for unmoved points, bit for bit; the fitted influences for the moved ones.
SkinWeights extended_weights(const Problem& pb) {
  const SkinWeights& artist = pb.model->weights;
  SkinWeights out;
  std::size_t m = 0;
  std::array<std::uint16_t, 8> bones;
  std::array<float, 8> values;
  for (std::size_t p = 0; p < pb.points; ++p) {
    if (m < pb.moved.size() && pb.moved[m] == p) {
      for (int k = 0; k < pb.fit_count[m]; ++k) {
        bones[std::size_t(k)] = std::uint16_t(pb.fit[m][k].bone);
        values[std::size_t(k)] = pb.fit[m][k].weight;
      }
      append_influences(out, std::span(bones.data(), pb.fit_count[m]), std::span(values.data(), pb.fit_count[m]),
                        bones[0]);
      ++m;
      continue;
    }
    out.bones.push_back(artist.bones[p]);
    out.weights.push_back(artist.weights[p]);
    if (!artist.has_extra()) continue;
    const auto it = std::lower_bound(artist.extra_points.begin(), artist.extra_points.end(), std::uint32_t(p));
    if (it == artist.extra_points.end() || *it != p) continue;
    const std::size_t j = static_cast<std::size_t>(it - artist.extra_points.begin());
    if (out.extra_offsets.empty()) out.extra_offsets.push_back(0);
    out.extra_points.push_back(std::uint32_t(p));
    for (std::uint32_t e = artist.extra_offsets[j]; e < artist.extra_offsets[j + 1]; ++e) {
      out.extra_bones.push_back(artist.extra_bones[e]);
      out.extra_weights.push_back(artist.extra_weights[e]);
    }
    out.extra_offsets.push_back(std::uint32_t(out.extra_bones.size()));
  }
  return out;
}

// Every bone's local motion at the frames' times: the body's rigid locals, and each extra bone's rest-to-frame
// motion expressed under its parent: L = W_parent⁻¹ · M · B, B its bind (parent orientation, at its centre).
Animation extended_clip(const Problem& pb, const Skeleton& skeleton, const ClipRange& range) {
  Animation clip;
  clip.name = range.frames->name;
  clip.loop = false;
  clip.duration = range.frames->times.back();
  const std::span<const float> times = range.frames->times;
  const std::size_t count = range.end - range.begin;
  const Pose rest = skeleton.bind_pose();
  for (std::size_t b = 0; b < pb.body; ++b) {
    std::vector<glm::quat> rotations(count);
    std::vector<glm::vec3> translations(count);
    for (std::size_t k = 0; k < count; ++k) {
      rotations[k] = pb.body_pose[range.begin + k].rotations[b];
      translations[k] = pb.body_pose[range.begin + k].translations[b];
    }
    write_channel(clip, std::int32_t(b), times, std::move(rotations), std::move(translations), rest.rotations[b],
                  rest.translations[b]);
  }
  for (std::size_t e = 0; e < pb.extras; ++e) {
    const std::size_t bone = pb.body + e, parent = pb.parent[e];
    const glm::mat4 bind = skeleton.bind_world()[bone];
    std::vector<glm::quat> rotations(count);
    std::vector<glm::vec3> translations(count);
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t t = range.begin + k;
      const glm::mat4 local =
          glm::inverse(pb.body_world[t * pb.body + parent]) * pb.extra_palette[t * pb.extras + e] * bind;
      rotations[k] = rotation_of(local);
      translations[k] = glm::vec3(local[3]);
    }
    write_channel(clip, std::int32_t(bone), times, std::move(rotations), std::move(translations), rest.rotations[bone],
                  rest.translations[bone]);
  }
  clip.require_valid(skeleton.bone_count(), "<skinning decomposition>");
  return clip;
}

}  // namespace

SkinningDecomposition decompose_skinning(const Model& model, const DecompositionFrames& frames,
                                         const DecompositionOptions& options) {
  return decompose_skinning(model, std::span<const DecompositionFrames>(&frames, 1), options);
}

SkinningDecomposition decompose_skinning(const Model& model, std::span<const DecompositionFrames> clips,
                                         const DecompositionOptions& options) {
  require_valid(model, clips, options);
  Problem pb;
  pb.model = &model;
  for (const DecompositionFrames& frames : clips) {
    pb.clips.push_back({&frames, pb.goals.size(), pb.goals.size() + frames.times.size()});
    for (std::size_t t = 0; t < frames.times.size(); ++t) {
      pb.goals.push_back(frames.positions[t].data());
      pb.world_in.push_back(frames.bone_world[t].data());
    }
  }
  pb.points = model.mesh.point_count();
  pb.frame_count = pb.goals.size();
  pb.body = model.skeleton.bone_count();
  const Bounds bounds = compute_bounds(model.mesh.positions);
  pb.diagonal = std::max(glm::length(bounds.max - bounds.min), std::numeric_limits<float>::min());
  ThreadPool pool(options.threads);
  prepare_body(pb);
  find_moved_points(pb, options.moved_tolerance);
  const std::vector<std::uint32_t> cluster = cluster_moved_points(pb, options);
  if (pb.extras == 0) {
    // No extra bone to give them (a budget of 0, or too few moved points): every point keeps the artist's weights.
    pb.moved.clear();
    find_moved_points(pb, std::numeric_limits<float>::infinity());
  }
  choose_parents(pb, cluster);
  pb.own.assign(pb.moved.size(), {});
  pb.own_count.assign(pb.moved.size(), 0);
  for (std::size_t m = 0; m < pb.moved.size(); ++m) {
    const std::vector<Influence> own = artist_influences(model.weights, pb.moved[m]);
    for (const Influence& in : own)
      if (pb.own_count[m] < max_own_bones) pb.own[m][pb.own_count[m]++] = in.bone;
  }
  SkinningDecomposition out;
  if (pb.extras > 0) {
    start_extra_bones(pb, cluster, pool);
    reconstruct(pb, pool);
    double previous = measure(pb).total;
    for (out.iterations = 1; out.iterations <= options.iterations; ++out.iterations) {
      pool.parallel_for(pb.moved.size(), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t m = begin; m < end; ++m) fit_point_weights(pb, m, options.influences);
      });
      reconstruct(pb, pool);
      const std::vector<std::vector<Member>> members = members_of(pb);
      restart_unused_bones(pb, members, measure(pb));
      fit_extra_bones(pb, members, pool);
      const double now = measure(pb).total;
      // Converged: an alternation that gains less than a thousandth. Neither step can raise the error: the weight
      // step keeps a point's weights unless the new ones fit better, the bone step solves each bone exactly.
      if (!(now < previous * (1.0 - 1e-5))) break;
      previous = now;
    }
    out.iterations = std::min(out.iterations, options.iterations);
  }
  out.skeleton = extended_skeleton(pb);
  out.weights = extended_weights(pb);
  for (const ClipRange& range : pb.clips) out.clips.push_back(extended_clip(pb, out.skeleton, range));
  out.extra_bones = pb.extras;
  out.moved_points = pb.moved;
  const Errors errors = measure(pb);
  double sse = 0.0;
  float largest = 0.0f;
  out.frame_rms_error.resize(pb.frame_count);
  out.frame_max_error.resize(pb.frame_count);
  for (std::size_t t = 0; t < pb.frame_count; ++t) {
    sse += errors.frame_sse[t];
    largest = std::max(largest, errors.frame_max[t]);
    out.frame_rms_error[t] = float(std::sqrt(errors.frame_sse[t] / double(pb.points))) / pb.diagonal;
    out.frame_max_error[t] = errors.frame_max[t] / pb.diagonal;
  }
  out.rms_error = float(std::sqrt(sse / double(pb.points * pb.frame_count))) / pb.diagonal;
  out.max_error = largest / pb.diagonal;
  return out;
}

std::vector<glm::vec3> decomposition_seeds(const DeformerHierarchy& hierarchy, const Skeleton& skeleton) {
  std::vector<glm::vec3> seeds;
  for (std::size_t l = 0; l < hierarchy.lattice_count(); ++l) {
    const BezierLattice& lattice = hierarchy.rest_lattice(l);
    const glm::mat4& bind = skeleton.bind_world()[std::size_t(hierarchy.spec(l).bone)];
    const glm::ivec3 counts = lattice.point_counts();
    for (int i = 0; i < counts.x; ++i) {
      glm::dvec3 sum(0.0);
      for (int k = 0; k < counts.z; ++k)
        for (int j = 0; j < counts.y; ++j) sum += glm::dvec3(transform(bind, lattice.rest_point(i, j, k)));
      seeds.push_back(glm::vec3(sum / double(counts.y * counts.z)));
    }
  }
  return seeds;
}

bool nonnegative_least_squares(std::span<const double> gram, std::span<const double> rhs, std::span<double> x) {
  const int n = int(rhs.size());
  if (n == 0 || n > 32 || gram.size() != rhs.size() * rhs.size() || x.size() != rhs.size())
    throw Error::invalid_argument("nonnegative_least_squares", "needs an n × n system with 1 <= n <= 32");
  const auto g = [&](int r, int c) { return gram[std::size_t(r * n + c)]; };
  std::array<bool, 32> passive{};
  std::array<double, 32> z{};
  std::fill(x.begin(), x.end(), 0.0);
  double scale = 0.0;
  for (int i = 0; i < n; ++i) scale = std::max({scale, std::abs(rhs[std::size_t(i)]), std::abs(g(i, i))});
  const double tolerance = 1e-10 * scale;
  // z = the unconstrained minimiser over the passive set (the others zero).
  const auto solve_passive = [&] {
    std::array<int, 32> index;
    int m = 0;
    for (int i = 0; i < n; ++i)
      if (passive[std::size_t(i)]) index[std::size_t(m++)] = i;
    Small a(m, m);
    SmallVector b(m);
    for (int r = 0; r < m; ++r) {
      b(r) = rhs[std::size_t(index[std::size_t(r)])];
      for (int c = 0; c < m; ++c) a(r, c) = g(index[std::size_t(r)], index[std::size_t(c)]);
    }
    const SmallVector solution = a.ldlt().solve(b);
    z.fill(0.0);
    for (int r = 0; r < m; ++r) z[std::size_t(index[std::size_t(r)])] = std::isfinite(solution(r)) ? solution(r) : 0.0;
  };
  for (int iteration = 0; iteration < 3 * n; ++iteration) {
    // The most negative gradient among the zero variables joins the passive set.
    int join = -1;
    double best = tolerance;
    for (int i = 0; i < n; ++i) {
      if (passive[std::size_t(i)]) continue;
      double gradient = rhs[std::size_t(i)];
      for (int j = 0; j < n; ++j) gradient -= g(i, j) * x[std::size_t(j)];
      if (gradient > best) {
        best = gradient;
        join = i;
      }
    }
    if (join < 0) return true;
    passive[std::size_t(join)] = true;
    for (int inner = 0; inner <= n; ++inner) {
      solve_passive();
      double step = 1.0;
      int leave = -1;
      for (int i = 0; i < n; ++i)
        if (passive[std::size_t(i)] && z[std::size_t(i)] <= 0.0) {
          const double s = x[std::size_t(i)] / (x[std::size_t(i)] - z[std::size_t(i)]);
          if (s < step) {
            step = s;
            leave = i;
          }
        }
      if (leave < 0 && std::all_of(z.begin(), z.begin() + n, [](double v) { return v >= 0.0; })) {
        for (int i = 0; i < n; ++i) x[std::size_t(i)] = passive[std::size_t(i)] ? z[std::size_t(i)] : 0.0;
        break;
      }
      // Step towards z until a variable reaches zero; it (and any other at zero) leaves the passive set.
      for (int i = 0; i < n; ++i)
        if (passive[std::size_t(i)]) {
          x[std::size_t(i)] += step * (z[std::size_t(i)] - x[std::size_t(i)]);
          if (x[std::size_t(i)] <= 0.0 || i == leave) {
            x[std::size_t(i)] = 0.0;
            passive[std::size_t(i)] = false;
          }
        }
    }
  }
  return false;
}

}  // namespace deform
