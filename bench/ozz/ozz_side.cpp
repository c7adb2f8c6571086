// The ozz-animation half of the side-by-side benchmark: ozz's offline builders make its skeleton and clips from the
// data libdeform's half hands over (ozz_side.hpp), and its runtime jobs run the frame as ozz's own samples drive them
// (a SamplingJob::Context per clip and character, BlendingJob, LocalToModelJob, then the model × inverse-bind
// palette and SkinningJob).
#include "ozz_side.hpp"

#include <cmath>
#include <vector>
#include <stdexcept>
#include <utility>

#include <ozz/animation/offline/animation_builder.h>
#include <ozz/animation/offline/raw_animation.h>
#include <ozz/animation/offline/raw_skeleton.h>
#include <ozz/animation/offline/skeleton_builder.h>
#include <ozz/animation/runtime/animation.h>
#include <ozz/animation/runtime/blending_job.h>
#include <ozz/animation/runtime/local_to_model_job.h>
#include <ozz/animation/runtime/sampling_job.h>
#include <ozz/animation/runtime/skeleton.h>
#include <ozz/base/maths/simd_math.h>
#include <ozz/base/maths/soa_transform.h>
#include <ozz/base/span.h>
#include <ozz/geometry/runtime/skinning_job.h>

namespace ozz_side {
namespace {

using ozz::animation::offline::RawAnimation;
using ozz::animation::offline::RawSkeleton;

ozz::math::Float4x4 load(const std::array<float, 16>& m) {
  ozz::math::Float4x4 r;
  for (int c = 0; c < 4; ++c) r.cols[c] = ozz::math::simd_float4::LoadPtrU(m.data() + 4 * c);
  return r;
}

RawSkeleton::Joint make_joint(const RigData& rig, const std::vector<std::vector<int>>& children, int b) {
  RawSkeleton::Joint joint;
  joint.name = rig.names[std::size_t(b)].c_str();
  const auto& t = rig.rest_translations[std::size_t(b)];
  const auto& q = rig.rest_rotations[std::size_t(b)];
  joint.transform.translation = ozz::math::Float3(t[0], t[1], t[2]);
  joint.transform.rotation = ozz::math::Quaternion(q[0], q[1], q[2], q[3]);
  joint.transform.scale = ozz::math::Float3::one();
  for (int child : children[std::size_t(b)]) joint.children.push_back(make_joint(rig, children, child));
  return joint;
}

struct Character {
  std::unique_ptr<ozz::animation::SamplingJob::Context> contexts[2];
  std::vector<ozz::math::SoaTransform> locals[2], blended;
  std::vector<ozz::math::Float4x4> models, palette;
  std::vector<float> positions, normals;
};

}  // namespace

// The points of one influence count as their own mesh, as ozz's fbx2mesh splits a mesh into parts (each part's
// points, indices and weights copied; influences_count - 1 weights per point, the last one implied).
struct Part {
  int influences = 0;
  std::vector<std::uint32_t> points;  // the whole mesh's points, ascending
  std::vector<float> positions, normals, weights;
  std::vector<std::uint16_t> indices;
};

struct Runner::Impl {
  ozz::unique_ptr<ozz::animation::Skeleton> skeleton;
  ozz::unique_ptr<ozz::animation::Animation> clips[2];
  std::vector<int> ozz_joint;  // libdeform bone -> ozz joint
  std::vector<ozz::math::Float4x4> inverse_bind;
  std::vector<ozz::math::Float4x4> palette;  // skinning alone (set_palette)
  MeshData mesh;
  std::vector<Part> parts;  // by influence count, 1 to 4; empty parts left out
  float blend = 0.5f;
  std::vector<Character> characters;

  // out_normals null: positions only.
  bool skin(std::span<const ozz::math::Float4x4> matrices, float* out_positions, float* out_normals) const {
    ozz::geometry::SkinningJob job;
    const auto points = mesh.positions.size() / 3;
    job.vertex_count = static_cast<int>(points);
    job.influences_count = 4;
    job.joint_matrices = {matrices.data(), matrices.size()};
    job.joint_indices = {mesh.indices.data(), mesh.indices.size()};
    job.joint_indices_stride = 4 * sizeof(std::uint16_t);
    job.joint_weights = {mesh.weights.data(), mesh.weights.size()};
    job.joint_weights_stride = 4 * sizeof(float);
    job.in_positions = {mesh.positions.data(), mesh.positions.size()};
    job.in_positions_stride = 3 * sizeof(float);
    job.out_positions = {out_positions, points * 3};
    job.out_positions_stride = 3 * sizeof(float);
    if (out_normals != nullptr) {
      job.in_normals = {mesh.normals.data(), mesh.normals.size()};
      job.in_normals_stride = 3 * sizeof(float);
      job.out_normals = {out_normals, points * 3};
      job.out_normals_stride = 3 * sizeof(float);
    }
    return job.Run();
  }

  // Each part with its own influences_count, into the outputs at the part's offset (parts in order).
  bool skin_parts(float* out_positions, float* out_normals) const {
    std::size_t at = 0;
    for (const Part& part : parts) {
      ozz::geometry::SkinningJob job;
      const std::size_t points = part.points.size(), k = std::size_t(part.influences);
      job.vertex_count = static_cast<int>(points);
      job.influences_count = part.influences;
      job.joint_matrices = {palette.data(), palette.size()};
      job.joint_indices = {part.indices.data(), part.indices.size()};
      job.joint_indices_stride = k * sizeof(std::uint16_t);
      if (k > 1) {
        job.joint_weights = {part.weights.data(), part.weights.size()};
        job.joint_weights_stride = (k - 1) * sizeof(float);
      }
      job.in_positions = {part.positions.data(), part.positions.size()};
      job.in_positions_stride = 3 * sizeof(float);
      job.out_positions = {out_positions + 3 * at, points * 3};
      job.out_positions_stride = 3 * sizeof(float);
      job.in_normals = {part.normals.data(), part.normals.size()};
      job.in_normals_stride = 3 * sizeof(float);
      job.out_normals = {out_normals + 3 * at, points * 3};
      job.out_normals_stride = 3 * sizeof(float);
      if (!job.Run()) return false;
      at += points;
    }
    return true;
  }
};

Runner::Runner(const RigData& rig, std::span<const ClipData> clips, const MeshData& mesh, float blend, int characters)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.mesh = mesh;
  s.blend = blend;
  // Parts by influence count: a point uses slots 0 .. k-1, slot k-1 its last with a nonzero weight.
  const std::size_t mesh_points = mesh.positions.size() / 3;
  s.parts.resize(4);
  for (std::size_t p = 0; p < mesh_points; ++p) {
    int used = 1;
    for (int k = 1; k < 4; ++k)
      if (mesh.weights[4 * p + std::size_t(k)] != 0.0f) used = k + 1;
    Part& part = s.parts[std::size_t(used - 1)];
    part.influences = used;
    part.points.push_back(std::uint32_t(p));
    for (int c = 0; c < 3; ++c) {
      part.positions.push_back(mesh.positions[3 * p + std::size_t(c)]);
      part.normals.push_back(mesh.normals[3 * p + std::size_t(c)]);
    }
    for (int k = 0; k < used; ++k) part.indices.push_back(mesh.indices[4 * p + std::size_t(k)]);
    for (int k = 0; k + 1 < used; ++k) part.weights.push_back(mesh.weights[4 * p + std::size_t(k)]);
  }
  std::erase_if(s.parts, [](const Part& part) { return part.points.empty(); });
  const std::size_t bones = rig.names.size();
  std::vector<std::vector<int>> children(bones);
  for (std::size_t b = 1; b < bones; ++b) children[std::size_t(rig.parents[b])].push_back(int(b));
  RawSkeleton raw_skeleton;
  raw_skeleton.roots.push_back(make_joint(rig, children, 0));
  s.skeleton = ozz::animation::offline::SkeletonBuilder()(raw_skeleton);
  if (!s.skeleton) throw std::runtime_error("ozz's SkeletonBuilder refused the skeleton");
  // ozz orders joints its own way (depth first): find each bone by its (unique) name.
  const auto names = s.skeleton->joint_names();
  s.ozz_joint.assign(bones, -1);
  for (std::size_t j = 0; j < names.size(); ++j)
    for (std::size_t b = 0; b < bones; ++b)
      if (rig.names[b] == names[j]) s.ozz_joint[b] = int(j);
  for (std::size_t b = 0; b < bones; ++b)
    if (s.ozz_joint[b] < 0) throw std::runtime_error("bone " + rig.names[b] + " is not in ozz's skeleton");
  for (const auto& m : rig.inverse_bind) s.inverse_bind.push_back(load(m));

  if (clips.size() != 2) throw std::runtime_error("two clips expected");
  for (std::size_t k = 0; k < 2; ++k) {
    const ClipData& clip = clips[k];
    RawAnimation raw;
    raw.name = clip.name.c_str();
    raw.duration = clip.duration;
    raw.tracks.resize(std::size_t(s.skeleton->num_joints()));
    for (std::size_t b = 0; b < bones; ++b) {
      RawAnimation::JointTrack& track = raw.tracks[std::size_t(s.ozz_joint[b])];
      for (std::size_t i = 0; i < clip.translation_times[b].size(); ++i) {
        const auto& v = clip.translations[b][i];
        track.translations.push_back({clip.translation_times[b][i], ozz::math::Float3(v[0], v[1], v[2])});
      }
      for (std::size_t i = 0; i < clip.rotation_times[b].size(); ++i) {
        const auto& v = clip.rotations[b][i];
        track.rotations.push_back({clip.rotation_times[b][i], ozz::math::Quaternion(v[0], v[1], v[2], v[3])});
      }
    }
    if (!raw.Validate()) throw std::runtime_error("ozz refused the raw animation " + clip.name);
    s.clips[k] = ozz::animation::offline::AnimationBuilder()(raw);
    if (!s.clips[k]) throw std::runtime_error("ozz's AnimationBuilder refused " + clip.name);
  }

  const auto joints = std::size_t(s.skeleton->num_joints());
  const auto soa = std::size_t(s.skeleton->num_soa_joints());
  const auto floats = mesh.positions.size();
  s.characters.resize(std::size_t(characters));
  for (Character& c : s.characters) {
    for (int k = 0; k < 2; ++k) {
      c.contexts[k] = std::make_unique<ozz::animation::SamplingJob::Context>(int(joints));
      c.locals[k].resize(soa);
    }
    c.blended.resize(soa);
    c.models.resize(joints);
    c.palette.resize(bones);
    c.positions.resize(floats);
    c.normals.resize(floats);
  }
}

Runner::~Runner() = default;

void Runner::set_palette(std::span<const std::array<float, 16>> palette) {
  impl_->palette.clear();
  for (const auto& m : palette) impl_->palette.push_back(load(m));
}

bool Runner::skin(std::span<float> out_positions, std::span<float> out_normals) const {
  if (out_positions.size() < impl_->mesh.positions.size() || out_normals.size() < impl_->mesh.positions.size())
    return false;
  return impl_->skin(impl_->palette, out_positions.data(), out_normals.data());
}

bool Runner::skin_parts(std::span<float> out_positions, std::span<float> out_normals) const {
  if (out_positions.size() < impl_->mesh.positions.size() || out_normals.size() < impl_->mesh.positions.size())
    return false;
  return impl_->skin_parts(out_positions.data(), out_normals.data());
}

std::vector<std::uint32_t> Runner::part_points() const {
  std::vector<std::uint32_t> points;
  for (const Part& part : impl_->parts) points.insert(points.end(), part.points.begin(), part.points.end());
  return points;
}

std::vector<std::size_t> Runner::part_sizes() const {
  std::vector<std::size_t> sizes(4, 0);
  for (const Part& part : impl_->parts) sizes[std::size_t(part.influences - 1)] = part.points.size();
  return sizes;
}

bool Runner::skin_positions(std::span<float> out_positions) const {
  if (out_positions.size() < impl_->mesh.positions.size()) return false;
  return impl_->skin(impl_->palette, out_positions.data(), nullptr);
}

bool Runner::frame(int index, float seconds) {
  if (!pose(index, seconds)) return false;
  Impl& s = *impl_;
  Character& c = s.characters[std::size_t(index)];
  return s.skin({c.palette.data(), c.palette.size()}, c.positions.data(), c.normals.data());
}

bool Runner::pose(int index, float seconds) {
  Impl& s = *impl_;
  Character& c = s.characters[std::size_t(index)];
  ozz::animation::BlendingJob::Layer layers[2];
  for (int k = 0; k < 2; ++k) {
    const float duration = s.clips[k]->duration();
    float local = seconds - std::floor(seconds / duration) * duration;  // loop, as libdeform's local_time
    if (local >= duration) local = 0.0f;
    ozz::animation::SamplingJob sampling;
    sampling.animation = s.clips[k].get();
    sampling.context = c.contexts[k].get();
    sampling.ratio = local / duration;
    sampling.output = ozz::make_span(c.locals[k]);
    if (!sampling.Run()) return false;
    layers[k].weight = k == 0 ? 1.0f - s.blend : s.blend;
    layers[k].transform = ozz::make_span(std::as_const(c.locals[k]));
  }
  ozz::animation::BlendingJob blending;
  blending.layers = layers;
  blending.rest_pose = s.skeleton->joint_rest_poses();
  blending.output = ozz::make_span(c.blended);
  if (!blending.Run()) return false;
  ozz::animation::LocalToModelJob ltm;
  ltm.skeleton = s.skeleton.get();
  ltm.input = ozz::make_span(std::as_const(c.blended));
  ltm.output = ozz::make_span(c.models);
  if (!ltm.Run()) return false;
  for (std::size_t b = 0; b < c.palette.size(); ++b)
    c.palette[b] = c.models[std::size_t(s.ozz_joint[b])] * s.inverse_bind[b];
  return true;
}

std::span<const float> Runner::positions(int c) const { return impl_->characters[std::size_t(c)].positions; }
std::span<const float> Runner::normals(int c) const { return impl_->characters[std::size_t(c)].normals; }

std::array<float, 16> Runner::model(int c, int b) const {
  const auto& m = impl_->characters[std::size_t(c)].models[std::size_t(impl_->ozz_joint[std::size_t(b)])];
  std::array<float, 16> r;
  for (int col = 0; col < 4; ++col) ozz::math::StorePtrU(m.cols[col], r.data() + 4 * col);
  return r;
}

const char* Runner::simd_name() {
#if defined(OZZ_SIMD_AVX2) && defined(OZZ_SIMD_FMA)
  return "AVX2+FMA";
#elif defined(OZZ_SIMD_AVX2)
  return "AVX2";
#elif defined(OZZ_SIMD_AVX)
  return "AVX";
#elif defined(OZZ_SIMD_SSE4_1)
  return "SSE4.1";
#elif defined(OZZ_SIMD_SSE2)
  return "SSE2";
#else
  return "reference (no SIMD)";
#endif
}

}  // namespace ozz_side
