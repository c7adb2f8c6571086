#pragma once
// Helpers the importers share (import_assimp.cpp, gltf_import.cpp, iqm_import.cpp, scene_assembly.cpp): the split of
// a transform into what a Skeleton holds and the skeleton of those parts, bone names that fit .sk, and the key a
// point is merged by.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <string>
#include <vector>

#include "deform/import/import.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform::import_detail {

// A transform split into its rigid part (rotation, translation) and a uniform scale. `similarity` is false when
// the matrix has non-uniform scale, shear or a mirror, which a Skeleton cannot hold (the rigid part is then the
// nearest rotation of the normalised columns).
struct Split {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 translation{0.0f};
  glm::vec3 axis_scale{1.0f};
  float scale = 1.0f;
  bool similarity = true;
  glm::mat4 rigid() const { return glm::translate(glm::mat4(1.0f), translation) * glm::mat4_cast(rotation); }
};

inline Split split(const glm::mat4& m) {
  Split s;
  s.translation = glm::vec3(m[3]);
  glm::mat3 r(m);
  const float det = glm::determinant(r);
  for (int i = 0; i < 3; ++i) {
    s.axis_scale[i] = glm::length(r[i]);
    if (s.axis_scale[i] > 0.0f) r[i] /= s.axis_scale[i];
  }
  if (det < 0.0f) r[2] = -r[2];
  s.rotation = glm::normalize(glm::quat_cast(r));
  s.scale = std::cbrt(std::fabs(det));
  constexpr float tolerance = 1e-3f;
  s.similarity = det > 0.0f;
  for (int i = 0; i < 3; ++i) {
    s.similarity = s.similarity && std::fabs(s.axis_scale[i] - s.scale) <= tolerance * s.scale &&
                   std::fabs(glm::dot(r[i], r[(i + 1) % 3])) <= tolerance;
  }
  return s;
}

// Sets each of `bones` (parents set, children empty) to the rigid part of its bind world transform `bind_split[b]`:
// bind translation and rotation relative to the parent's rigid part; fills the children in bone order; returns the
// Skeleton of them. Throws what Skeleton's constructor throws, naming `path`.
inline Skeleton skeleton_from_binds(std::vector<Bone>& bones, const std::vector<Split>& bind_split,
                                    const std::string& path) {
  for (std::size_t b = 0; b < bones.size(); ++b) {
    const glm::mat4 parent =
        bones[b].parent < 0 ? glm::mat4(1.0f) : bind_split[static_cast<std::size_t>(bones[b].parent)].rigid();
    const Split local = split(glm::inverse(parent) * bind_split[b].rigid());
    bones[b].bind_translation = local.translation;
    bones[b].bind_rotation = euler_from_quat(local.rotation);
  }
  for (std::size_t b = 0; b < bones.size(); ++b)
    if (bones[b].parent >= 0)
      bones[static_cast<std::size_t>(bones[b].parent)].children.push_back(static_cast<std::int32_t>(b));
  return Skeleton(bones, path);
}

// Length of the valid UTF-8 sequence starting at `i` (1 to 4), or 0 when the bytes there are not one.
inline std::size_t utf8_length(const std::string& s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char lead = byte(i);
  const std::size_t n = lead < 0x80 ? 1 : (lead >> 5) == 0x6 ? 2 : (lead >> 4) == 0xE ? 3 : (lead >> 3) == 0x1E ? 4 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  return n;
}

// A bone name that fits a .sk record: valid UTF-8 without control characters (each invalid byte or control character
// becomes '_'), at most 79 bytes, cut at a character boundary.
inline std::string fit_name(const std::string& raw, std::size_t& shortened) {
  std::string name;
  for (std::size_t i = 0; i < raw.size();) {
    const std::size_t n = utf8_length(raw, i);
    const auto lead = static_cast<unsigned char>(raw[i]);
    if (n == 0 || lead < 0x20 || lead == 0x7f) {
      name.push_back('_');
      ++i;
    } else {
      name.append(raw, i, n);
      i += n;
    }
  }
  if (name.size() <= 79) return name;
  std::size_t end = 79;
  while (end > 0 && (static_cast<unsigned char>(name[end]) & 0xC0) == 0x80) --end;
  ++shortened;
  return name.substr(0, end);
}

// One vertex's skin influences, strongest first; the key a point is merged by (with the exact position).
struct Influences {
  std::array<std::uint16_t, 4> bones{};
  std::array<float, 4> weights{};
};

// Word 11 is 0 for a vertex that may merge with others of the same position and influences; for one with more than
// four influences or that morph targets move, the id of its extra influences and morph deltas (ExtraInfluenceIds:
// equal lists, equal ids, with the top bit set).
struct PointKey {
  std::array<std::uint32_t, 12> bits;
  bool operator==(const PointKey&) const = default;
};
struct PointKeyHash {
  std::size_t operator()(const PointKey& key) const noexcept {
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the words
    for (std::uint32_t word : key.bits) h = (h ^ word) * 1099511628211ull;
    return static_cast<std::size_t>(h);
  }
};

// Ids of the lists of influences past the fourth (bone, normalised weight) that vertices carry, equal for equal
// lists: with the position and the four slots they decide which render vertices share a point, so that a vertex
// with extras merges exactly as one without (a point is a distinct position with its skin, docs/import.md).
class ExtraInfluenceIds {
 public:
  void add(std::uint16_t bone, float weight) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &weight, 4);
    list_.push_back(bone);
    list_.push_back(bits);
  }
  // A morph target's position delta, as its bits (-0 and 0 differ: a delta is only merged with its exact copy).
  void add(glm::vec3 delta) {
    std::uint32_t bits[3];
    std::memcpy(bits, &delta, sizeof bits);
    list_.insert(list_.end(), bits, bits + 3);
  }
  // Ends the extras' (bone, weight) pairs, before the deltas.
  void separate() { list_.push_back(0xFFFFFFFFu); }
  void add_word(std::uint32_t word) { list_.push_back(word); }
  // The id of the list added since the last call (then cleared), 0x80000000 and up.
  std::uint32_t take() {
    const auto [found, inserted] = ids_.emplace(list_, 0x80000000u | static_cast<std::uint32_t>(ids_.size()));
    list_.clear();
    return found->second;
  }

 private:
  std::vector<std::uint32_t> list_;
  std::map<std::vector<std::uint32_t>, std::uint32_t> ids_;
};

inline PointKey point_key(glm::vec3 position, const Influences& influences, std::uint32_t apart = 0) {
  PointKey key{};
  key.bits[11] = apart;
  std::memcpy(key.bits.data(), &position, sizeof(float) * 3);
  for (int i = 0; i < 4; ++i) {
    key.bits[static_cast<std::size_t>(3 + i)] = influences.bones[static_cast<std::size_t>(i)];
    std::memcpy(&key.bits[static_cast<std::size_t>(7 + i)], &influences.weights[static_cast<std::size_t>(i)], 4);
  }
  return key;
}

// The ImportedModel of a .gltf or .glb file, read with tinygltf (gltf_import.cpp). Same contract as import_model.
ImportedModel import_gltf(const std::string& path, const ImportOptions& options);

bool is_gltf_path(const std::string& path);

// The ImportedModel of an Inter-Quake Model (.iqm, version 2), read by iqm_import.cpp: joints, skin and animations,
// which Assimp 5.2's IQM importer drops. Same contract as import_model.
ImportedModel import_iqm(const std::string& path, const ImportOptions& options);

bool is_iqm_path(const std::string& path);

}  // namespace deform::import_detail
