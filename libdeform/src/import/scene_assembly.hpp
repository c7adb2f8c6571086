#pragma once
// The stages every importer (gltf_import.cpp, iqm_import.cpp, import_assimp.cpp) runs once it has read its format:
// the bones of the node forest, naming materials and clips, confining a texture, merging render vertices into points
// by (exact position, influences), closing the mesh's faces, holding rest transforms in clips and reporting a clip.
// Each reader keeps what its format decides (which nodes become bones, the bind, the key conversion); the rules
// shared live here once.
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "deform/import/import.hpp"
#include "deform/io/referenced_file.hpp"
#include "import_common.hpp"
namespace deform::import_detail {

// Which nodes of a forest (`parents[i]`: node i's parent, -1 for a top node) the skeleton holds: every `needed` node
// and its ancestors, up to `stop` (included; -1: up to the top).
std::vector<bool> skeleton_nodes(const std::vector<std::int32_t>& parents, const std::vector<bool>& needed,
                                 std::int32_t stop = -1);

// The bones of a forest of nodes listed parents first: node i is named `names[i]` (fitted to .sk, counted in
// `shortened` when cut) and has parent `parents[i]` (an index into the list, below i; -1 for a top node). Several top
// nodes hang under an added bone "root" at the origin; an empty forest (a static scene) is that bone alone. Node i is
// bone `first + i`, `first` 1 when "root" was added to a non-empty forest, else 0.
struct ForestBones {
  std::vector<Bone> bones;
  std::int32_t first = 0;
};
ForestBones bones_of_forest(const std::vector<std::string>& names, const std::vector<std::int32_t>& parents,
                            std::size_t& shortened);

// "N bone names longer than 79 bytes shortened to fit .sk", when `shortened` > 0.
void warn_shortened_names(std::size_t shortened, std::vector<std::string>& warnings);

// Throws "N bones (at most 65535)" naming `path` when there are more bones than a u16 bone id holds.
void require_bone_count(std::size_t bones, const std::string& path);

// A material's name: whitespace and control characters become '_'; an empty name, or one already in `used`,
// becomes "material<index>" (an MTL refers to materials by name). Appends the result to `used`.
std::string unique_material_name(std::string raw, std::size_t index, std::vector<std::string>& used);

// A clip's name: an empty name or one already in `used` becomes "clip<index>". Appends the result to `used`.
std::string unique_clip_name(std::string raw, std::size_t index, std::vector<std::string>& used);

// A diffuse texture the model names by a path (backslashes read as '/'): confined to the model's folder like every
// file a model names (resolve_referenced_file, which throws naming `element`; first, as it refuses a name that is
// no path), returned as the model's folder joined with it, with a warning naming material `material` when absent.
std::string referenced_texture(const std::string& path, std::string texture, const std::string& element,
                               const ReferencePolicy& policy, const std::string& material,
                               std::vector<std::string>& warnings);

// One influence of a render vertex: a bone and its weight, normalised over the vertex's influences.
struct Influence {
  std::uint16_t bone = 0;
  float weight = 0.0f;
};

// Merges render vertices into points: vertices of the exact same position and influences share one point (a point
// is a distinct position with its skin, docs/import.md). Appends each new point to `positions` and `weights`: the
// four strongest influences in the slots, the rest as extras.
class PointMerger {
 public:
  PointMerger(std::vector<glm::vec3>& positions, SkinWeights& weights) : positions_(positions), weights_(weights) {}
  // The point of one vertex and whether it is new. `influences`: strongest first, at least one. One with more than
  // four influences merges only with vertices of the same extras too; one that morph targets move only with
  // vertices that the same targets move by the same position deltas (`morph_deltas`: the delta of targets
  // `first_target`, `first_target` + 1, ... in order, compared bit for bit), so that the split copies of a point
  // along a UV or normal seam stay one point, smooth, as they are without targets.
  std::pair<std::uint32_t, bool> add(glm::vec3 position, std::span<const Influence> influences,
                                     std::span<const glm::vec3> morph_deltas = {}, std::uint32_t first_target = 0);

 private:
  std::vector<glm::vec3>& positions_;
  SkinWeights& weights_;
  std::unordered_map<PointKey, std::uint32_t, PointKeyHash> point_of_key_;
  ExtraInfluenceIds extra_ids_;  // PointKey word 11: the id of a vertex's extras and morph deltas
};

// Closes a mesh read as triangles: throws "the scene has no triangles" naming `path` when there are none, else sets
// every face to its triangle.
void close_triangle_faces(Mesh& mesh, const std::string& path);

// The rest transforms (the file's node tree) of the skeleton's bones in skeleton space, and which of them differ
// from the bind pose: a clip holds those, as players leave unanimated nodes at their node transform.
struct RestLocals {
  std::vector<std::pair<glm::vec3, glm::quat>> local;
  std::vector<bool> differs;
};
// `local[b]` for each bone with `has_rest[b]`; differing means by more than 1e-6 of the model's size (its points'
// bounding box diagonal) in translation, or 1e-6 in rotation (either sign of the quaternion).
RestLocals rest_locals(const Skeleton& skeleton, const std::vector<glm::vec3>& points,
                       std::vector<std::pair<glm::vec3, glm::quat>> local, const std::vector<bool>& has_rest);

// A clip's channels without translation or rotation keys hold the bone's rest value there; every bone the clip does
// not move (`has_channel`) whose rest differs from its bind gets a channel holding its rest.
void hold_rest(Animation& clip, const RestLocals& rest, const std::vector<bool>& has_channel);

// Reports the keys `dropped` and the bones that animate scale in warnings naming the clip, checks the clip against
// `bones` (throwing naming `path`) and appends it to `clips`.
void add_clip(Animation clip, std::size_t dropped, std::size_t scaled_bones, std::size_t bones, const std::string& path,
              std::vector<Animation>& clips, std::vector<std::string>& warnings);

}  // namespace deform::import_detail
