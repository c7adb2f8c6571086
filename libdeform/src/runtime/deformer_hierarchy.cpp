// Elastic lattices bound to bones, and the hierarchy that makes a stretched lattice carry what lies below it.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/prefetch.hpp"
#include "finite.hpp"

namespace deform {
namespace {

glm::vec3 transform_point(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

// The smallest length ratio volume compensation reads (a floorless lattice squashed past zero stays finite).
constexpr float min_volume_ratio = 0.01f;

// Per slice along U (the control points with one index i; i-fastest over `counts`): its points' mean, e.g. the centre
// of the rest, where an affine forcing's value is its slice mean. No division per point (a slice is every counts.x-th
// point from i).
using Slices = std::array<glm::vec3, max_bezier_degree + 1>;
void slice_means(std::span<const glm::vec3> points, glm::ivec3 counts, Slices& means) noexcept {
  const auto slices = std::size_t(counts.x);
  for (std::size_t i = 0; i < slices; ++i) means[i] = glm::vec3(0.0f);
  for (std::size_t n = 0; n < points.size(); n += slices)
    for (std::size_t i = 0; i < slices; ++i) means[i] += points[n + i];
  const float per_slice = 1.0f / float(counts.y * counts.z);
  for (std::size_t i = 0; i < slices; ++i) means[i] *= per_slice;
}

// Splits each slice's forcing (or impulse) `f` into its part across the bone `axis`, kept in `f`, and along it,
// written to `along`; the last slice's (the far face's) both scaled by `far_weight`.
void split_slices(Slices& f, std::size_t slices, glm::vec3 axis, float far_weight,
                  std::array<float, max_bezier_degree + 1>& along) noexcept {
  f[slices - 1] *= far_weight;
  for (std::size_t i = 0; i < slices; ++i) {
    along[i] = glm::dot(f[i], axis);
    f[i] -= axis * along[i];
  }
}

// Every point gets its slice's value.
void fill_slices(std::span<glm::vec3> points, std::size_t slices, const Slices& values) noexcept {
  for (std::size_t n = 0; n < points.size(); n += slices)
    for (std::size_t i = 0; i < slices; ++i) points[n + i] = values[i];
}

}  // namespace

float soft_length_floor(float ratio, float min_fraction) noexcept {
  if (!(min_fraction > 0.0f)) return ratio;
  const float knee = (1.0f - min_fraction) / 3.0f;
  const float bend = min_fraction + knee;
  if (ratio >= bend) return ratio;
  return min_fraction + knee * std::exp((ratio - bend) / knee);
}

void require_valid_shape(const StretchShape& shape) {
  if (!(shape.min_length_fraction >= 0.0f && shape.min_length_fraction < 1.0f))
    throw Error::invalid_argument("<stretch shape>", "shape min_length_fraction must be in [0, 1)");
  if (!(shape.volume >= 0.0f && shape.volume <= 1.0f))
    throw Error::invalid_argument("<stretch shape>", "shape volume must be in [0, 1]");
}

void require_valid_motion(const LatticeMotion& motion) {
  if (!(motion.inertia >= 0.0f && motion.inertia <= 1.0f))
    throw Error::invalid_argument("<lattice motion>", "motion inertia must be in [0, 1]");
  // Bounds far beyond any character, so that their product cannot overflow a float.
  if (!finite(motion.gravity) || !(glm::length(motion.gravity) <= 1e6f))
    throw Error::invalid_argument("<lattice motion>", "motion gravity must be finite and at most 1e6 m/s²");
  if (!(motion.units_per_metre > 0.0f && motion.units_per_metre <= 1e6f))
    throw Error::invalid_argument("<lattice motion>", "motion units_per_metre must be in (0, 1e6]");
  if (!(motion.along_bound >= 0.0f && motion.along_bound <= 1.0f))
    throw Error::invalid_argument("<lattice motion>", "motion along_bound must be in [0, 1]");
  if (!(motion.far_share >= 0.0f && motion.far_share <= 1.0f))
    throw Error::invalid_argument("<lattice motion>", "motion far_share must be in [0, 1]");
  if (body_part_name(motion.part).empty())
    throw Error::invalid_argument("<lattice motion>", "motion part is not a BodyPart");
}

LatticeMotion default_lattice_motion(BodyPart part) noexcept {
  // {inertia, gravity, units_per_metre, along_bound, far_share, part}: measured on the built-in walk and run by
  // tests/character/secondary_motion_test.cpp ("flesh: ...") and tools/motion_study --flesh-csv, and on imported
  // clips with default_rig (the same file, "flesh on imported characters").
  const glm::vec3 none(0.0f);
  switch (part) {
    case BodyPart::upper_limb: return {0.3f, none, 1.0f, 0.02f, 0.0f, part};
    case BodyPart::lower_limb: return {0.3f, none, 1.0f, 0.02f, 0.0f, part};
    case BodyPart::hand: return {0.2f, none, 1.0f, 0.02f, 1.0f, part};
    case BodyPart::foot: return {0.1f, none, 1.0f, 0.01f, 0.0f, part};
    case BodyPart::torso: return {0.4f, none, 1.0f, 0.02f, 0.0f, part};
    case BodyPart::head: return {0.1f, none, 1.0f, 0.01f, 0.0f, part};
    case BodyPart::appendage: return {0.8f, none, 1.0f, 0.05f, 1.0f, part};
    case BodyPart::unspecified: break;
  }
  // What a lattice with no part had before parts existed: the defaults, the knob (scaled_inertia) its inertia.
  LatticeMotion motion;
  motion.inertia = 1.0f;
  return motion;
}

float scaled_inertia(BodyPart part, float scale) {
  if (!(scale >= 0.0f && scale <= 1.0f))
    throw Error::invalid_argument("<lattice motion>", "inertia scale must be in [0, 1]");
  if (body_part_name(part).empty()) throw Error::invalid_argument("<lattice motion>", "motion part is not a BodyPart");
  return scale * default_lattice_motion(part).inertia;  // a tuned inertia is in [0, 1]: so is the product
}

namespace {
constexpr std::array<std::pair<BodyPart, std::string_view>, 8> body_part_names{{
    {BodyPart::upper_limb, "upper_limb"},
    {BodyPart::lower_limb, "lower_limb"},
    {BodyPart::hand, "hand"},
    {BodyPart::foot, "foot"},
    {BodyPart::torso, "torso"},
    {BodyPart::head, "head"},
    {BodyPart::appendage, "appendage"},
    {BodyPart::unspecified, "unspecified"},
}};
}  // namespace

std::string_view body_part_name(BodyPart part) noexcept {
  for (const auto& [p, name] : body_part_names)
    if (p == part) return name;
  return {};
}

std::optional<BodyPart> body_part_named(std::string_view name) noexcept {
  if (name.empty()) return std::nullopt;
  for (const auto& [p, n] : body_part_names)
    if (n == name) return p;
  return std::nullopt;
}

DeformerHierarchy::DeformerHierarchy(const Skeleton& skeleton, std::vector<BoundLattice> lattices,
                                     std::size_t point_count)
    : point_count_(point_count) {
  bone_parents_.reserve(skeleton.bone_count());
  for (const Bone& bone : skeleton.bones()) bone_parents_.push_back(bone.parent);
  lattices_.reserve(lattices.size());
  for (BoundLattice& bound : lattices) {
    const std::string element = "lattice '" + bound.spec.name + "'";
    if (bound.spec.bone < 0 || std::size_t(bound.spec.bone) >= skeleton.bone_count()) {
      throw Error::invalid_argument(element, "bone is out of range");
    }
    try {
      require_valid_shape(bound.spec.shape);
      require_valid_motion(bound.spec.motion);
    } catch (const Error& error) {
      throw Error::invalid_argument(element, error.message());
    }
    const LatticeBinding& binding = bound.binding;
    if (binding.kind != LatticeKind::bezier || binding.point_counts != bound.rest.point_counts() ||
        bound.lane_weights.size() != binding.vertices.size() ||
        (binding.vertex_count > 0 && binding.max_vertex >= point_count) ||
        bound.carried_points.size() != bound.carried_weights.size() || !(bound.length > 0.0f)) {
      throw Error::invalid_argument(element, "binding does not fit its rest lattice or the mesh");
    }
    for (std::uint32_t p : bound.carried_points) {
      if (p >= point_count) throw Error::invalid_argument(element, "a carried point is out of range");
    }
    Lattice lattice;
    lattice.spec = std::move(bound.spec);
    lattice.rest = std::move(bound.rest);
    lattice.axis = bound.axis;
    lattice.length = bound.length;
    auto shared = std::make_shared<Binding>();
    shared->binding = std::move(bound.binding);
    shared->lane_weights = std::move(bound.lane_weights);
    shared->carried_points = std::move(bound.carried_points);
    shared->carried_weights = std::move(bound.carried_weights);
    lattice.bind_world = skeleton.bind_world()[std::size_t(lattice.spec.bone)];
    lattice.inverse_bind_world = skeleton.inverse_bind_world()[std::size_t(lattice.spec.bone)];
    lattice.field = lattice.rest;
    for (int i = 0; i < lattice.rest.point_counts().x; ++i)
      for (int k = 0; k < lattice.rest.point_counts().z; ++k)
        for (int j = 0; j < lattice.rest.point_counts().y; ++j)
          shared->slice_along[std::size_t(i)] +=
              glm::dot(lattice.rest.control_points()[lattice.rest.index(i, j, k)], lattice.axis);
    for (const glm::vec3& x : lattice.rest.control_points())
      shared->radial.push_back(x - lattice.axis * glm::dot(x, lattice.axis));

    // The springs: the first face pinned, the last face read as one rigid translation.
    const glm::ivec3 counts = lattice.rest.point_counts();
    std::vector<std::uint8_t> pinned(lattice.rest.point_count(), 0);
    for (int k = 0; k < counts.z; ++k) {
      for (int j = 0; j < counts.y; ++j) {
        pinned[lattice.rest.index(0, j, k)] = 1;
        lattice.far_face.push_back(std::uint32_t(lattice.rest.index(counts.x - 1, j, k)));
      }
    }
    lattice.elastic = ElasticLattice(lattice.rest.control_points(), lattice.spec.elastic, counts);
    lattice.elastic.set_pinned(pinned);
    lattice.target_points.assign(lattice.rest.control_points().begin(), lattice.rest.control_points().end());
    std::fill(lattice.field.control_points().begin(), lattice.field.control_points().end(), glm::vec3(0.0f));
    lattice.world_points.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    lattice.mapped_points.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    // A rest lattice on its frame's regular grid is the affine map X(u, v, w) of the frame, whose Jacobian is the
    // frame's edges: apply() with normals then needs one evaluation, not two.
    lattice.regular_rest = true;
    for (int k = 0; k < counts.z; ++k)
      for (int j = 0; j < counts.y; ++j)
        for (int i = 0; i < counts.x; ++i)
          lattice.regular_rest = lattice.regular_rest && lattice.rest.control_points()[lattice.rest.index(i, j, k)] ==
                                                             lattice.rest.rest_point(i, j, k);
    lattice.rest_velocity.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    lattice.accel_start.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    lattice.accel_end.assign(lattice.rest.point_count(), glm::vec3(0.0f));
    lattice.bound = std::move(shared);
    lattices_.push_back(std::move(lattice));
  }

  for (Lattice& lattice : lattices_) {
    for (std::int32_t b = bone_parents_[std::size_t(lattice.spec.bone)]; b >= 0 && lattice.parent < 0;
         b = bone_parents_[std::size_t(b)]) {
      for (std::size_t other = 0; other < lattices_.size(); ++other) {
        if (lattices_[other].spec.bone == b) {
          lattice.parent = std::int32_t(other);
          break;
        }
      }
    }
  }
  std::vector<glm::mat4> world(skeleton.bind_world().begin(), skeleton.bind_world().end());
  update(world);
}

bool DeformerHierarchy::is_ancestor(std::int32_t ancestor, std::int32_t bone) const noexcept {
  for (std::int32_t b = bone; b >= 0 && std::size_t(b) < bone_parents_.size(); b = bone_parents_[std::size_t(b)]) {
    if (b == ancestor) return true;
  }
  return false;
}

std::int32_t DeformerHierarchy::find(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < lattices_.size(); ++i) {
    if (lattices_[i].spec.name == name) return std::int32_t(i);
  }
  return -1;
}

void DeformerHierarchy::stretch_points(Lattice& lattice) const {
  const glm::ivec3 counts = lattice.rest.point_counts();
  const float last = float(counts.x - 1);
  for (int k = 0; k < counts.z; ++k) {
    for (int j = 0; j < counts.y; ++j) {
      for (int i = 0; i < counts.x; ++i) {
        const std::size_t n = lattice.rest.index(i, j, k);
        lattice.target_points[n] = lattice.rest.control_points()[n] + lattice.axis * (lattice.target * float(i) / last);
      }
    }
  }
}

Status DeformerHierarchy::set_stretch_target(std::size_t index, float stretch) {
  if (index >= lattices_.size()) return Status::failure("lattice index out of range");
  Lattice& lattice = lattices_[index];
  if (!std::isfinite(stretch) || !(stretch > -lattice.length))
    return Status::failure("stretch not finite and > -length");
  lattice.target = stretch;
  stretch_points(lattice);
  return {};
}

Status DeformerHierarchy::restart_motion(std::size_t index) noexcept {
  if (index >= lattices_.size()) return Status::failure("lattice index out of range");
  lattices_[index].motion_known = false;
  return {};
}

float DeformerHierarchy::stretch(std::size_t index) const noexcept {
  const Lattice& lattice = lattices_[index];
  float sum = 0.0f;
  for (std::uint32_t n : lattice.far_face) {
    sum += glm::dot(lattice.elastic.positions()[n] - lattice.rest.control_points()[n], lattice.axis);
  }
  SliceShape slices;
  shape_slices(lattice, slices);
  std::array<float, max_bezier_degree + 1> along;
  along_shown(lattice, along);
  const auto last = std::size_t(lattice.rest.point_counts().x - 1);
  return sum / float(lattice.far_face.size()) + along[last] + slices.shift[last];
}

void DeformerHierarchy::along_shown(const Lattice& lattice, std::array<float, max_bezier_degree + 1>& shown) noexcept {
  // b·tanh(z / b): the oscillator's offset for small z, never beyond b (b = 0 shows nothing).
  const float bound = lattice.spec.motion.along_bound * lattice.length;
  for (std::size_t i = 0; i < shown.size(); ++i) {
    const float z = lattice.along_offset[i];
    shown[i] = bound > 0.0f && z != 0.0f ? bound * std::tanh(z / bound) : 0.0f;
  }
}

void DeformerHierarchy::step_along(Lattice& lattice, float dt, const std::array<float, max_bezier_degree + 1>& start,
                                   const std::array<float, max_bezier_degree + 1>& end) noexcept {
  if (!(dt > 0.0f)) return;
  if (double(dt) != lattice.along_dt) {  // a fixed frame rate computes the maps once
    lattice.along_step = oscillator_step(lattice.spec.elastic.oscillator, dt);
    lattice.along_forced = forced_step(lattice.spec.elastic.oscillator, dt);
    lattice.along_dt = dt;
  }
  const OscillatorStep& m = lattice.along_step;
  const ForcedStep& f = lattice.along_forced;
  for (std::size_t i = 1; i < std::size_t(lattice.rest.point_counts().x); ++i) {
    const double z = lattice.along_offset[i], u = lattice.along_velocity[i];
    lattice.along_offset[i] = float(m.position_from_offset * z + m.position_from_velocity * u +
                                    f.position_from_start * start[i] + f.position_from_end * end[i]);
    lattice.along_velocity[i] = float(m.velocity_from_offset * z + m.velocity_from_velocity * u +
                                      f.velocity_from_start * start[i] + f.velocity_from_end * end[i]);
  }
}

void DeformerHierarchy::shape_slices(const Lattice& lattice, SliceShape& slices) noexcept {
  const glm::ivec3 counts = lattice.rest.point_counts();
  const auto last = std::size_t(counts.x - 1);
  if (lattice.spec.shape.min_length_fraction == 0.0f && lattice.spec.shape.volume == 0.0f) {  // the plain stretch
    slices.shift.fill(0.0f);
    slices.scale.fill(1.0f);
    return;
  }
  const float per_slice = float(counts.y * counts.z);
  const std::span<const glm::vec3> rest = lattice.rest.control_points();
  const std::span<const glm::vec3> now = lattice.elastic.positions();
  // Rest position (bind time) and displacement along the bone, slice sums; the far face's mean is its rigid
  // translation's.
  const std::array<float, max_bezier_degree + 1>& along = lattice.bound->slice_along;
  std::array<float, max_bezier_degree + 1> moved{};
  along_shown(lattice, moved);  // what the motion shows along the bone, per point of the slice
  for (std::size_t i = 0; i <= last; ++i) moved[i] *= per_slice;
  for (int k = 0; k < counts.z; ++k) {
    for (int j = 0; j < counts.y; ++j) {
      for (std::size_t i = 0; i <= last; ++i) {
        const std::size_t n = lattice.rest.index(int(i), j, k);
        moved[i] += glm::dot(now[n] - rest[n], lattice.axis);
      }
    }
  }
  // A segment the floor leaves alone adds no shift, exactly: a lattice that never shortens that far moves as before.
  std::array<float, max_bezier_degree + 1> ratio{};
  slices.shift[0] = 0.0f;
  for (std::size_t i = 1; i <= last; ++i) {
    const float rest_length = (along[i] - along[i - 1]) / per_slice;
    const float springs = (rest_length + (moved[i] - moved[i - 1]) / per_slice) / rest_length;
    ratio[i] = soft_length_floor(springs, lattice.spec.shape.min_length_fraction);
    slices.shift[i] = slices.shift[i - 1] + (ratio[i] == springs ? 0.0f : (ratio[i] - springs) * rest_length);
  }
  const float volume = lattice.spec.shape.volume;
  for (std::size_t i = 0; i <= last; ++i) {
    const float s = i == 0 ? ratio[1] : i == last ? ratio[last] : 0.5f * (ratio[i] + ratio[i + 1]);
    // s^(-volume/2); for full compensation (the default) 1/√s, to float rounding, without a pow.
    const float ratio_s = std::max(s, min_volume_ratio);
    slices.scale[i] = volume == 1.0f  ? 1.0f / std::sqrt(ratio_s)
                      : volume > 0.0f ? std::pow(ratio_s, -0.5f * volume)
                                      : 1.0f;
  }
}

DeformerHierarchy::Lattice& DeformerHierarchy::configured(std::size_t index) {
  if (index >= lattices_.size())
    throw Error::invalid_argument("lattice " + std::to_string(index), "lattice index out of range");
  return lattices_[index];
}

void DeformerHierarchy::set_shape(std::size_t index, const StretchShape& shape) {
  Lattice& lattice = configured(index);
  require_valid_shape(shape);
  lattice.spec.shape = shape;
}

void DeformerHierarchy::set_elastic(std::size_t index, const ElasticSettings& settings) {
  Lattice& lattice = configured(index);
  lattice.elastic.set_settings(settings);
  lattice.spec.elastic = settings;
  lattice.along_dt = -1.0;
}

Status DeformerHierarchy::step(float dt) {
  if (!(dt >= 0.0f) || !std::isfinite(dt)) return Status::failure("dt is negative or not finite");
  for (Lattice& lattice : lattices_)
    if (const Status status = step_lattice(lattice, dt, nullptr, nullptr); !status) return status;
  return {};
}

Status DeformerHierarchy::step(float dt, std::span<const glm::mat4> world, std::span<const glm::mat4> world_rate) {
  if (!(dt >= 0.0f) || !std::isfinite(dt)) return Status::failure("dt is negative or not finite");
  if (world.size() != bone_parents_.size()) return Status::failure("world does not have one entry per bone");
  if (!world_rate.empty() && world_rate.size() != bone_parents_.size())
    return Status::failure("world_rate is neither empty nor one per bone");
  for (Lattice& lattice : lattices_) {
    const auto bone = std::size_t(lattice.spec.bone);
    if (const Status status = step_lattice(lattice, dt, &world[bone], world_rate.empty() ? nullptr : &world_rate[bone]);
        !status)
      return status;
  }
  return {};
}

Status DeformerHierarchy::step_lattice(Lattice& lattice, float dt, const glm::mat4* world, const glm::mat4* rate) {
  // With dt checked, a lattice's step cannot refuse: its target and acceleration arrays were sized with it.
  const LatticeMotion& motion = lattice.spec.motion;
  if (!motion.active()) {
    // Motion switched off (set_motion) lets the along oscillators settle as the springs do.
    if (std::any_of(lattice.along_offset.begin(), lattice.along_offset.end(), [](float z) { return z != 0.0f; }) ||
        std::any_of(lattice.along_velocity.begin(), lattice.along_velocity.end(), [](float u) { return u != 0.0f; }))
      step_along(lattice, dt, {}, {});
    return lattice.elastic.step(dt, lattice.target_points);
  }
  // Everything in the bone's frame: the rest's world acceleration taken back by the bone's inverse 3×3, gravity by
  // the same and rescaled by the bone's scale (so a scaled character moves the same way, scaled).
  const glm::mat4 now = world != nullptr ? *world : lattice.motion_known ? lattice.motion_world : lattice.bind_world;
  if (!lattice.motion_known || world == nullptr) {
    // The first step, or bones held still: the motion starts as it is now, with no jolt — a rate given now is the
    // step's starting rate, and without one the first step's own velocity is (rest_velocity_known).
    lattice.motion_world = now;
    lattice.rate_known = rate != nullptr;
    if (rate != nullptr) lattice.motion_rate = *rate;
    lattice.rest_velocity_known = false;
    lattice.motion_known = world != nullptr;
  }
  const glm::mat4 before = lattice.motion_world;
  // A bone squashed flat has no frame to feel motion in: the springs then step as if it were still.
  const auto invertible = [](const glm::mat4& m) {
    const float det = glm::determinant(glm::mat3(m));
    return std::isfinite(det) && std::abs(det) > 1e-30f;
  };
  std::array<float, max_bezier_degree + 1> along_start{}, along_end{};
  const glm::ivec3 counts = lattice.rest.point_counts();
  const float far_weight = lattice.bound->carried_points.empty() ? 1.0f : motion.far_share;
  if (!invertible(before) || !invertible(now) || (rate != nullptr && !finite(*rate))) {
    lattice.motion_known = false;
    step_along(lattice, dt, along_start, along_end);
    return lattice.elastic.step(dt, lattice.target_points);
  }
  const glm::mat3 inverse_before = glm::inverse(glm::mat3(before));
  const glm::mat3 inverse_now = glm::inverse(glm::mat3(now));
  const auto scale = [](const glm::mat4& m) { return std::cbrt(std::abs(glm::determinant(glm::mat3(m)))); };
  const glm::vec3 gravity = motion.gravity * motion.units_per_metre;
  const glm::vec3 gravity_before = inverse_before * (gravity * scale(before));
  const glm::vec3 gravity_now = inverse_now * (gravity * scale(now));
  const float inertia = motion.inertia;
  const auto slices = std::size_t(counts.x);
  // The forcing is affine in the point and taken per slice (LatticeMotion): its value at each slice's centre.
  Slices centre, force_at_start, force_at_end;
  slice_means(lattice.target_points, counts, centre);
  for (std::size_t i = 0; i < slices; ++i) force_at_start[i] = gravity_before, force_at_end[i] = gravity_now;
  if (dt > 0.0f && rate != nullptr && inertia > 0.0f) {
    // The rest moves along the cubic through its positions and velocities at the two ends: its acceleration is linear
    // over the step, which the exact integrator follows exactly. The cubic's end accelerations are linear in the
    // point (hermite_accelerations of M·x and Ṁ·x), so each end's forcing is one affine map per lattice.
    const glm::mat4 rate_before = lattice.rate_known ? lattice.motion_rate : *rate;
    const float h = dt;
    const glm::mat4 chord = (now - before) * (6.0f / (h * h));
    const glm::mat4 start = chord - (4.0f * rate_before + 2.0f * *rate) * (1.0f / h);
    const glm::mat4 end = (2.0f * rate_before + 4.0f * *rate) * (1.0f / h) - chord;
    const glm::mat4 force_start = glm::mat4(-inertia * inverse_before) * start;  // rows 0-2 used, bottom row 0
    const glm::mat4 force_end = glm::mat4(-inertia * inverse_now) * end;
    for (std::size_t i = 0; i < slices; ++i) {
      const glm::vec4 x(centre[i], 1.0f);
      force_at_start[i] += glm::vec3(force_start * x);
      force_at_end[i] += glm::vec3(force_end * x);
    }
  } else if (dt > 0.0f && inertia > 0.0f) {
    // The rest moves linearly within the step: its velocity changes at the step's start, an impulse of minus λ times
    // that change on the points' velocities (in the bone's frame); per slice, as the forcing.
    Slices impulse;
    std::array<float, max_bezier_degree + 1> along_impulse{};
    for (std::size_t i = 0; i < slices; ++i) {
      const glm::vec4 x(centre[i], 1.0f);
      const glm::vec3 velocity = glm::vec3(now * x - before * x) / dt;
      const glm::vec3 change = lattice.rest_velocity_known ? velocity - lattice.rest_velocity[i] : glm::vec3(0.0f);
      impulse[i] = -inertia * (inverse_before * change);
      lattice.rest_velocity[i] = velocity;
    }
    split_slices(impulse, slices, lattice.axis, far_weight, along_impulse);
    fill_slices(lattice.accel_start, slices, impulse);
    lattice.elastic.add_velocity(lattice.accel_start);
    for (std::size_t i = 1; i < slices; ++i) lattice.along_velocity[i] += along_impulse[i];
  }
  if (dt > 0.0f) {
    lattice.motion_world = now;
    lattice.rest_velocity_known = rate == nullptr && inertia > 0.0f;  // what the linear path above left
    lattice.rate_known = rate != nullptr;
    if (rate != nullptr) lattice.motion_rate = *rate;
  } else if (world != nullptr) {  // a pose changed without time passing is a jump, not a motion
    lattice.motion_world = now;
    lattice.rate_known = rate != nullptr;
    if (rate != nullptr) lattice.motion_rate = *rate;
    lattice.rest_velocity_known = false;
  }
  split_slices(force_at_start, slices, lattice.axis, far_weight, along_start);
  split_slices(force_at_end, slices, lattice.axis, far_weight, along_end);
  fill_slices(lattice.accel_start, slices, force_at_start);
  fill_slices(lattice.accel_end, slices, force_at_end);
  step_along(lattice, dt, along_start, along_end);
  return lattice.elastic.step(dt, lattice.target_points, lattice.accel_start, lattice.accel_end);
}

void DeformerHierarchy::set_motion(std::size_t index, const LatticeMotion& motion) {
  Lattice& lattice = configured(index);
  require_valid_motion(motion);
  lattice.spec.motion = motion;
}

void DeformerHierarchy::set_inertia_scale(float scale) {
  for (Lattice& lattice : lattices_) (void)scaled_inertia(lattice.spec.motion.part, scale);  // before any changes
  for (Lattice& lattice : lattices_) lattice.spec.motion.inertia = scaled_inertia(lattice.spec.motion.part, scale);
}

void DeformerHierarchy::reset() {
  for (Lattice& lattice : lattices_) {
    lattice.target = 0.0f;
    stretch_points(lattice);
    lattice.elastic.reset(lattice.rest.control_points());
    lattice.along_offset.fill(0.0f);
    lattice.along_velocity.fill(0.0f);
    lattice.motion_known = false;
    lattice.rate_known = false;
  }
}

void DeformerHierarchy::prefetch() const noexcept {
  prefetch_span(lattices_);
  for (const Lattice& lattice : lattices_) {
    lattice.elastic.prefetch();
    prefetch_span(lattice.rest.control_points());
    prefetch_span(lattice.field.control_points());
    prefetch_span(lattice.far_face);
    prefetch_span(lattice.target_points);
    if (lattice.spec.motion.active()) {
      prefetch_span(lattice.rest_velocity);
      prefetch_span(lattice.accel_start);
      prefetch_span(lattice.accel_end);
    }
  }
}

Status DeformerHierarchy::update(std::span<const glm::mat4> world) {
  if (world.size() != bone_parents_.size()) return Status::failure("world does not have one entry per bone");
  SliceShape slices;
  for (Lattice& lattice : lattices_) {
    const std::span<const glm::vec3> rest = lattice.rest.control_points();
    const std::span<const glm::vec3> now = lattice.elastic.positions();
    const glm::ivec3 counts = lattice.rest.point_counts();
    const auto last = std::size_t(counts.x - 1);
    glm::vec3 far(0.0f);
    for (std::uint32_t n : lattice.far_face) far += now[n] - rest[n];
    far /= float(lattice.far_face.size());
    shape_slices(lattice, slices);
    std::array<float, max_bezier_degree + 1> motion_along;
    along_shown(lattice, motion_along);
    const glm::mat3 linear(world[std::size_t(lattice.spec.bone)]);
    lattice.linear = linear;
    const float still = 1e-7f * lattice.length;
    const std::span<glm::vec3> displacements = lattice.field.control_points();
    const std::vector<glm::vec3>& radial = lattice.bound->radial;
    std::array<glm::vec3, max_bezier_degree + 1> along;  // per slice: its shift along the bone
    for (std::size_t i = 0; i <= last; ++i) along[i] = lattice.axis * (slices.shift[i] + motion_along[i]);
    for (int k = 0; k < counts.z; ++k) {
      for (int j = 0; j < counts.y; ++j) {
        for (std::size_t i = 0; i <= last; ++i) {
          const std::size_t n = lattice.rest.index(int(i), j, k);
          const glm::vec3 local =
              (i == last ? far : now[n] - rest[n]) + along[i] + radial[n] * (slices.scale[i] - 1.0f);
          displacements[n] = linear * local;
        }
      }
    }
    lattice.far_displacement = linear * (far + along[last]);
    const float still2 = still * still;
    bool active = glm::dot(lattice.far_displacement, lattice.far_displacement) > still2;
    for (const glm::vec3& d : displacements) active = active || glm::dot(d, d) > still2;  // most stop at once
    lattice.active = active;
    lattice.bone_world = world[std::size_t(lattice.spec.bone)];
  }
  drawing_current_ = false;  // control_points() computes them when asked: an engine frame never draws lattices
  return {};
}

std::span<const glm::vec3> DeformerHierarchy::control_points(std::size_t index) const noexcept {
  const Lattice& wanted = lattices_[index];
  if (!drawing_current_) {
    // Every lattice's field is known, so each can be carried by those above it.
    for (const Lattice& lattice : lattices_) {
      const glm::vec3 carried = point_displacement(lattice.spec.bone, glm::vec3(lattice.bind_world[3]));
      const std::span<const glm::vec3> rest = lattice.rest.control_points();
      for (std::size_t n = 0; n < rest.size(); ++n) {
        lattice.world_points[n] =
            transform_point(lattice.bone_world, rest[n]) + lattice.field.control_points()[n] + carried;
      }
    }
    drawing_current_ = true;
  }
  return wanted.world_points;
}

Status DeformerHierarchy::apply_carried(std::span<glm::vec3> positions) {
  if (positions.size() != point_count_) return Status::failure("positions do not have one entry per point");
  for (const Lattice& lattice : lattices_) {
    if (!lattice.active) continue;
    // Locals, not members: a store to `positions` could alias them, and reloading them after every store made
    // this loop wait on each one (three times slower).
    const glm::vec3 far = lattice.far_displacement;
    const std::uint32_t* points = lattice.bound->carried_points.data();
    const float* weights = lattice.bound->carried_weights.data();
    const std::size_t count = lattice.bound->carried_points.size();
    for (std::size_t n = 0; n < count; ++n) positions[points[n]] += weights[n] * far;
  }
  return {};
}

LatticeEvaluateJob DeformerHierarchy::field_job(const Lattice& lattice, std::span<glm::vec3> positions) {
  LatticeEvaluateJob job;
  job.binding = &lattice.bound->binding;
  job.control_points = lattice.field.control_points();
  job.positions = positions;
  job.weights = lattice.bound->lane_weights;
  return job;
}

Status DeformerHierarchy::apply(std::span<glm::vec3> positions) {
  if (positions.size() != point_count_) return Status::failure("positions do not have one entry per point");
  // The constructor checked every binding against its lattice and the points, and the control point arrays are
  // sized with the lattice, so no field can refuse: their O(bound points) validate() stays out of the frame, as
  // lattice.hpp promises ("once per binding"). Only the points' count is the caller's, checked above.
  apply_carried(positions);
  for (const Lattice& lattice : lattices_)
    if (lattice.active) field_job(lattice, positions).run();
  return {};
}

Status DeformerHierarchy::apply(std::span<glm::vec3> positions, std::span<glm::vec3> normals) {
  if (positions.size() != point_count_ || normals.size() != point_count_)
    return Status::failure("positions and normals do not have one entry per point");
  // The constructor checked every binding against its lattice and the points, and the control point arrays are
  // sized with the lattice, so no job can refuse: their O(bound points) validate() stays out of the frame. Only the
  // points' count is the caller's, checked above.
  apply_carried(positions);
  for (std::size_t l = 0; l < lattices_.size(); ++l) {
    Lattice& lattice = lattices_[l];
    if (!lattice.active) continue;
    LatticeEvaluateJob job = field_job(lattice, positions);
    job.normals_in = normals;
    job.normals_out = normals;
    // The binding takes normals in the bind pose's model space (normals_to_bind).
    job.normals_in_to_binding = normals_to_bind(l);
    if (lattice.regular_rest) {
      // One evaluation: the field's displacements (the same bits as apply()'s: the kernel's sums do not depend on
      // the normals) and the normals of linear · X + D, the Jacobian of linear · X added as an offset.
      const LatticeFrame& frame = lattice.rest.frame();
      job.normals_jacobian_offset = lattice.linear * glm::mat3(frame.u_axis, frame.v_axis, frame.w_axis);
      job.run();
    } else {
      // The displacements exactly as apply() adds them; then the normals of the map linear · X + D, evaluated from
      // its own control points (its positions are not wanted).
      field_job(lattice, positions).run();
      mapped_points(l, lattice.mapped_points);
      job.control_points = lattice.mapped_points;
      job.positions = {};
      job.run();
    }
  }
  return {};
}

void DeformerHierarchy::mapped_points(std::size_t index, std::span<glm::vec3> out) const noexcept {
  const Lattice& lattice = lattices_[index];
  const std::span<const glm::vec3> rest = lattice.rest.control_points();
  if (out.size() != rest.size()) return;
  // The lattice's map without its translation: x (bone bind frame) -> linear · x + D(x), whose Jacobian is the
  // skinned neighbourhood's (linear) times the field's (I + ∂D_local/∂x).
  for (std::size_t n = 0; n < rest.size(); ++n) out[n] = lattice.linear * rest[n] + lattice.field.control_points()[n];
}

glm::mat3 DeformerHierarchy::normals_to_bind(std::size_t index) const noexcept {
  const Lattice& lattice = lattices_[index];
  // The binding takes normals in the bind pose's model space: the skinned normal taken back there by the inverse of
  // its map, cof(linear · inverse bind)⁻¹ ∝ (linear · inverse bind)ᵀ (a positive scale dropped).
  return glm::transpose(lattice.linear * glm::mat3(lattice.inverse_bind_world));
}

glm::vec3 DeformerHierarchy::point_displacement(std::int32_t bone, glm::vec3 bind_point) const noexcept {
  glm::vec3 sum(0.0f);
  for (const Lattice& lattice : lattices_) {
    if (!lattice.active || !is_ancestor(lattice.spec.bone, bone)) continue;
    const glm::vec3 local = transform_point(lattice.inverse_bind_world, bind_point);
    const glm::vec3 uvw = lattice.rest.frame().to_lattice(local);
    if (uvw.x <= 0.0f) continue;
    if (uvw.x >= 1.0f) {
      if (lattice.spec.carry_descendants) sum += lattice.far_displacement;
      continue;
    }
    sum += lattice.field.evaluate(glm::clamp(uvw, glm::vec3(0.0f), glm::vec3(1.0f)));
  }
  return sum;
}

}  // namespace deform
