// Skeleton: hierarchy validation, bind matrices, pose setters and forward kinematics (docs/formats.md).
#include "deform/runtime/skeleton.hpp"
#include <algorithm>
#include <charconv>
#include <cmath>

#include "deform/runtime/error.hpp"
#include "finite.hpp"
#include "skeleton_rules.hpp"

namespace deform {
namespace detail {

std::optional<BoneProblem> find_bone_problem(std::span<const Bone> bones, std::span<std::int32_t> order) {
  using Field = BoneProblem::Field;
  const std::size_t count = bones.size();
  if (count == 0) return BoneProblem{-1, Field::none, "a skeleton needs at least one bone"};
  if (count > max_bones)
    return BoneProblem{-1, Field::none, std::to_string(count) + " bones; at most 65535 are allowed"};
  const auto n = static_cast<std::int32_t>(count);

  for (std::int32_t id = 0; id < n; ++id) {
    const Bone& b = bones[static_cast<std::size_t>(id)];
    if (!finite(b.bind_translation)) return BoneProblem{id, Field::translation, "translation is not finite"};
    if (!finite(b.bind_rotation)) return BoneProblem{id, Field::rotation, "rotation is not finite"};
    if (!finite(b.limits.min) || !finite(b.limits.max)) return BoneProblem{id, Field::limits, "limit is not finite"};
    for (int axis = 0; axis < 3; ++axis)
      if (b.limits.min[axis] > b.limits.max[axis])
        return BoneProblem{id, Field::limits,
                           std::string("limit min > max on axis ") + "xyz"[axis] + " (" +
                               std::to_string(b.limits.min[axis]) + " > " + std::to_string(b.limits.max[axis]) + ")"};
    if (b.parent < -1 || b.parent >= n)
      return BoneProblem{id, Field::parent, "parent " + std::to_string(b.parent) + " is out of range"};
    if (b.parent == id) return BoneProblem{id, Field::parent, "bone is its own parent"};
    if (id == 0 && b.parent != -1)
      return BoneProblem{0, Field::parent,
                         "bone 0 must be the root (parent -1), has parent " + std::to_string(b.parent)};
    if (id != 0 && b.parent == -1) return BoneProblem{id, Field::parent, "a second root (only bone 0 has parent -1)"};
    for (std::int32_t child : b.children)
      if (child < 0 || child >= n)
        return BoneProblem{id, Field::children, "child " + std::to_string(child) + " is out of range"};
  }

  // Child lists must agree with parent ids: every non-root bone listed exactly once, by its parent.
  std::vector<bool> listed(count, false);
  for (std::int32_t id = 0; id < n; ++id)
    for (std::int32_t child : bones[static_cast<std::size_t>(id)].children) {
      const Bone& c = bones[static_cast<std::size_t>(child)];
      if (c.parent != id)
        return BoneProblem{id, Field::children,
                           "lists child " + std::to_string(child) + " whose parent is " + std::to_string(c.parent)};
      if (listed[static_cast<std::size_t>(child)])
        return BoneProblem{id, Field::children, "lists child " + std::to_string(child) + " twice"};
      listed[static_cast<std::size_t>(child)] = true;
    }
  for (std::int32_t id = 1; id < n; ++id)
    if (!listed[static_cast<std::size_t>(id)])
      return BoneProblem{
          id, Field::parent,
          "parent " + std::to_string(bones[static_cast<std::size_t>(id)].parent) + " does not list it as a child"};

  // With one root and agreeing lists, the hierarchy is a tree exactly when every bone is reachable from bone 0.
  std::vector<std::int32_t> queue;
  queue.reserve(count);
  queue.push_back(0);
  for (std::size_t head = 0; head < queue.size(); ++head)
    for (std::int32_t child : bones[static_cast<std::size_t>(queue[head])].children) queue.push_back(child);
  if (queue.size() != count) {
    std::vector<bool> reached(count, false);
    for (std::int32_t id : queue) reached[static_cast<std::size_t>(id)] = true;
    const auto it = std::find(reached.begin(), reached.end(), false);
    const auto id = static_cast<std::int32_t>(it - reached.begin());
    return BoneProblem{id, Field::parent, "is on a parent cycle (not reachable from the root)"};
  }
  if (order.size() == count) std::copy(queue.begin(), queue.end(), order.begin());
  return std::nullopt;
}

}  // namespace detail

namespace {

// Inverse of a rigid transform (rotation + translation): transpose the rotation, rotate the negated translation.
glm::mat4 rigid_inverse(const glm::mat4& m) {
  const glm::mat3 rt = glm::transpose(glm::mat3(m));
  glm::mat4 inv(rt);
  inv[3] = glm::vec4(-(rt * glm::vec3(m[3])), 1.0f);
  return inv;
}

// The two Euler triples (X·Y·Z) of one rotation: (x, y, z) and (x + 180, 180 - y, z + 180), wrapped to (-180, 180].
glm::vec3 other_euler(glm::vec3 e) {
  auto wrap = [](float a) { return a > 180.0f ? a - 360.0f : (a <= -180.0f ? a + 360.0f : a); };
  return {wrap(e.x + 180.0f), wrap(180.0f - e.y), wrap(e.z + 180.0f)};
}

// e's angles (in [-180, 180]) each moved by the multiple of 360 that brings it nearest its axis' range: clamping
// then goes to the limit nearer around the circle (across ±180 when that one is nearer), as the solvers' clamp.
glm::vec3 nearest_turn(glm::vec3 e, const DofLimits& limits) {
  for (int axis = 0; axis < 3; ++axis) {
    float best = e[axis], best_outside = 1e30f;
    for (const float shift : {0.0f, -360.0f, 360.0f}) {
      const float a = e[axis] + shift;
      const float outside = std::max(0.0f, limits.min[axis] - a) + std::max(0.0f, a - limits.max[axis]);
      if (outside < best_outside) best = a, best_outside = outside;
    }
    e[axis] = best;
  }
  return e;
}

float clamp_distance(glm::vec3 e, const DofLimits& limits) {
  const glm::vec3 d = e - clamp_euler(e, limits);
  return std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
}

}  // namespace

Skeleton::Skeleton(std::vector<Bone> bones, const std::string& source) : bones_(std::move(bones)) {
  order_.resize(bones_.size());
  if (auto problem = detail::find_bone_problem(bones_, order_))
    throw Error::in_file(source, problem->bone >= 0 ? "bone " + std::to_string(problem->bone) : "", problem->message);
  const Pose bind = bind_pose();
  bind_world_.resize(bones_.size());
  inverse_bind_world_.resize(bones_.size());
  LocalToWorldJob fk;  // cannot fail: the bind pose was checked finite above and has an entry per bone
  fk.skeleton = this;
  fk.rotations = bind.rotations;
  fk.translations = bind.translations;
  fk.world = bind_world_;
  fk.run();
  // Finite numbers can still overflow along a chain (translations near 3e38 add up to infinity): such a skeleton
  // would skin every vertex to NaN, so it is refused here, naming the first bone whose head is not finite.
  for (const std::int32_t id : order_)
    if (!finite(bind_world_[std::size_t(id)]))
      throw Error::in_file(source, "bone " + std::to_string(id), "bind transform overflows (not finite)");
  std::transform(bind_world_.begin(), bind_world_.end(), inverse_bind_world_.begin(), rigid_inverse);

  // Names, looked up by find() and key() in O(log bones) rather than by a scan (a pose of 65,535 bones would be
  // quadratic): bone ids sorted by (name, id), and whether each bone's name is its alone.
  by_name_.resize(bones_.size());
  for (std::size_t i = 0; i < bones_.size(); ++i) by_name_[i] = static_cast<std::int32_t>(i);
  std::sort(by_name_.begin(), by_name_.end(), [&](std::int32_t a, std::int32_t b) {
    const std::string& na = bones_[std::size_t(a)].name;
    const std::string& nb = bones_[std::size_t(b)].name;
    return na != nb ? na < nb : a < b;
  });
  unique_name_.assign(bones_.size(), 0);
  for (std::size_t i = 0; i < by_name_.size(); ++i) {
    const std::string& name = bones_[std::size_t(by_name_[i])].name;
    const bool same_before = i > 0 && bones_[std::size_t(by_name_[i - 1])].name == name;
    const bool same_after = i + 1 < by_name_.size() && bones_[std::size_t(by_name_[i + 1])].name == name;
    unique_name_[std::size_t(by_name_[i])] = !same_before && !same_after && !name.empty() && name.front() != '#';
  }
}

std::int32_t Skeleton::find(std::string_view name) const noexcept {
  if (!name.empty() && name.front() == '#') {
    std::int32_t id = -1;
    const char* end = name.data() + name.size();
    const auto [ptr, ec] = std::from_chars(name.data() + 1, end, id);
    if (ec != std::errc() || ptr != end || name.size() < 2 || id < 0 || static_cast<std::size_t>(id) >= bones_.size())
      return -1;
    return id;
  }
  const auto first = std::lower_bound(by_name_.begin(), by_name_.end(), name, [&](std::int32_t id, std::string_view n) {
    return std::string_view(bones_[std::size_t(id)].name) < n;
  });
  if (first == by_name_.end() || bones_[std::size_t(*first)].name != name) return -1;
  return *first;  // the lowest id of that name: ids are sorted within a name
}

std::string Skeleton::key(std::int32_t id) const {
  const std::string& name = bone(id).name;
  if (unique_name_[std::size_t(id)]) return name;
  std::string id_key(1, '#');
  return id_key.append(std::to_string(id));
}

bool Skeleton::is_ancestor(std::int32_t ancestor, std::int32_t bone_id) const noexcept {
  const auto n = static_cast<std::int32_t>(bones_.size());
  if (ancestor < 0 || ancestor >= n || bone_id < 0 || bone_id >= n) return false;
  for (std::int32_t id = bone_id; id >= 0; id = bones_[static_cast<std::size_t>(id)].parent)
    if (id == ancestor) return true;
  return false;
}

Pose Skeleton::bind_pose() const {
  Pose pose;
  pose.rotations.reserve(bones_.size());
  pose.translations.reserve(bones_.size());
  for (const Bone& b : bones_) {
    pose.rotations.push_back(quat_from_euler(b.bind_rotation));
    pose.translations.push_back(b.bind_translation);
  }
  return pose;
}

glm::vec3 Skeleton::set_euler(Pose& pose, std::int32_t bone_id, glm::vec3 degrees, bool clamp) const {
  const glm::vec3 used = clamp ? clamp_euler(degrees, bone(bone_id).limits) : degrees;
  pose.rotations.at(static_cast<std::size_t>(bone_id)) = quat_from_euler(used);
  return used;
}

void Skeleton::clamp_to_limits(Pose& pose, std::int32_t bone_id) const {
  const DofLimits& limits = bone(bone_id).limits;
  glm::quat& rotation = pose.rotations.at(static_cast<std::size_t>(bone_id));
  const glm::vec3 first = nearest_turn(euler_from_quat(rotation), limits);
  const glm::vec3 second = nearest_turn(other_euler(euler_from_quat(rotation)), limits);
  const glm::vec3 nearer = clamp_distance(second, limits) < clamp_distance(first, limits) ? second : first;
  if (clamp_distance(nearer, limits) == 0.0f) return;  // already inside: keep the exact quaternion
  rotation = quat_from_euler(clamp_euler(nearer, limits));
}

glm::mat4 local_matrix(glm::quat rotation, glm::vec3 translation) noexcept {
  glm::mat4 m = glm::mat4_cast(rotation);
  m[3] = glm::vec4(translation, 1.0f);
  return m;
}

namespace {

// The size checks of LocalToWorldJob (O(1)).
Status check_sizes(const LocalToWorldJob& job, std::size_t begin, std::size_t end) noexcept {
  if (job.skeleton == nullptr) return Status::failure("no skeleton");
  const std::size_t n = job.skeleton->bone_count();
  if (job.rotations.size() != n || job.translations.size() != n)
    return Status::failure("rotations or translations do not have one entry per bone");
  if (job.world.size() != n) return Status::failure("world does not have one entry per bone");
  if (!job.palette.empty() && job.palette.size() != n)
    return Status::failure("palette is neither empty nor one entry per bone");
  if (begin > end || end > n) return Status::failure("bone range out of bounds");
  return {};
}

// Whether the pose entries of bones order()[begin, end) are finite, without a branch per number: v - v is 0 for a
// finite v and NaN for an infinity or a NaN, and a NaN stays NaN through the sums, so one test at the end decides.
// The whole pose (the usual call) is read in memory order, a range through order().
bool pose_finite(const LocalToWorldJob& job, std::size_t begin, std::size_t end) noexcept {
  glm::vec4 r(0.0f);
  glm::vec3 t(0.0f);
  auto add = [&](std::size_t i) noexcept {
    const glm::quat q = job.rotations[i];
    const glm::vec3 v = job.translations[i];
    r += glm::vec4(q.x - q.x, q.y - q.y, q.z - q.z, q.w - q.w);
    t += v - v;
  };
  if (begin == 0 && end == job.rotations.size()) {
    for (std::size_t i = 0; i < end; ++i) add(i);
  } else {
    const std::span<const std::int32_t> order = job.skeleton->order();
    for (std::size_t k = begin; k < end; ++k) add(static_cast<std::size_t>(order[k]));
  }
  return finite(r) && finite(t);
}

}  // namespace

std::size_t LocalToWorldJob::count() const noexcept { return skeleton == nullptr ? 0 : skeleton->bone_count(); }

Status LocalToWorldJob::validate() const noexcept {
  if (const Status status = check_sizes(*this, 0, count()); !status) return status;
  if (!pose_finite(*this, 0, count())) return Status::failure("pose is not finite");
  return {};
}

Status LocalToWorldJob::run() const noexcept { return run(0, count()); }

namespace {

// a · b for affine matrices (bottom row 0 0 0 1), b given by its rotation columns and translation: glm's product
// without the terms that multiply b's zero bottom row (or its 1), which add +0 (or a's translation times 1): the same
// bits (but for the sign of a zero), a quarter of the arithmetic less. Always inlined: as a call its arguments and
// result went through the stack, which cost as much as the products.
[[gnu::always_inline]] inline glm::mat4 affine_product(const glm::mat4& a, const glm::vec3& b0, const glm::vec3& b1,
                                                       const glm::vec3& b2, const glm::vec3& b3) noexcept {
  glm::mat4 r;
  r[0] = a[0] * b0.x + a[1] * b0.y + a[2] * b0.z;
  r[1] = a[0] * b1.x + a[1] * b1.y + a[2] * b1.z;
  r[2] = a[0] * b2.x + a[1] * b2.y + a[2] * b2.z;
  r[3] = a[0] * b3.x + a[1] * b3.y + a[2] * b3.z + a[3];
  return r;
}

}  // namespace

// Per bone: the local rotation as glm::mat3_cast computes it (local_matrix's columns), the world matrix as the affine
// product with the parent's, the palette as the affine product with the inverse bind matrix; all inline, the world
// matrix kept in registers for the palette. Bit for bit what local_matrix and the full affine products give.
Status LocalToWorldJob::run(std::size_t begin, std::size_t end) const noexcept {
  if (const Status status = check_sizes(*this, begin, end); !status) return status;
  if (!pose_finite(*this, begin, end)) return Status::failure("pose is not finite");
  const std::span<const Bone> bones = skeleton->bones();
  const std::span<const std::int32_t> order = skeleton->order();
  const std::span<const glm::mat4> inverse_bind = skeleton->inverse_bind_world();
  const bool with_palette = !palette.empty();
  for (std::size_t n = begin; n < end; ++n) {
    const auto i = static_cast<std::size_t>(order[n]);
    const glm::mat3 r = glm::mat3_cast(rotations[i]);
    const glm::vec3 t = translations[i];
    const std::int32_t parent = bones[i].parent;
    glm::mat4 w;
    if (parent < 0) {
      w[0] = glm::vec4(r[0], 0.0f);
      w[1] = glm::vec4(r[1], 0.0f);
      w[2] = glm::vec4(r[2], 0.0f);
      w[3] = glm::vec4(t, 1.0f);
    } else {
      w = affine_product(world[static_cast<std::size_t>(parent)], r[0], r[1], r[2], t);
    }
    world[i] = w;
    if (with_palette) {
      const glm::mat4& b = inverse_bind[i];
      palette[i] = affine_product(w, glm::vec3(b[0]), glm::vec3(b[1]), glm::vec3(b[2]), glm::vec3(b[3]));
    }
  }
  return {};
}

}  // namespace deform
