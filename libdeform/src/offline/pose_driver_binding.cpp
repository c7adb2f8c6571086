// bind_pose_driver (offline/pose_driver.hpp): the sample poses' distances, the kernel matrix, its solve.
#include "deform/offline/pose_driver.hpp"
#include "deform/offline/rig.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "deform/runtime/error.hpp"
#include "finite.hpp"

namespace deform {
namespace {

void require_valid(const Skeleton& skeleton, std::span<const std::int32_t> bones, std::span<const Pose> samples,
                   std::span<const float> targets, std::size_t shape_count, const PoseDriverSettings& settings) {
  if (bones.empty()) throw Error::invalid_argument("bones", "a pose driver needs at least one driver bone");
  for (std::size_t j = 0; j < bones.size(); ++j) {
    if (bones[j] < 0 || std::size_t(bones[j]) >= skeleton.bone_count())
      throw Error::invalid_argument("bones", "bone " + std::to_string(bones[j]) + " is not in the skeleton");
    if (std::count(bones.begin(), bones.end(), bones[j]) > 1)
      throw Error::invalid_argument("bones", "bone '" + skeleton.key(bones[j]) + "' is listed twice");
  }
  if (samples.empty()) throw Error::invalid_argument("samples", "a pose driver needs at least one sample pose");
  if (shape_count == 0) throw Error::invalid_argument("shape_count", "a pose driver drives at least one shape");
  if (targets.size() != samples.size() * shape_count)
    throw Error::invalid_argument("targets", "expected one weight per sample pose and shape");
  for (const float t : targets)
    if (!std::isfinite(t)) throw Error::invalid_argument("targets", "a target weight is not finite");
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (samples[k].rotations.size() != skeleton.bone_count())
      throw Error::invalid_argument("sample " + std::to_string(k), "the pose does not have one rotation per bone");
    for (const std::int32_t bone : bones)
      if (!finite(samples[k].rotations[std::size_t(bone)]) ||
          glm::length(samples[k].rotations[std::size_t(bone)]) < 0.5f)
        throw Error::invalid_argument("sample " + std::to_string(k),
                                      "bone '" + skeleton.key(bone) + "' has no finite unit rotation");
  }
  if (!(settings.radius >= 0.0f) || !std::isfinite(settings.radius))
    throw Error::invalid_argument("radius", "must be finite and >= 0 (0 picks it)");
  if (!(settings.twist_weight >= 0.0f) || !std::isfinite(settings.twist_weight))
    throw Error::invalid_argument("twist_weight", "must be finite and >= 0");
  if (!(settings.regularization >= 0.0f) || !std::isfinite(settings.regularization))
    throw Error::invalid_argument("regularization", "must be finite and >= 0");
}

glm::vec3 twist_axis(const Skeleton& skeleton, std::int32_t bone) {
  for (const std::int32_t child : skeleton.bone(bone).children) {
    const glm::vec3 head = skeleton.bone(child).bind_translation;
    if (glm::length(head) > 0.0f) return glm::normalize(head);
  }
  return {0.0f, 1.0f, 0.0f};
}

}  // namespace

PoseDriverBinding bind_pose_driver(const Skeleton& skeleton, std::span<const std::int32_t> bones,
                                   std::span<const Pose> samples, std::span<const float> targets,
                                   std::size_t shape_count, const PoseDriverSettings& settings) {
  require_valid(skeleton, bones, samples, targets, shape_count, settings);
  PoseDriverBinding out;
  out.bones.assign(bones.begin(), bones.end());
  for (const std::int32_t bone : bones) out.twist_axes.push_back(twist_axis(skeleton, bone));
  for (const Pose& pose : samples)
    for (const std::int32_t bone : bones) out.sample_poses.push_back(glm::normalize(pose.rotations[std::size_t(bone)]));
  out.shape_count = shape_count;
  out.kernel = settings.kernel;
  out.twist_weight = settings.twist_weight;
  out.clamp = settings.clamp;
  // The squared distances between the samples, as the job measures them (float, the same function).
  const std::size_t n = samples.size(), b = bones.size();
  const auto size = static_cast<Eigen::Index>(n);
  Eigen::MatrixXd d2(size, size);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t l = 0; l < n; ++l) {
      float sum = 0.0f;
      for (std::size_t j = 0; j < b; ++j)
        sum += swing_twist_distance_squared(out.sample_poses[l * b + j], out.sample_poses[k * b + j], out.twist_axes[j],
                                            out.twist_weight);
      d2(Eigen::Index(k), Eigen::Index(l)) = sum;
    }
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t l = k + 1; l < n; ++l)
      if (!(d2(Eigen::Index(k), Eigen::Index(l)) > 1e-10))
        throw Error::invalid_argument("samples", "samples " + std::to_string(k) + " and " + std::to_string(l) +
                                                     " are the same pose for the driver bones");
  if (settings.radius > 0.0f) {
    out.radius = settings.radius;
  } else if (n == 1) {
    out.radius = 1.0f;
  } else {
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      double nearest = std::numeric_limits<double>::infinity();
      for (std::size_t l = 0; l < n; ++l)
        if (l != k) nearest = std::min(nearest, d2(Eigen::Index(k), Eigen::Index(l)));
      sum += std::sqrt(nearest);
    }
    out.radius = float(sum / double(n));
  }
  Eigen::MatrixXd phi(size, size);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t l = 0; l < n; ++l)
      phi(Eigen::Index(k), Eigen::Index(l)) =
          rbf_kernel(out.kernel, float(d2(Eigen::Index(k), Eigen::Index(l))), out.radius) +
          (k == l ? settings.regularization : 0.0f);
  Eigen::MatrixXd t(size, static_cast<Eigen::Index>(shape_count));
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t s = 0; s < shape_count; ++s) t(Eigen::Index(k), Eigen::Index(s)) = targets[k * shape_count + s];
  const Eigen::MatrixXd c = phi.fullPivLu().solve(t);
  out.coefficients.resize(n * shape_count);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t s = 0; s < shape_count; ++s) {
      const double value = c(Eigen::Index(k), Eigen::Index(s));
      if (!std::isfinite(value)) throw Error::invalid_argument("samples", "the kernel matrix cannot be solved");
      out.coefficients[k * shape_count + s] = float(value);
    }
  return out;
}

MorphTarget corrective_from_sculpt(const Model& model, std::span<const glm::mat4> palette,
                                   std::span<const glm::vec3> sculpted, float tolerance, const std::string& name) {
  const std::size_t points = model.mesh.point_count();
  if (sculpted.size() != points) throw Error::invalid_argument("sculpted", "expected one position per mesh point");
  if (model.weights.size() != points) throw Error::invalid_argument("model", "the weights are not one per point");
  if (!(tolerance >= 0.0f) || !std::isfinite(tolerance))
    throw Error::invalid_argument("tolerance", "must be finite and >= 0");
  for (const glm::mat4& m : palette)
    if (!finite(m)) throw Error::invalid_argument("palette", "a matrix is not finite");
  const SkinWeights& w = model.weights;
  MorphTarget target;
  target.name = name;
  for (std::size_t p = 0; p < points; ++p) {
    if (!finite(sculpted[p]))
      throw Error::invalid_argument("sculpted", "point " + std::to_string(p) + " is not finite");
    // The point's blended matrix over every influence (the four slots and the extras), in double.
    glm::dmat4 blended(0.0);
    const auto add = [&](std::uint16_t bone, float weight) {
      if (weight == 0.0f) return;
      if (bone >= palette.size())
        throw Error::invalid_argument(
            "palette", "point " + std::to_string(p) + "'s bone " + std::to_string(bone) + " is beyond the palette");
      blended += double(weight) * glm::dmat4(palette[bone]);
    };
    for (int k = 0; k < 4; ++k) add(w.bones[p][k], w.weights[p][k]);
    const auto it = std::lower_bound(w.extra_points.begin(), w.extra_points.end(), std::uint32_t(p));
    if (it != w.extra_points.end() && *it == p) {
      const std::size_t j = std::size_t(it - w.extra_points.begin());
      for (std::uint32_t e = w.extra_offsets[j]; e < w.extra_offsets[j + 1]; ++e)
        add(w.extra_bones[e], w.extra_weights[e]);
    }
    const glm::dvec3 rest(model.mesh.positions[p]);
    const glm::dvec3 skinned = glm::dvec3(blended * glm::dvec4(rest, 1.0));
    const glm::dmat3 a(blended);
    const double det = glm::determinant(a);
    if (!(std::abs(det) > 1e-12))
      throw Error::invalid_argument("point " + std::to_string(p), "its blended skinning matrix cannot be inverted");
    const glm::vec3 delta(glm::inverse(a) * (glm::dvec3(sculpted[p]) - skinned));
    if (glm::length(delta) <= tolerance) continue;
    target.points.push_back(std::uint32_t(p));
    target.position_deltas.push_back(delta);
  }
  return target;
}

PoseDriverBinding bind_corrective(const CorrectiveSpec& spec, const Skeleton& skeleton) {
  const std::string group = "corrective group '" + spec.name + "'";
  if (spec.shapes.empty()) throw Error::invalid_argument(group, "has no shape");
  std::vector<Pose> samples;
  if (spec.rest) samples.push_back(skeleton.bind_pose());
  for (const CorrectiveShape& shape : spec.shapes) {
    if (shape.pose.size() != spec.bones.size())
      throw Error::invalid_argument(group, "shape '" + shape.name + "' does not give one rotation per driver bone");
    Pose pose = skeleton.bind_pose();
    for (std::size_t j = 0; j < spec.bones.size(); ++j) {
      if (spec.bones[j] < 0 || std::size_t(spec.bones[j]) >= skeleton.bone_count())
        throw Error::invalid_argument(group, "a driver bone is not in the skeleton");
      if (!finite(shape.pose[j])) throw Error::invalid_argument(group, "shape '" + shape.name + "' has a bad angle");
      pose.rotations[std::size_t(spec.bones[j])] = quat_from_euler(shape.pose[j]);
    }
    samples.push_back(std::move(pose));
  }
  const std::size_t shapes = spec.shapes.size();
  std::vector<float> targets(samples.size() * shapes, 0.0f);
  for (std::size_t s = 0; s < shapes; ++s) targets[(spec.rest ? s + 1 : s) * shapes + s] = 1.0f;
  PoseDriverSettings settings;
  settings.kernel = spec.kernel;
  settings.radius = spec.radius;
  settings.twist_weight = spec.twist_weight;
  try {
    return bind_pose_driver(skeleton, spec.bones, samples, targets, shapes, settings);
  } catch (const Error& e) {
    throw Error::invalid_argument(group, e.what());
  }
}

}  // namespace deform
