// Importer through Assimp (import.hpp). docs/import.md describes the conversions; the comments here give reasons.
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <optional>
#include <unordered_map>

#include "deform/io/atomic_file.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/import/import.hpp"
#include "import_common.hpp"
#include "scene_assembly.hpp"
#include "utf8_path.hpp"
#include "finite.hpp"
namespace deform {
namespace {

namespace fs = std::filesystem;
using namespace import_detail;

// The absolute form of `path` (as given when the working directory cannot be read).
fs::path absolute_path(const fs::path& path) {
  std::error_code error;
  fs::path absolute = fs::absolute(path, error);
  return error ? path : absolute;
}

// Every file Assimp opens while it reads a model (an .md5anim beside an .md5mesh, an MD3's skins, an Ogre
// .material) is a file the model names: it is opened only inside the model's folder or a folder the policy allows
// (resolve_referenced_file). A refusal cannot travel through Assimp as an exception: it is kept, the open fails, and
// import_model throws it once ReadFile returns. Exists() answers false for a refused file, so whether a file outside
// exists never shows; a file an importer only looked for (its Exists() refused, never opened) fails the import only
// when the import fails, and is a warning otherwise: importers probe several names and go on without one.
// Assimp's own IO system takes a relative name from the working directory. The model's path is made absolute before
// ReadFile, so that the names importers build from it are absolute; a bare name an importer looks for (the Ogre
// importer's `<material>.material`) is looked for beside the model, where the format keeps it — from another working
// directory it would be refused, and the model fail to load.
class ConfinedIOSystem : public Assimp::DefaultIOSystem {
 public:
  ConfinedIOSystem(const std::string& model, const ReferencePolicy& policy)
      : model_(model), folder_(absolute_path(utf8_path::from_utf8(model)).parent_path()), policy_(policy) {}

  bool Exists(const char* file) const override {
    const std::optional<std::string> name = allowed(file, "a file the importer looked for", probe_refusal_);
    return name && Assimp::DefaultIOSystem::Exists(name->c_str());
  }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    const std::optional<std::string> name = allowed(file, "a file the importer opened", refusal_);
    return name ? Assimp::DefaultIOSystem::Open(name->c_str(), mode) : nullptr;
  }
  // The first refusal of a file opened, and of a file only looked for, if any.
  const std::optional<Error>& refusal() const { return refusal_; }
  const std::optional<Error>& probe_refusal() const { return probe_refusal_; }

 private:
  // The absolute name of `file` (relative names beside the model) when the policy allows it; else the refusal (of
  // `element`) is kept in `kept` (the first one) and nothing is returned.
  std::optional<std::string> allowed(const char* file, const char* element, std::optional<Error>& kept) const {
    if (file == nullptr) return std::nullopt;
    try {
      // Assimp's names are UTF-8 (its Windows IO system opens them as wide names).
      const fs::path name = utf8_path::from_utf8(file);
      const std::string absolute = utf8_path::to_utf8((name.is_absolute() ? name : folder_ / name).lexically_normal());
      resolve_referenced_file(model_, absolute, element, policy_);
      return absolute;
    } catch (const Error& e) {
      if (!kept) kept = e;
      return std::nullopt;
    }
  }
  std::string model_;
  fs::path folder_;  // the model's, absolute
  const ReferencePolicy& policy_;
  mutable std::optional<Error> refusal_, probe_refusal_;
};

glm::mat4 to_glm(const aiMatrix4x4& m) {
  // aiMatrix4x4 is row-major with column vectors (translation in a4, b4, c4); glm is column-major.
  return glm::transpose(
      glm::mat4(m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4));
}
glm::vec3 to_glm(const aiVector3D& v) { return {v.x, v.y, v.z}; }
glm::quat to_glm(const aiQuaternion& q) { return glm::quat(q.w, q.x, q.y, q.z); }

// The node tree, flattened in pre-order (parents before children), with rest-pose transforms.
struct Node {
  const aiNode* node;
  std::int32_t parent;
  glm::mat4 local;
  glm::mat4 global;
};

void flatten(const aiNode* node, std::int32_t parent, std::vector<Node>& out, std::size_t depth = 0) {
  if (depth > 10000) throw Error::in_file("", "node '" + std::string(node->mName.C_Str()) + "'", "node tree too deep");
  const glm::mat4 local = to_glm(node->mTransformation);
  const glm::mat4 global = parent < 0 ? local : out[static_cast<std::size_t>(parent)].global * local;
  out.push_back({node, parent, local, global});
  const auto self = static_cast<std::int32_t>(out.size() - 1);
  for (unsigned i = 0; i < node->mNumChildren; ++i) flatten(node->mChildren[i], self, out, depth + 1);
}

Material convert_material(const aiScene& scene, const aiMaterial& source, std::size_t index, const std::string& file,
                          const ReferencePolicy& policy, std::vector<std::string>& used,
                          std::vector<std::string>& warnings) {
  Material m;
  aiString raw;
  m.name =
      unique_material_name(source.Get(AI_MATKEY_NAME, raw) == AI_SUCCESS ? std::string(raw.C_Str()) : "", index, used);
  aiColor3D c;
  if (source.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS) m.diffuse = {c.r, c.g, c.b};
  if (source.Get(AI_MATKEY_COLOR_AMBIENT, c) == AI_SUCCESS) m.ambient = {c.r, c.g, c.b};
  if (source.Get(AI_MATKEY_COLOR_SPECULAR, c) == AI_SUCCESS) m.specular = {c.r, c.g, c.b};
  float value = 0.0f;
  if (source.Get(AI_MATKEY_OPACITY, value) == AI_SUCCESS && std::isfinite(value))
    m.opacity = std::clamp(value, 0.0f, 1.0f);
  if (source.Get(AI_MATKEY_SHININESS, value) == AI_SUCCESS && std::isfinite(value)) m.shininess = std::max(value, 0.0f);
  aiString texture;
  if (source.GetTexture(aiTextureType_DIFFUSE, 0, &texture) == AI_SUCCESS && texture.length > 0) {
    const std::string path = texture.C_Str();
    if (path[0] == '*' || scene.GetEmbeddedTexture(texture.C_Str()) != nullptr)
      warnings.push_back("material '" + m.name + "': embedded texture '" + path + "' is not extracted");
    else
      m.diffuse_map = referenced_texture(file, path, "materials[" + std::to_string(index) + "] diffuse texture", policy,
                                         m.name, warnings);
  }
  return m;
}

// Key times must increase strictly: a key at or before its predecessor is dropped (counted in `dropped`).
template <class T, class Key, class Convert>
Track<T> convert_track(const Key* keys, unsigned count, double ticks_per_second, Convert convert, std::size_t& dropped,
                       const std::string& file, const std::string& element) {
  Track<T> track;
  track.times.reserve(count);
  track.values.reserve(count);
  for (unsigned k = 0; k < count; ++k) {
    const auto time = static_cast<float>(keys[k].mTime / ticks_per_second);
    const T value = convert(keys[k].mValue);
    if (!std::isfinite(time) || !finite(value))
      throw Error::in_file(file, element, "key " + std::to_string(k) + " is not finite");
    if (!track.times.empty() && !(time > track.times.back())) {
      ++dropped;
      continue;
    }
    track.times.push_back(time);
    track.values.push_back(value);
  }
  return track;
}

// A mesh placed by a node.
struct Instance {
  std::int32_t node;
  const aiMesh* mesh;
};

// One weight of a mesh's vertex, as its aiBones list them.
struct Weight {
  std::uint32_t vertex;
  std::uint16_t bone;
  float weight;
};

// The Assimp reader: each step reads one part of the scene into the ImportedModel, in the order below (run()).
class AssimpImport {
 public:
  AssimpImport(const std::string& path, const ImportOptions& options) : path_(path), options_(options) {}
  ImportedModel run();

 private:
  void load();
  void read_nodes();
  void find_instances();
  void choose_needed();
  void find_root();
  void make_bones();
  void find_mesh_frames();
  std::int32_t bone_id_of(const aiBone* bone) const {
    const auto found = node_by_name_.find(bone->mName.C_Str());
    return found != node_by_name_.end() ? bone_of_node_[static_cast<std::size_t>(found->second)]
                                        : orphan_bone_.at(bone->mName.C_Str());
  }
  void bind_bones();
  void read_meshes();
  void sorted_weights(const aiMesh& source, const std::string& element);
  void add_vertices(std::size_t i, const std::string& element);
  void add_faces(std::size_t i, const std::string& element);
  void read_clips();
  void read_clip(unsigned a, const RestLocals& rest, std::vector<std::string>& clip_names);
  float parent_scale(std::size_t bone) const {
    return split(nodes_[static_cast<std::size_t>(nodes_[static_cast<std::size_t>(node_of_bone_[bone])].parent)].global)
        .scale;
  }
  glm::vec3 to_skeleton_translation(std::size_t bone, glm::vec3 t) const {
    return bone == 0 ? glm::vec3(root_parent_world_ * glm::vec4(t, 1.0f)) : parent_scale(bone) * t;
  }
  glm::quat to_skeleton_rotation(std::size_t bone, glm::quat q) const {
    return bone == 0 ? glm::normalize(root_parent_.rotation * q) : glm::normalize(q);
  }

  const std::string& path_;
  const ImportOptions& options_;
  Assimp::Importer importer_;
  const aiScene* scene_ = nullptr;
  ImportedModel result_;
  std::vector<std::string>& warnings_ = result_.warnings;
  std::vector<Node> nodes_;
  std::map<std::string, std::int32_t> node_by_name_;  // first node of each name, as Assimp looks bones up
  std::vector<Instance> instances_;
  bool rigged_ = false;
  std::vector<bool> needed_, animated_;
  std::vector<std::string> orphans_;
  std::int32_t root_ = -1;
  std::vector<std::int32_t> bone_of_node_, node_of_bone_;
  std::vector<Bone> bones_;
  std::vector<glm::mat4> bind_world_;  // with scale (file_bind_world)
  std::vector<bool> has_offset_;
  std::map<std::string, std::int32_t> orphan_bone_;
  std::vector<glm::mat4> mesh_frame_;
  PointMerger points_{result_.model.mesh.positions, result_.model.weights};
  std::vector<Weight> vertex_weights_;
  std::size_t unweighted_ = 0, skipped_faces_ = 0;
  bool any_uvs_ = false;
  glm::mat4 root_parent_world_{1.0f};  // the world transform above the root bone (clips' skeleton space)
  Split root_parent_;
};

ImportedModel AssimpImport::run() {
  load();
  result_.model.name = utf8_path::to_utf8(utf8_path::from_utf8(path_).stem());
  // The up axis the file declares, where Assimp reads one (its FBX reader; glTF is +Y by definition).
  int up_axis = 1, up_sign = 1;
  if (scene_->mMetaData != nullptr && scene_->mMetaData->Get("UpAxis", up_axis) && up_axis >= 0 && up_axis <= 2) {
    scene_->mMetaData->Get("UpAxisSign", up_sign);
    result_.up = glm::vec3(0.0f);
    result_.up[up_axis] = up_sign < 0 ? -1.0f : 1.0f;
  }
  read_nodes();
  find_instances();
  choose_needed();
  find_root();
  make_bones();
  find_mesh_frames();
  bind_bones();
  read_meshes();
  if (rigged_) read_clips();
  return std::move(result_);
}

void AssimpImport::load() {
  importer_.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);  // no $AssimpFbx$ helper nodes
  importer_.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                         aiProcess_GenSmoothNormals | aiProcess_ValidateDataStructure;
  auto* io = new ConfinedIOSystem(path_, options_.references);  // the importer owns it
  importer_.SetIOHandler(io);
  scene_ = importer_.ReadFile(utf8_path::to_utf8(absolute_path(utf8_path::from_utf8(path_))), flags);
  if (io->refusal()) throw Error(*io->refusal());
  if (scene_ == nullptr || scene_->mRootNode == nullptr || (scene_->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    if (io->probe_refusal()) throw Error(*io->probe_refusal());  // the file it looked for is the likely reason
    const char* message = importer_.GetErrorString();
    throw Error::in_file(
        path_, "", std::string("Assimp cannot import it: ") + (message && *message ? message : "incomplete scene"));
  }
  if (io->probe_refusal())
    result_.warnings.push_back(io->probe_refusal()->element() + ": " + io->probe_refusal()->message() +
                               "; read without it");
}

void AssimpImport::read_nodes() {
  try {
    flatten(scene_->mRootNode, -1, nodes_);
  } catch (const Error& e) {
    throw Error::in_file(path_, e.element(), e.message());
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i)
    node_by_name_.emplace(nodes_[i].node->mName.C_Str(), static_cast<std::int32_t>(i));
  for (const Node& n : nodes_)
    if (!finite(n.global))
      throw Error::in_file(path_, "node '" + std::string(n.node->mName.C_Str()) + "'", "transform is not finite");
}

// Mesh instances: (node, mesh), in node pre-order; whether any is skinned, and the skin listing.
void AssimpImport::find_instances() {
  for (std::size_t i = 0; i < nodes_.size(); ++i)
    for (unsigned k = 0; k < nodes_[i].node->mNumMeshes; ++k) {
      const unsigned index = nodes_[i].node->mMeshes[k];
      if (index >= scene_->mNumMeshes) throw Error::in_file(path_, "mesh " + std::to_string(index), "out of range");
      const aiMesh* mesh = scene_->mMeshes[index];
      if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
      instances_.push_back({static_cast<std::int32_t>(i), mesh});
      rigged_ = rigged_ || mesh->mNumBones > 0;
    }
  if (instances_.empty()) throw Error::in_file(path_, "", "the scene has no triangles");
  result_.rigged = rigged_;
  if (!rigged_) return;
  // One skin for the listing (ImportedModel::skins): the distinct bones the meshes name, the meshes with bones.
  ImportedSkin listed;
  std::vector<std::string> joints;
  for (const Instance& instance : instances_) {
    if (instance.mesh->mNumBones == 0) continue;
    for (unsigned b = 0; b < instance.mesh->mNumBones; ++b)
      if (instance.mesh->mBones[b] != nullptr) joints.emplace_back(instance.mesh->mBones[b]->mName.C_Str());
    std::string name = instance.mesh->mName.C_Str();
    if (std::find(listed.meshes.begin(), listed.meshes.end(), name) == listed.meshes.end())
      listed.meshes.push_back(std::move(name));
  }
  std::sort(joints.begin(), joints.end());
  listed.joints = static_cast<std::size_t>(std::unique(joints.begin(), joints.end()) - joints.begin());
  result_.skins.push_back(std::move(listed));
}

// --- which nodes become bones ---
// Skinning needs the bones' nodes and, for vertices with no weight, their mesh's node. Orphan aiBones (no node of
// that name) become static bones under their mesh's node.
void AssimpImport::choose_needed() {
  needed_.assign(nodes_.size(), false);
  if (rigged_) {
    for (const Instance& instance : instances_) {
      std::vector<bool> weighted(instance.mesh->mNumVertices, false);
      for (unsigned b = 0; b < instance.mesh->mNumBones; ++b) {
        const aiBone* bone = instance.mesh->mBones[b];
        const auto found = node_by_name_.find(bone->mName.C_Str());
        if (found != node_by_name_.end()) {
          needed_[static_cast<std::size_t>(found->second)] = true;
        } else {
          needed_[static_cast<std::size_t>(instance.node)] = true;
          if (std::find(orphans_.begin(), orphans_.end(), bone->mName.C_Str()) == orphans_.end())
            orphans_.emplace_back(bone->mName.C_Str());
        }
        for (unsigned w = 0; w < bone->mNumWeights; ++w)
          if (bone->mWeights[w].mVertexId < weighted.size() && bone->mWeights[w].mWeight > 0.0f)
            weighted[bone->mWeights[w].mVertexId] = true;
      }
      if (std::find(weighted.begin(), weighted.end(), false) != weighted.end())
        needed_[static_cast<std::size_t>(instance.node)] = true;
    }
  }
  animated_.assign(nodes_.size(), false);
  for (unsigned a = 0; a < scene_->mNumAnimations; ++a)
    for (unsigned c = 0; c < scene_->mAnimations[a]->mNumChannels; ++c) {
      const auto found = node_by_name_.find(scene_->mAnimations[a]->mChannels[c]->mNodeName.C_Str());
      if (found != node_by_name_.end()) animated_[static_cast<std::size_t>(found->second)] = true;
    }
}

// Root: the lowest common ancestor of the needed nodes, raised to its topmost animated ancestor so that no motion
// above the skeleton is lost.
void AssimpImport::find_root() {
  const auto parent = [&](std::int32_t n) { return nodes_[static_cast<std::size_t>(n)].parent; };
  auto depth = [&](std::int32_t n) {
    int d = 0;
    for (; parent(n) >= 0; n = parent(n)) ++d;
    return d;
  };
  std::int32_t& root = root_;
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (!needed_[i]) continue;
    auto n = static_cast<std::int32_t>(i);
    if (root < 0) {
      root = n;
      continue;
    }
    int dn = depth(n), dr = depth(root);
    for (; dn > dr; --dn) n = parent(n);
    for (; dr > dn; --dr) root = parent(root);
    while (n != root) {
      n = parent(n);
      root = parent(root);
    }
  }
  if (root >= 0)
    for (std::int32_t n = parent(root); n >= 0; n = parent(n))
      if (animated_[static_cast<std::size_t>(n)]) root = n;
}

// --- bones: every node on a path from the root to a needed node, in pre-order, then the orphans ---
void AssimpImport::make_bones() {
  bone_of_node_.assign(nodes_.size(), -1);
  std::size_t shortened = 0;
  if (root_ >= 0) {
    std::vector<std::int32_t> node_parents(nodes_.size());
    for (std::size_t i = 0; i < nodes_.size(); ++i) node_parents[i] = nodes_[i].parent;
    const std::vector<bool> in_skeleton = skeleton_nodes(node_parents, needed_, root_);
    // One top node (the root), so node i is bone i of the forest.
    std::vector<std::string> names;
    std::vector<std::int32_t> parents;
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      if (!in_skeleton[i]) continue;
      names.emplace_back(nodes_[i].node->mName.C_Str());
      parents.push_back(
          static_cast<std::int32_t>(i) == root_ ? -1 : bone_of_node_[static_cast<std::size_t>(nodes_[i].parent)]);
      bone_of_node_[i] = static_cast<std::int32_t>(node_of_bone_.size());
      node_of_bone_.push_back(static_cast<std::int32_t>(i));
    }
    bones_ = bones_of_forest(names, parents, shortened).bones;
  } else {
    bones_ = bones_of_forest({}, {}, shortened).bones;  // static scene: one bone at the origin holds every point
    node_of_bone_.push_back(-1);
  }
  bind_world_.assign(bones_.size(), glm::mat4(1.0f));
  has_offset_.assign(bones_.size(), false);
  for (const std::string& name : orphans_) {
    orphan_bone_[name] = static_cast<std::int32_t>(bones_.size());
    Bone bone;
    bone.name = fit_name(name, shortened);
    bones_.push_back(std::move(bone));  // parent set from its mesh's node below
    node_of_bone_.push_back(-1);
    bind_world_.emplace_back(1.0f);
    has_offset_.push_back(false);
  }
  require_bone_count(bones_.size(), path_);
  warn_shortened_names(shortened, warnings_);
}

// The frame each mesh instance's vertices are bound in. Assimp draws a skinned vertex at Σ w · G_bone · offset · v,
// whatever its mesh node holds; when every bone of a fully weighted mesh agrees on G_bone · offset at rest (the
// node tree at rest is the pose the mesh was bound in) that common matrix is where the file shows the mesh. It
// can differ from the mesh node's transform: DirectX .x files keep a frame transform on the mesh that D3DX skinning
// ignores (BCN_Epileptic.X has its torso, head and legs under three differently turned frames, which drawn with
// the frame transform fall apart). Otherwise (no consensus: the node tree is posed away from the bind, or some
// vertices are carried by the node itself) the mesh node's transform is the bind frame.
void AssimpImport::find_mesh_frames() {
  auto close = [](const glm::mat4& a, const glm::mat4& b) {
    float difference = 0.0f;
    for (int c = 0; c < 4; ++c) difference = std::max(difference, glm::length(a[c] - b[c]));
    return difference <= 1e-4f * std::max(1.0f, std::max(glm::length(glm::vec3(a[3])), glm::length(glm::vec3(b[3]))));
  };
  mesh_frame_.resize(instances_.size());
  for (std::size_t i = 0; i < instances_.size(); ++i) {
    const aiMesh& source = *instances_[i].mesh;
    const glm::mat4& node_world = nodes_[static_cast<std::size_t>(instances_[i].node)].global;
    mesh_frame_[i] = node_world;
    if (source.mNumBones == 0) continue;
    std::vector<bool> weighted(source.mNumVertices, false);
    bool consensus = true, first = true;
    glm::mat4 common(1.0f);
    for (unsigned b = 0; b < source.mNumBones && consensus; ++b) {
      const aiBone* bone = source.mBones[b];
      for (unsigned w = 0; w < bone->mNumWeights; ++w)
        if (bone->mWeights[w].mVertexId < weighted.size() && bone->mWeights[w].mWeight > 0.0f)
          weighted[bone->mWeights[w].mVertexId] = true;
      const auto found = node_by_name_.find(bone->mName.C_Str());
      if (found == node_by_name_.end()) {
        consensus = false;  // an orphan bone has no node-tree transform to agree with
        continue;
      }
      const glm::mat4 drawn = nodes_[static_cast<std::size_t>(found->second)].global * to_glm(bone->mOffsetMatrix);
      if (first) {
        common = drawn;
        first = false;
      } else {
        consensus = close(drawn, common);
      }
    }
    consensus = consensus && !first && std::find(weighted.begin(), weighted.end(), false) == weighted.end();
    if (consensus && finite(common) && std::fabs(glm::determinant(glm::mat3(common))) > 0.0f &&
        !close(common, node_world)) {
      mesh_frame_[i] = common;
    }
  }
}

// Bind world transforms: mesh frame · offset⁻¹ for bones with an offset (the pose the mesh was bound in); a bone
// without one binds at its node-tree transform, where Assimp draws what hangs rigidly on it. Then the skeleton of
// their rigid parts; scale that cannot be folded into translations is reported.
void AssimpImport::bind_bones() {
  std::size_t inconsistent_binds = 0;
  for (std::size_t i = 0; rigged_ && i < instances_.size(); ++i) {
    const Instance& instance = instances_[i];
    for (unsigned b = 0; b < instance.mesh->mNumBones; ++b) {
      const aiBone* bone = instance.mesh->mBones[b];
      const auto id = static_cast<std::size_t>(bone_id_of(bone));
      const glm::mat4 offset = to_glm(bone->mOffsetMatrix);
      const glm::mat4 world = mesh_frame_[i] * glm::inverse(offset);
      if (!finite(world))
        throw Error::in_file(path_, "bone '" + std::string(bone->mName.C_Str()) + "'",
                             "offset matrix is singular or not finite");
      if (!has_offset_[id]) {
        bind_world_[id] = world;
        has_offset_[id] = true;
        if (node_of_bone_[id] < 0) bones_[id].parent = bone_of_node_[static_cast<std::size_t>(instance.node)];
      } else {
        float difference = 0.0f;
        for (int c = 0; c < 4; ++c) difference = std::max(difference, glm::length(world[c] - bind_world_[id][c]));
        if (difference > 1e-4f * std::max(1.0f, glm::length(glm::vec3(world[3])))) ++inconsistent_binds;
      }
    }
  }
  for (std::size_t b = 0; b < bones_.size(); ++b)
    if (!has_offset_[b] && node_of_bone_[b] >= 0)
      bind_world_[b] = nodes_[static_cast<std::size_t>(node_of_bone_[b])].global;
  if (inconsistent_binds > 0)
    warnings_.push_back(std::to_string(inconsistent_binds) +
                        " bone offsets disagree between meshes: the first mesh's bind is used");
  std::vector<Split> bind_split(bones_.size());
  std::size_t scaled = 0;
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    bind_split[b] = split(bind_world_[b]);
    bool exact = bind_split[b].similarity;
    if (node_of_bone_[b] >= 0) {
      const Split rest = split(nodes_[static_cast<std::size_t>(node_of_bone_[b])].global);
      exact = exact && rest.similarity && std::fabs(rest.scale - bind_split[b].scale) <= 1e-3f * rest.scale;
    }
    if (!exact) ++scaled;
  }
  if (scaled > 0)
    warnings_.push_back(std::to_string(scaled) +
                        " bones have non-uniform, mirrored or bind-vs-node-tree differing scale: a Skeleton holds no "
                        "scale, so clips move them approximately (the bind pose stays exact)");
  result_.model.skeleton = skeleton_from_binds(bones_, bind_split, path_);
  result_.file_bind_world = bind_world_;
}

// --- mesh, materials and weights ---
void AssimpImport::read_meshes() {
  Mesh& mesh = result_.model.mesh;
  std::vector<std::string> used_names;
  for (unsigned m = 0; m < scene_->mNumMaterials; ++m)
    mesh.materials.push_back(
        convert_material(*scene_, *scene_->mMaterials[m], m, path_, options_.references, used_names, warnings_));
  any_uvs_ =
      std::any_of(instances_.begin(), instances_.end(), [](const Instance& i) { return i.mesh->HasTextureCoords(0); });
  for (std::size_t i = 0; i < instances_.size(); ++i) {
    const aiMesh& source = *instances_[i].mesh;
    const std::string element = "mesh '" + std::string(source.mName.C_Str()) + "'";
    sorted_weights(source, element);
    if (mesh.vertex_point.size() + source.mNumVertices > 0xFFFFFFFFull)
      throw Error::in_file(path_, element, "too many vertices");
    add_vertices(i, element);
    add_faces(i, element);
  }
  close_triangle_faces(mesh, path_);
  if (unweighted_ > 0)
    warnings_.push_back(std::to_string(unweighted_) +
                        " vertices have no bone weight: bound rigidly to their mesh's node");
  if (skipped_faces_ > 0) warnings_.push_back(std::to_string(skipped_faces_) + " faces that are not triangles skipped");
  if (!orphans_.empty())
    warnings_.push_back(std::to_string(orphans_.size()) + " bones have no node in the hierarchy (first: '" +
                        orphans_[0] + "'): kept static under their mesh's node");
}

// The mesh's positive weights by vertex, strongest first (ties: lower bone first), into vertex_weights_.
void AssimpImport::sorted_weights(const aiMesh& source, const std::string& element) {
  vertex_weights_.clear();
  for (unsigned b = 0; b < source.mNumBones; ++b) {
    const aiBone* bone = source.mBones[b];
    const auto id = static_cast<std::uint16_t>(bone_id_of(bone));
    for (unsigned w = 0; w < bone->mNumWeights; ++w) {
      const aiVertexWeight& vw = bone->mWeights[w];
      if (vw.mVertexId >= source.mNumVertices || !std::isfinite(vw.mWeight) || vw.mWeight < 0.0f)
        throw Error::in_file(path_, element + ": bone '" + bone->mName.C_Str() + "'",
                             "weight " + std::to_string(w) + " is negative, not finite or names no vertex");
      if (vw.mWeight > 0.0f) vertex_weights_.push_back({vw.mVertexId, id, vw.mWeight});
    }
  }
  std::sort(vertex_weights_.begin(), vertex_weights_.end(), [](const Weight& a, const Weight& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.weight != b.weight ? a.weight > b.weight : a.bone < b.bone;
  });
}

// Instance `i`'s vertices in its mesh frame, each with its point (every influence kept), normal and UV.
void AssimpImport::add_vertices(std::size_t i, const std::string& element) {
  Mesh& mesh = result_.model.mesh;
  const Instance& instance = instances_[i];
  const aiMesh& source = *instance.mesh;
  const glm::mat4& frame = mesh_frame_[i];
  const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(frame)));
  const std::int32_t node_bone = bone_of_node_[static_cast<std::size_t>(instance.node)];
  const std::uint16_t rigid_bone = rigged_ ? static_cast<std::uint16_t>(node_bone < 0 ? 0 : node_bone) : 0;
  std::vector<Influence> influences;
  std::size_t cursor = 0;
  for (unsigned v = 0; v < source.mNumVertices; ++v) {
    float total = 0.0f;
    const std::size_t begin = cursor;
    for (; cursor < vertex_weights_.size() && vertex_weights_[cursor].vertex == v; ++cursor)
      total += vertex_weights_[cursor].weight;
    influences.clear();
    for (std::size_t k = begin; k < cursor; ++k)  // strongest first (sorted_weights)
      influences.push_back({vertex_weights_[k].bone, vertex_weights_[k].weight / total});
    if (influences.empty()) {
      if (rigged_) ++unweighted_;
      influences.push_back({rigid_bone, 1.0f});
    }
    const glm::vec3 position = glm::vec3(frame * glm::vec4(to_glm(source.mVertices[v]), 1.0f));
    if (!finite(position))
      throw Error::in_file(path_, element + ": vertex " + std::to_string(v), "position is not finite");
    mesh.vertex_point.push_back(points_.add(position, influences).first);
    glm::vec3 normal = source.HasNormals() ? normal_matrix * to_glm(source.mNormals[v]) : glm::vec3(0.0f);
    const float length = glm::length(normal);
    normal = std::isfinite(length) && length > 0.0f ? normal / length : glm::vec3(0.0f, 0.0f, 1.0f);
    mesh.vertex_normals.push_back(normal);
    if (any_uvs_) {
      const glm::vec3 uv = source.HasTextureCoords(0) ? to_glm(source.mTextureCoords[0][v]) : glm::vec3(0.0f);
      mesh.vertex_uvs.emplace_back(std::isfinite(uv.x) ? uv.x : 0.0f, std::isfinite(uv.y) ? uv.y : 0.0f);
    }
  }
}

// Instance `i`'s triangles as one submesh; faces that are not triangles are skipped (counted).
void AssimpImport::add_faces(std::size_t i, const std::string& element) {
  Mesh& mesh = result_.model.mesh;
  const aiMesh& source = *instances_[i].mesh;
  const auto first_vertex = mesh.vertex_point.size() - source.mNumVertices;
  Submesh submesh;
  submesh.first_triangle = static_cast<std::uint32_t>(mesh.triangle_count());
  submesh.material =
      source.mMaterialIndex < mesh.materials.size() ? static_cast<std::int32_t>(source.mMaterialIndex) : -1;
  for (unsigned f = 0; f < source.mNumFaces; ++f) {
    const aiFace& face = source.mFaces[f];
    if (face.mNumIndices != 3) {
      ++skipped_faces_;
      continue;
    }
    for (unsigned c = 0; c < 3; ++c) {
      if (face.mIndices[c] >= source.mNumVertices)
        throw Error::in_file(path_, element + ": face " + std::to_string(f), "index out of range");
      mesh.triangles.push_back(static_cast<std::uint32_t>(first_vertex + face.mIndices[c]));
    }
  }
  submesh.triangle_count = static_cast<std::uint32_t>(mesh.triangle_count()) - submesh.first_triangle;
  mesh.submeshes.push_back(std::move(submesh));
  result_.submesh_names.push_back(
      {nodes_[static_cast<std::size_t>(instances_[i].node)].node->mName.C_Str(), source.mName.C_Str()});
}

// --- clips ---
// Skeleton space: a bone's local transform is T(s_p · t) · R(q), s_p the parent node's uniform world scale
// (uniform scale commutes with rotation, so it folds into child translations); the root takes its parent's
// whole world transform A: T(A · t) · R(rot(A) · q).
void AssimpImport::read_clips() {
  const std::int32_t above_root = nodes_[static_cast<std::size_t>(node_of_bone_[0])].parent;
  root_parent_world_ = above_root < 0 ? glm::mat4(1.0f) : nodes_[static_cast<std::size_t>(above_root)].global;
  root_parent_ = split(root_parent_world_);
  // Rest locals (the node tree) of bones whose rest differs from their bind: clips hold them with a constant
  // channel, as Assimp leaves unanimated nodes at their node-tree transform.
  std::vector<std::pair<glm::vec3, glm::quat>> local(bones_.size());
  std::vector<bool> has_rest(bones_.size(), false);
  for (std::size_t b = 0; b < bones_.size(); ++b) {
    if (node_of_bone_[b] < 0) continue;
    const Split split_local = split(nodes_[static_cast<std::size_t>(node_of_bone_[b])].local);
    local[b] = {to_skeleton_translation(b, split_local.translation), to_skeleton_rotation(b, split_local.rotation)};
    has_rest[b] = true;
  }
  const RestLocals rest = rest_locals(result_.model.skeleton, result_.model.mesh.positions, std::move(local), has_rest);
  std::vector<std::string> clip_names;
  for (unsigned a = 0; a < scene_->mNumAnimations; ++a) read_clip(a, rest, clip_names);
}

void AssimpImport::read_clip(unsigned a, const RestLocals& rest, std::vector<std::string>& clip_names) {
  const aiAnimation& source = *scene_->mAnimations[a];
  Animation clip;
  clip.name = unique_clip_name(source.mName.C_Str(), a, clip_names);
  const std::string element = "clip '" + clip.name + "'";
  double ticks = source.mTicksPerSecond;
  if (!(ticks > 0.0) || !std::isfinite(ticks)) {
    ticks = options_.default_ticks_per_second;
    warnings_.push_back(element + ": no time base in the file, " + std::to_string(ticks) + " ticks per second assumed");
  }
  clip.duration = static_cast<float>(source.mDuration / ticks);
  if (!std::isfinite(clip.duration) || clip.duration < 0.0f)
    throw Error::in_file(path_, element, "duration is not finite");
  clip.loop = options_.loop_clips;
  std::vector<bool> has_channel(bones_.size(), false);
  std::size_t dropped = 0, scaled_bones = 0;
  for (unsigned c = 0; c < source.mNumChannels; ++c) {
    const aiNodeAnim& channel = *source.mChannels[c];
    const auto found = node_by_name_.find(channel.mNodeName.C_Str());
    if (found == node_by_name_.end()) continue;
    const std::int32_t bone = bone_of_node_[static_cast<std::size_t>(found->second)];
    if (bone < 0 || has_channel[static_cast<std::size_t>(bone)]) continue;  // not in the skeleton, or repeated
    const auto b = static_cast<std::size_t>(bone);
    has_channel[b] = true;
    const std::string channel_element = element + ": bone '" + bones_[b].name + "'";
    Channel out;
    out.bone = bone;
    out.translation = convert_track<glm::vec3>(
        channel.mPositionKeys, channel.mNumPositionKeys, ticks,
        [&](const aiVector3D& v) { return to_skeleton_translation(b, to_glm(v)); }, dropped, path_, channel_element);
    out.rotation = convert_track<glm::quat>(
        channel.mRotationKeys, channel.mNumRotationKeys, ticks,
        [&](const aiQuaternion& q) { return to_skeleton_rotation(b, to_glm(q)); }, dropped, path_, channel_element);
    const glm::vec3 rest_scale = split(nodes_[static_cast<std::size_t>(found->second)].local).axis_scale;
    out.scale = convert_track<glm::vec3>(
        channel.mScalingKeys, channel.mNumScalingKeys, ticks,
        [&](const aiVector3D& v) { return to_glm(v) / rest_scale; }, dropped, path_, channel_element);
    if (std::any_of(out.scale.values.begin(), out.scale.values.end(),
                    [](glm::vec3 s) { return glm::length(s - glm::vec3(1.0f)) > 1e-3f; }))
      ++scaled_bones;
    clip.channels.push_back(std::move(out));
  }
  hold_rest(clip, rest, has_channel);
  add_clip(std::move(clip), dropped, scaled_bones, bones_.size(), path_, result_.clips, warnings_);
}

}  // namespace

bool is_importable(const std::string& path) {
  const std::string extension = utf8_path::to_utf8(utf8_path::from_utf8(path).extension());
  if (extension.size() < 2) return false;
  Assimp::Importer importer;
  return importer.IsExtensionSupported(extension.c_str());
}

// Warnings quote names and paths from the file: each is escaped as errors are (one printable line each).
ImportedModel import_model(const std::string& path, const ImportOptions& options) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) throw Error::in_file(path, "", "no such file");
  const auto size = fs::file_size(path, error);
  if (error || size > max_file_bytes) throw Error::in_file(path, "", "cannot be read or larger than 1 GiB");
  ImportedModel result = is_gltf_path(path)  ? import_gltf(path, options)
                         : is_iqm_path(path) ? import_iqm(path, options)
                                             : AssimpImport(path, options).run();
  for (std::string& warning : result.warnings) warning = escape_control_characters(warning);
  return result;
}

}  // namespace deform
