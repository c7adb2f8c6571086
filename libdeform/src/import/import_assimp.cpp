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
#include "utf8_path.hpp"
#include "finite.hpp"
namespace deform {
namespace {

namespace fs = std::filesystem;
using namespace import_detail;

// Every file Assimp opens while it reads a model (an .md5anim beside an .md5mesh, an MD3's skins, an Ogre
// .material) is a file the model names: it is opened only inside the model's folder or a folder the policy allows
// (resolve_referenced_file). A refusal cannot travel through Assimp as an exception: it is kept, the open fails, and
// import_model throws it once ReadFile returns. Exists() answers false for a refused file, so whether a file outside
// exists never shows.
class ConfinedIOSystem : public Assimp::DefaultIOSystem {
 public:
  ConfinedIOSystem(const std::string& model, const ReferencePolicy& policy) : model_(model), policy_(policy) {}

  bool Exists(const char* file) const override { return allowed(file) && Assimp::DefaultIOSystem::Exists(file); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!allowed(file)) return nullptr;
    return Assimp::DefaultIOSystem::Open(file, mode);
  }
  // The first refusal, if any.
  const std::optional<Error>& refusal() const { return refusal_; }

 private:
  bool allowed(const char* file) const {
    if (file == nullptr) return false;
    try {
      std::error_code error;
      // Assimp joins the folder; its names are UTF-8 (its Windows IO system opens them as wide names).
      const std::string absolute =
          utf8_path::to_utf8(fs::absolute(utf8_path::from_utf8(file), error).lexically_normal());
      if (error) return false;
      resolve_referenced_file(model_, absolute, "a file the importer opened", policy_);
      return true;
    } catch (const Error& e) {
      if (!refusal_) refusal_ = e;
      return false;
    }
  }
  std::string model_;
  const ReferencePolicy& policy_;
  mutable std::optional<Error> refusal_;
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

std::string material_name(const aiMaterial& material, std::size_t index, std::vector<std::string>& used) {
  aiString raw;
  std::string name = material.Get(AI_MATKEY_NAME, raw) == AI_SUCCESS ? std::string(raw.C_Str()) : std::string();
  for (char& c : name)
    if (std::isspace(static_cast<unsigned char>(c)) || static_cast<unsigned char>(c) < 0x20) c = '_';
  if (name.empty() || std::find(used.begin(), used.end(), name) != used.end())
    name = "material" + std::to_string(index);
  used.push_back(name);
  return name;
}

Material convert_material(const aiScene& scene, const aiMaterial& source, std::size_t index, const std::string& file,
                          const ReferencePolicy& policy, std::vector<std::string>& used,
                          std::vector<std::string>& warnings) {
  Material m;
  m.name = material_name(source, index, used);
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
    std::string path = texture.C_Str();
    if (path[0] == '*' || scene.GetEmbeddedTexture(texture.C_Str()) != nullptr) {
      warnings.push_back("material '" + m.name + "': embedded texture '" + path + "' is not extracted");
    } else {
      std::replace(path.begin(), path.end(), '\\', '/');
      // Confined to the model's folder like every file a model names (resolve_referenced_file); first, as it
      // refuses a name that is no path (not UTF-8, on Windows).
      const std::string real =
          resolve_referenced_file(file, path, "materials[" + std::to_string(index) + "] diffuse texture", policy);
      fs::path resolved = utf8_path::from_utf8(path);
      if (resolved.is_relative()) resolved = utf8_path::from_utf8(file).parent_path() / resolved;
      m.diffuse_map = utf8_path::to_utf8(resolved.lexically_normal());
      std::error_code error;
      if (!fs::is_regular_file(utf8_path::from_utf8(real), error))
        warnings.push_back("material '" + m.name + "': texture '" + m.diffuse_map + "' not found");
    }
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

}  // namespace

bool is_importable(const std::string& path) {
  const std::string extension = utf8_path::to_utf8(utf8_path::from_utf8(path).extension());
  if (extension.size() < 2) return false;
  Assimp::Importer importer;
  return importer.IsExtensionSupported(extension.c_str());
}

namespace {
ImportedModel import_any(const std::string& path, const ImportOptions& options);
}  // namespace

// Warnings quote names and paths from the file: each is escaped as errors are (one printable line each).
ImportedModel import_model(const std::string& path, const ImportOptions& options) {
  ImportedModel result = import_any(path, options);
  for (std::string& warning : result.warnings) warning = escape_control_characters(warning);
  return result;
}

namespace {
ImportedModel import_any(const std::string& path, const ImportOptions& options) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) throw Error::in_file(path, "", "no such file");
  const auto size = fs::file_size(path, error);
  if (error || size > max_file_bytes) throw Error::in_file(path, "", "cannot be read or larger than 1 GiB");
  if (is_gltf_path(path)) return import_gltf(path, options);
  if (is_iqm_path(path)) return import_iqm(path, options);

  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);  // no $AssimpFbx$ helper nodes
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                         aiProcess_GenSmoothNormals | aiProcess_ValidateDataStructure;
  auto* io = new ConfinedIOSystem(path, options.references);  // the importer owns it
  importer.SetIOHandler(io);
  const aiScene* scene = importer.ReadFile(path, flags);
  if (io->refusal()) throw Error(*io->refusal());
  if (scene == nullptr || scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    const char* message = importer.GetErrorString();
    throw Error::in_file(
        path, "", std::string("Assimp cannot import it: ") + (message && *message ? message : "incomplete scene"));
  }

  ImportedModel result;
  std::vector<std::string>& warnings = result.warnings;
  result.model.name = utf8_path::to_utf8(utf8_path::from_utf8(path).stem());
  // The up axis the file declares, where Assimp reads one (its FBX reader; glTF is +Y by definition).
  int up_axis = 1, up_sign = 1;
  if (scene->mMetaData != nullptr && scene->mMetaData->Get("UpAxis", up_axis) && up_axis >= 0 && up_axis <= 2) {
    scene->mMetaData->Get("UpAxisSign", up_sign);
    result.up = glm::vec3(0.0f);
    result.up[up_axis] = up_sign < 0 ? -1.0f : 1.0f;
  }

  std::vector<Node> nodes;
  try {
    flatten(scene->mRootNode, -1, nodes);
  } catch (const Error& e) {
    throw Error::in_file(path, e.element(), e.message());
  }
  std::map<std::string, std::int32_t> node_by_name;  // first node of each name, as Assimp looks bones up
  for (std::size_t i = 0; i < nodes.size(); ++i)
    node_by_name.emplace(nodes[i].node->mName.C_Str(), static_cast<std::int32_t>(i));
  for (const Node& n : nodes)
    if (!finite(n.global))
      throw Error::in_file(path, "node '" + std::string(n.node->mName.C_Str()) + "'", "transform is not finite");

  // Mesh instances: (node, mesh), in node pre-order.
  struct Instance {
    std::int32_t node;
    const aiMesh* mesh;
  };
  std::vector<Instance> instances;
  bool rigged = false;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (unsigned k = 0; k < nodes[i].node->mNumMeshes; ++k) {
      const unsigned index = nodes[i].node->mMeshes[k];
      if (index >= scene->mNumMeshes) throw Error::in_file(path, "mesh " + std::to_string(index), "out of range");
      const aiMesh* mesh = scene->mMeshes[index];
      if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
      instances.push_back({static_cast<std::int32_t>(i), mesh});
      rigged = rigged || mesh->mNumBones > 0;
    }
  if (instances.empty()) throw Error::in_file(path, "", "the scene has no triangles");
  result.rigged = rigged;
  if (rigged) {
    // One skin for the listing (ImportedModel::skins): the distinct bones the meshes name, the meshes with bones.
    ImportedSkin listed;
    std::vector<std::string> joints;
    for (const Instance& instance : instances) {
      if (instance.mesh->mNumBones == 0) continue;
      for (unsigned b = 0; b < instance.mesh->mNumBones; ++b)
        if (instance.mesh->mBones[b] != nullptr) joints.emplace_back(instance.mesh->mBones[b]->mName.C_Str());
      std::string name = instance.mesh->mName.C_Str();
      if (std::find(listed.meshes.begin(), listed.meshes.end(), name) == listed.meshes.end())
        listed.meshes.push_back(std::move(name));
    }
    std::sort(joints.begin(), joints.end());
    listed.joints = static_cast<std::size_t>(std::unique(joints.begin(), joints.end()) - joints.begin());
    result.skins.push_back(std::move(listed));
  }

  // --- which nodes become bones ---
  // Skinning needs the bones' nodes and, for vertices with no weight, their mesh's node. Orphan aiBones (no node of
  // that name) become static bones under their mesh's node.
  std::vector<bool> needed(nodes.size(), false);
  std::vector<std::string> orphans;
  if (rigged) {
    for (const Instance& instance : instances) {
      std::vector<bool> weighted(instance.mesh->mNumVertices, false);
      for (unsigned b = 0; b < instance.mesh->mNumBones; ++b) {
        const aiBone* bone = instance.mesh->mBones[b];
        const auto found = node_by_name.find(bone->mName.C_Str());
        if (found != node_by_name.end()) {
          needed[static_cast<std::size_t>(found->second)] = true;
        } else {
          needed[static_cast<std::size_t>(instance.node)] = true;
          if (std::find(orphans.begin(), orphans.end(), bone->mName.C_Str()) == orphans.end())
            orphans.emplace_back(bone->mName.C_Str());
        }
        for (unsigned w = 0; w < bone->mNumWeights; ++w)
          if (bone->mWeights[w].mVertexId < weighted.size() && bone->mWeights[w].mWeight > 0.0f)
            weighted[bone->mWeights[w].mVertexId] = true;
      }
      if (std::find(weighted.begin(), weighted.end(), false) != weighted.end())
        needed[static_cast<std::size_t>(instance.node)] = true;
    }
  }
  std::vector<bool> animated(nodes.size(), false);
  for (unsigned a = 0; a < scene->mNumAnimations; ++a)
    for (unsigned c = 0; c < scene->mAnimations[a]->mNumChannels; ++c) {
      const auto found = node_by_name.find(scene->mAnimations[a]->mChannels[c]->mNodeName.C_Str());
      if (found != node_by_name.end()) animated[static_cast<std::size_t>(found->second)] = true;
    }

  // Root: the lowest common ancestor of the needed nodes, raised to its topmost animated ancestor so that no motion
  // above the skeleton is lost.
  std::int32_t root = -1;
  auto depth = [&](std::int32_t n) {
    int d = 0;
    for (; nodes[static_cast<std::size_t>(n)].parent >= 0; n = nodes[static_cast<std::size_t>(n)].parent) ++d;
    return d;
  };
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (!needed[i]) continue;
    auto n = static_cast<std::int32_t>(i);
    if (root < 0) {
      root = n;
      continue;
    }
    int dn = depth(n), dr = depth(root);
    for (; dn > dr; --dn) n = nodes[static_cast<std::size_t>(n)].parent;
    for (; dr > dn; --dr) root = nodes[static_cast<std::size_t>(root)].parent;
    while (n != root) {
      n = nodes[static_cast<std::size_t>(n)].parent;
      root = nodes[static_cast<std::size_t>(root)].parent;
    }
  }
  if (root >= 0)
    for (std::int32_t n = nodes[static_cast<std::size_t>(root)].parent; n >= 0;
         n = nodes[static_cast<std::size_t>(n)].parent)
      if (animated[static_cast<std::size_t>(n)]) root = n;

  // --- bones: every node on a path from the root to a needed node, in pre-order, then the orphans ---
  std::vector<std::int32_t> bone_of_node(nodes.size(), -1);
  std::vector<std::int32_t> node_of_bone;
  std::vector<Bone> bones;
  std::vector<glm::mat4> bind_world;  // with scale (file_bind_world)
  std::vector<bool> has_offset;
  std::size_t shortened = 0;
  if (root >= 0) {
    std::vector<bool> in_skeleton(nodes.size(), false);
    for (std::size_t i = 0; i < nodes.size(); ++i)
      if (needed[i])
        for (auto n = static_cast<std::int32_t>(i); n >= 0 && !in_skeleton[static_cast<std::size_t>(n)];
             n = n == root ? -1 : nodes[static_cast<std::size_t>(n)].parent)
          in_skeleton[static_cast<std::size_t>(n)] = true;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (!in_skeleton[i]) continue;
      Bone bone;
      bone.name = fit_name(nodes[i].node->mName.C_Str(), shortened);
      bone.parent = static_cast<std::int32_t>(i) == root ? -1 : bone_of_node[static_cast<std::size_t>(nodes[i].parent)];
      bone_of_node[i] = static_cast<std::int32_t>(bones.size());
      node_of_bone.push_back(static_cast<std::int32_t>(i));
      bones.push_back(std::move(bone));
    }
  } else {
    Bone bone;  // static scene: one bone at the origin holds every point
    bone.name = "root";
    bones.push_back(bone);
    node_of_bone.push_back(-1);
  }
  bind_world.assign(bones.size(), glm::mat4(1.0f));
  has_offset.assign(bones.size(), false);
  std::map<std::string, std::int32_t> orphan_bone;
  for (const std::string& name : orphans) {
    orphan_bone[name] = static_cast<std::int32_t>(bones.size());
    Bone bone;
    bone.name = fit_name(name, shortened);
    bones.push_back(std::move(bone));  // parent set from its mesh's node below
    node_of_bone.push_back(-1);
    bind_world.emplace_back(1.0f);
    has_offset.push_back(false);
  }
  if (bones.size() > 65535) throw Error::in_file(path, "", std::to_string(bones.size()) + " bones (at most 65535)");
  if (shortened > 0)
    warnings.push_back(std::to_string(shortened) + " bone names longer than 79 bytes shortened to fit .sk");

  // The frame each mesh instance's vertices are bound in. Assimp draws a skinned vertex at Σ w · G_bone · offset · v,
  // whatever its mesh node holds; when every bone of a fully weighted mesh agrees on G_bone · offset at rest (the
  // node tree at rest is the pose the mesh was bound in) that common matrix is where the file shows the mesh. It
  // can differ from the mesh node's transform: DirectX .x files keep a frame transform on the mesh that D3DX skinning
  // ignores (BCN_Epileptic.X has its torso, head and legs under three differently turned frames, which drawn with
  // the frame transform fall apart). Otherwise (no consensus: the node tree is posed away from the bind, or some
  // vertices are carried by the node itself) the mesh node's transform is the bind frame.
  auto close = [](const glm::mat4& a, const glm::mat4& b) {
    float difference = 0.0f;
    for (int c = 0; c < 4; ++c) difference = std::max(difference, glm::length(a[c] - b[c]));
    return difference <= 1e-4f * std::max(1.0f, std::max(glm::length(glm::vec3(a[3])), glm::length(glm::vec3(b[3]))));
  };
  std::vector<glm::mat4> mesh_frame(instances.size());
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const aiMesh& source = *instances[i].mesh;
    const glm::mat4& node_world = nodes[static_cast<std::size_t>(instances[i].node)].global;
    mesh_frame[i] = node_world;
    if (source.mNumBones == 0) continue;
    std::vector<bool> weighted(source.mNumVertices, false);
    bool consensus = true, first = true;
    glm::mat4 common(1.0f);
    for (unsigned b = 0; b < source.mNumBones && consensus; ++b) {
      const aiBone* bone = source.mBones[b];
      for (unsigned w = 0; w < bone->mNumWeights; ++w)
        if (bone->mWeights[w].mVertexId < weighted.size() && bone->mWeights[w].mWeight > 0.0f)
          weighted[bone->mWeights[w].mVertexId] = true;
      const auto found = node_by_name.find(bone->mName.C_Str());
      if (found == node_by_name.end()) {
        consensus = false;  // an orphan bone has no node-tree transform to agree with
        continue;
      }
      const glm::mat4 drawn = nodes[static_cast<std::size_t>(found->second)].global * to_glm(bone->mOffsetMatrix);
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
      mesh_frame[i] = common;
    }
  }

  // Bind world transforms: mesh frame · offset⁻¹ for bones with an offset (the pose the mesh was bound in).
  std::size_t inconsistent_binds = 0;
  auto bone_id_of = [&](const aiBone* bone) {
    const auto found = node_by_name.find(bone->mName.C_Str());
    return found != node_by_name.end() ? bone_of_node[static_cast<std::size_t>(found->second)]
                                       : orphan_bone.at(bone->mName.C_Str());
  };
  if (rigged) {
    for (std::size_t i = 0; i < instances.size(); ++i) {
      const Instance& instance = instances[i];
      for (unsigned b = 0; b < instance.mesh->mNumBones; ++b) {
        const aiBone* bone = instance.mesh->mBones[b];
        const auto id = static_cast<std::size_t>(bone_id_of(bone));
        const glm::mat4 offset = to_glm(bone->mOffsetMatrix);
        const glm::mat4 world = mesh_frame[i] * glm::inverse(offset);
        if (!finite(world))
          throw Error::in_file(path, "bone '" + std::string(bone->mName.C_Str()) + "'",
                               "offset matrix is singular or not finite");
        if (!has_offset[id]) {
          bind_world[id] = world;
          has_offset[id] = true;
          if (node_of_bone[id] < 0) bones[id].parent = bone_of_node[static_cast<std::size_t>(instance.node)];
        } else {
          float difference = 0.0f;
          for (int c = 0; c < 4; ++c) difference = std::max(difference, glm::length(world[c] - bind_world[id][c]));
          if (difference > 1e-4f * std::max(1.0f, glm::length(glm::vec3(world[3])))) ++inconsistent_binds;
        }
      }
    }
  }
  // A bone without an offset binds at its node-tree transform: that is where Assimp draws what hangs rigidly on it.
  for (std::size_t b = 0; b < bones.size(); ++b)
    if (!has_offset[b] && node_of_bone[b] >= 0) bind_world[b] = nodes[static_cast<std::size_t>(node_of_bone[b])].global;
  if (inconsistent_binds > 0)
    warnings.push_back(std::to_string(inconsistent_binds) +
                       " bone offsets disagree between meshes: the first mesh's bind is used");

  // Rigid bind locals; scale that cannot be folded into translations is reported.
  std::vector<Split> bind_split(bones.size());
  std::size_t scaled = 0;
  for (std::size_t b = 0; b < bones.size(); ++b) {
    bind_split[b] = split(bind_world[b]);
    bool exact = bind_split[b].similarity;
    if (node_of_bone[b] >= 0) {
      const Split rest = split(nodes[static_cast<std::size_t>(node_of_bone[b])].global);
      exact = exact && rest.similarity && std::fabs(rest.scale - bind_split[b].scale) <= 1e-3f * rest.scale;
    }
    if (!exact) ++scaled;
  }
  if (scaled > 0)
    warnings.push_back(std::to_string(scaled) +
                       " bones have non-uniform, mirrored or bind-vs-node-tree differing scale: a Skeleton holds no "
                       "scale, so clips move them approximately (the bind pose stays exact)");
  result.model.skeleton = skeleton_from_binds(bones, bind_split, path);
  result.file_bind_world = bind_world;
  const Skeleton& skeleton = result.model.skeleton;

  // --- mesh, materials and weights ---
  Mesh& mesh = result.model.mesh;
  std::vector<std::string> used_names;
  for (unsigned m = 0; m < scene->mNumMaterials; ++m)
    mesh.materials.push_back(
        convert_material(*scene, *scene->mMaterials[m], m, path, options.references, used_names, warnings));
  const bool any_uvs =
      std::any_of(instances.begin(), instances.end(), [](const Instance& i) { return i.mesh->HasTextureCoords(0); });
  std::unordered_map<PointKey, std::uint32_t, PointKeyHash> point_of_key;
  std::size_t unweighted = 0, skipped_faces = 0;
  ExtraInfluenceIds extra_ids;  // the point key's word for vertices with more than four influences
  struct Weight {
    std::uint32_t vertex;
    std::uint16_t bone;
    float weight;
  };
  std::vector<Weight> vertex_weights;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const Instance& instance = instances[i];
    const aiMesh& source = *instance.mesh;
    const Node& node = nodes[static_cast<std::size_t>(instance.node)];
    const glm::mat4& frame = mesh_frame[i];
    const std::string element = "mesh '" + std::string(source.mName.C_Str()) + "'";
    const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(frame)));
    const std::uint16_t rigid_bone =
        rigged ? static_cast<std::uint16_t>(bone_of_node[static_cast<std::size_t>(instance.node)] < 0
                                                ? 0
                                                : bone_of_node[static_cast<std::size_t>(instance.node)])
               : 0;

    vertex_weights.clear();
    for (unsigned b = 0; b < source.mNumBones; ++b) {
      const aiBone* bone = source.mBones[b];
      const auto id = static_cast<std::uint16_t>(bone_id_of(bone));
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const aiVertexWeight& vw = bone->mWeights[w];
        if (vw.mVertexId >= source.mNumVertices || !std::isfinite(vw.mWeight) || vw.mWeight < 0.0f)
          throw Error::in_file(path, element + ": bone '" + bone->mName.C_Str() + "'",
                               "weight " + std::to_string(w) + " is negative, not finite or names no vertex");
        if (vw.mWeight > 0.0f) vertex_weights.push_back({vw.mVertexId, id, vw.mWeight});
      }
    }
    std::sort(vertex_weights.begin(), vertex_weights.end(), [](const Weight& a, const Weight& b) {
      return a.vertex != b.vertex ? a.vertex < b.vertex : a.weight != b.weight ? a.weight > b.weight : a.bone < b.bone;
    });

    const auto first_vertex = mesh.vertex_point.size();
    if (first_vertex + source.mNumVertices > 0xFFFFFFFFull) throw Error::in_file(path, element, "too many vertices");
    std::size_t cursor = 0;
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      Influences influences;
      float total = 0.0f;
      const std::size_t begin = cursor;
      for (; cursor < vertex_weights.size() && vertex_weights[cursor].vertex == v; ++cursor)
        total += vertex_weights[cursor].weight;
      const std::size_t count = cursor - begin;  // strongest first (sorted above)
      if (count == 0) {
        if (rigged) ++unweighted;
        influences.bones[0] = rigid_bone;
        influences.weights[0] = 1.0f;
      } else {
        // Every influence is kept: the four strongest in the slots, the rest as extras (SkinWeights).
        for (std::size_t k = 0; k < count && k < 4; ++k) {
          influences.bones[k] = vertex_weights[begin + k].bone;
          influences.weights[k] = vertex_weights[begin + k].weight / total;
        }
      }
      const glm::vec3 position = glm::vec3(frame * glm::vec4(to_glm(source.mVertices[v]), 1.0f));
      if (!finite(position))
        throw Error::in_file(path, element + ": vertex " + std::to_string(v), "position is not finite");
      // A vertex with extras merges with the vertices of the same position and the same influences, extras too.
      std::uint32_t extras = 0;
      if (count > 4) {
        for (std::size_t k = 4; k < count; ++k)
          extra_ids.add(vertex_weights[begin + k].bone, vertex_weights[begin + k].weight / total);
        extras = extra_ids.take();
      }
      const auto [found, inserted] = point_of_key.emplace(point_key(position, influences, extras),
                                                          static_cast<std::uint32_t>(mesh.positions.size()));
      if (inserted) {
        const auto point = static_cast<std::uint32_t>(mesh.positions.size());
        mesh.positions.push_back(position);
        SkinWeights& sw = result.model.weights;
        sw.bones.emplace_back(influences.bones[0], influences.bones[1], influences.bones[2], influences.bones[3]);
        sw.weights.emplace_back(influences.weights[0], influences.weights[1], influences.weights[2],
                                influences.weights[3]);
        if (count > 4) {
          if (sw.extra_offsets.empty()) sw.extra_offsets.push_back(0);
          sw.extra_points.push_back(point);
          for (std::size_t k = 4; k < count; ++k) {
            sw.extra_bones.push_back(vertex_weights[begin + k].bone);
            sw.extra_weights.push_back(vertex_weights[begin + k].weight / total);
          }
          sw.extra_offsets.push_back(static_cast<std::uint32_t>(sw.extra_bones.size()));
        }
      }
      mesh.vertex_point.push_back(found->second);
      glm::vec3 normal = source.HasNormals() ? normal_matrix * to_glm(source.mNormals[v]) : glm::vec3(0.0f);
      const float length = glm::length(normal);
      normal = std::isfinite(length) && length > 0.0f ? normal / length : glm::vec3(0.0f, 0.0f, 1.0f);
      mesh.vertex_normals.push_back(normal);
      if (any_uvs) {
        const glm::vec3 uv = source.HasTextureCoords(0) ? to_glm(source.mTextureCoords[0][v]) : glm::vec3(0.0f);
        mesh.vertex_uvs.emplace_back(std::isfinite(uv.x) ? uv.x : 0.0f, std::isfinite(uv.y) ? uv.y : 0.0f);
      }
    }

    Submesh submesh;
    submesh.first_triangle = static_cast<std::uint32_t>(mesh.triangle_count());
    submesh.material =
        source.mMaterialIndex < mesh.materials.size() ? static_cast<std::int32_t>(source.mMaterialIndex) : -1;
    submesh.object = node.node->mName.C_Str();
    submesh.group = source.mName.C_Str();
    for (unsigned f = 0; f < source.mNumFaces; ++f) {
      const aiFace& face = source.mFaces[f];
      if (face.mNumIndices != 3) {
        ++skipped_faces;
        continue;
      }
      for (unsigned c = 0; c < 3; ++c) {
        if (face.mIndices[c] >= source.mNumVertices)
          throw Error::in_file(path, element + ": face " + std::to_string(f), "index out of range");
        mesh.triangles.push_back(static_cast<std::uint32_t>(first_vertex + face.mIndices[c]));
      }
    }
    submesh.triangle_count = static_cast<std::uint32_t>(mesh.triangle_count()) - submesh.first_triangle;
    mesh.submeshes.push_back(std::move(submesh));
  }
  if (mesh.triangles.empty()) throw Error::in_file(path, "", "the scene has no triangles");
  mesh.face_sizes.assign(mesh.triangle_count(), 3);
  mesh.face_corners = mesh.triangles;
  if (unweighted > 0)
    warnings.push_back(std::to_string(unweighted) +
                       " vertices have no bone weight: bound rigidly to their mesh's node");
  if (skipped_faces > 0) warnings.push_back(std::to_string(skipped_faces) + " faces that are not triangles skipped");
  if (!orphans.empty())
    warnings.push_back(std::to_string(orphans.size()) + " bones have no node in the hierarchy (first: '" + orphans[0] +
                       "'): kept static under their mesh's node");
  if (!rigged) return result;

  // --- clips ---
  // Skeleton space: a bone's local transform is T(s_p · t) · R(q), s_p the parent node's uniform world scale
  // (uniform scale commutes with rotation, so it folds into child translations); the root takes its parent's
  // whole world transform A: T(A · t) · R(rot(A) · q).
  const glm::vec3 extent = [&] {
    const Bounds b = compute_bounds(mesh.positions);
    return b.max - b.min;
  }();
  const float model_size = std::max(glm::length(extent), 1e-6f);
  const std::int32_t above_root = nodes[static_cast<std::size_t>(node_of_bone[0])].parent;
  const glm::mat4 root_parent_world =
      above_root < 0 ? glm::mat4(1.0f) : nodes[static_cast<std::size_t>(above_root)].global;
  const Split root_parent = split(root_parent_world);
  auto parent_scale = [&](std::size_t bone) {
    return split(nodes[static_cast<std::size_t>(nodes[static_cast<std::size_t>(node_of_bone[bone])].parent)].global)
        .scale;
  };
  auto to_skeleton_translation = [&](std::size_t bone, glm::vec3 t) {
    return bone == 0 ? glm::vec3(root_parent_world * glm::vec4(t, 1.0f)) : parent_scale(bone) * t;
  };
  auto to_skeleton_rotation = [&](std::size_t bone, glm::quat q) {
    return bone == 0 ? glm::normalize(root_parent.rotation * q) : glm::normalize(q);
  };
  // Rest locals (the node tree) of bones whose rest differs from their bind: clips hold them with a constant
  // channel, as Assimp leaves unanimated nodes at their node-tree transform.
  const Pose bind = skeleton.bind_pose();
  std::vector<std::pair<glm::vec3, glm::quat>> rest_differs(bones.size());
  std::vector<bool> differs(bones.size(), false);
  for (std::size_t b = 0; b < bones.size(); ++b) {
    if (node_of_bone[b] < 0) continue;
    const Split local = split(nodes[static_cast<std::size_t>(node_of_bone[b])].local);
    const glm::vec3 t = to_skeleton_translation(b, local.translation);
    const glm::quat q = to_skeleton_rotation(b, local.rotation);
    rest_differs[b] = {t, q};
    const glm::quat r = bind.rotations[b];
    differs[b] = glm::length(t - bind.translations[b]) > 1e-6f * model_size ||
                 std::min(glm::length(q - r), glm::length(q + r)) > 1e-6f;
  }

  std::vector<std::string> clip_names;
  for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
    const aiAnimation& source = *scene->mAnimations[a];
    Animation clip;
    clip.name = source.mName.C_Str();
    if (clip.name.empty() || std::find(clip_names.begin(), clip_names.end(), clip.name) != clip_names.end())
      clip.name = "clip" + std::to_string(a);
    clip_names.push_back(clip.name);
    const std::string element = "clip '" + clip.name + "'";
    double ticks = source.mTicksPerSecond;
    if (!(ticks > 0.0) || !std::isfinite(ticks)) {
      ticks = options.default_ticks_per_second;
      warnings.push_back(element + ": no time base in the file, " + std::to_string(ticks) +
                         " ticks per second assumed");
    }
    clip.duration = static_cast<float>(source.mDuration / ticks);
    if (!std::isfinite(clip.duration) || clip.duration < 0.0f)
      throw Error::in_file(path, element, "duration is not finite");
    clip.loop = options.loop_clips;
    std::vector<bool> has_channel(bones.size(), false);
    std::size_t dropped = 0, scaled_bones = 0;
    for (unsigned c = 0; c < source.mNumChannels; ++c) {
      const aiNodeAnim& channel = *source.mChannels[c];
      const auto found = node_by_name.find(channel.mNodeName.C_Str());
      if (found == node_by_name.end()) continue;
      const std::int32_t bone = bone_of_node[static_cast<std::size_t>(found->second)];
      if (bone < 0 || has_channel[static_cast<std::size_t>(bone)]) continue;  // not in the skeleton, or repeated
      const auto b = static_cast<std::size_t>(bone);
      has_channel[b] = true;
      const std::string channel_element = element + ": bone '" + bones[b].name + "'";
      Channel out;
      out.bone = bone;
      out.translation = convert_track<glm::vec3>(
          channel.mPositionKeys, channel.mNumPositionKeys, ticks,
          [&](const aiVector3D& v) { return to_skeleton_translation(b, to_glm(v)); }, dropped, path, channel_element);
      out.rotation = convert_track<glm::quat>(
          channel.mRotationKeys, channel.mNumRotationKeys, ticks,
          [&](const aiQuaternion& q) { return to_skeleton_rotation(b, to_glm(q)); }, dropped, path, channel_element);
      const glm::vec3 rest_scale = split(nodes[static_cast<std::size_t>(found->second)].local).axis_scale;
      out.scale = convert_track<glm::vec3>(
          channel.mScalingKeys, channel.mNumScalingKeys, ticks,
          [&](const aiVector3D& v) { return to_glm(v) / rest_scale; }, dropped, path, channel_element);
      if (std::any_of(out.scale.values.begin(), out.scale.values.end(),
                      [](glm::vec3 s) { return glm::length(s - glm::vec3(1.0f)) > 1e-3f; }))
        ++scaled_bones;
      if (out.translation.empty()) out.translation = {Interpolation::linear, {0.0f}, {rest_differs[b].first}, {}, {}};
      if (out.rotation.empty()) out.rotation = {Interpolation::linear, {0.0f}, {rest_differs[b].second}, {}, {}};
      clip.channels.push_back(std::move(out));
    }
    for (std::size_t b = 0; b < bones.size(); ++b) {
      if (has_channel[b] || !differs[b]) continue;
      Channel hold;
      hold.bone = static_cast<std::int32_t>(b);
      hold.translation = {Interpolation::linear, {0.0f}, {rest_differs[b].first}, {}, {}};
      hold.rotation = {Interpolation::linear, {0.0f}, {rest_differs[b].second}, {}, {}};
      clip.channels.push_back(std::move(hold));
    }
    if (dropped > 0)
      warnings.push_back(element + ": " + std::to_string(dropped) +
                         " keys at or before their predecessor's time dropped");
    if (scaled_bones > 0)
      warnings.push_back(element + ": " + std::to_string(scaled_bones) +
                         " bones animate scale, which a Pose cannot hold (ignored)");
    clip.require_valid(bones.size(), path);
    result.clips.push_back(std::move(clip));
  }
  return result;
}
}  // namespace

}  // namespace deform
