#pragma once
// Importer (optional component deform::import, link deform::import): rigged characters from glTF 2.0 (.gltf, .glb:
// a reader of our own on tinygltf, skins bound by node index, samplers kept), from Inter-Quake Models (.iqm: a reader
// of our own, as Assimp 5.2 drops their joints and clips) and from any other format Assimp reads (FBX, Collada,
// DirectX .x, B3D, SMD, MD5, ...) as a Model plus animation clips. docs/import.md explains every conversion (glTF's
// and IQM's differences in their own sections); in short:
//  - all meshes merge into one Mesh in the scene's world space (node transforms applied), one submesh per mesh
//    instance, with its materials; texture paths are resolved relative to the model's folder, and every file the
//    model names (glTF buffers and images, textures) must lie inside that folder or one options.references allows.
//  - a *point* (Mesh::positions, .skw line, OBJ `v`) is a unique (exact bind position, skin influences) pair: Assimp
//    vertices that differ only by normal or UV share one point; each Assimp vertex is one render vertex.
//  - bones are the nodes skinning needs (those named by the meshes' bones, the nodes of meshes with unweighted
//    vertices) and every node on the paths between them, rooted at their lowest common ancestor (raised to the
//    topmost animated ancestor). A bone's bind world transform is F · offset⁻¹ (the file's inverse bind matrix), F
//    the frame the mesh is bound in: where its bones agree on G_bone · offset with the node tree at rest (where
//    Assimp draws it), else the mesh node's world transform; the mesh is stored as F · v, so the rest pose
//    reproduces the file's rest mesh exactly. A node without an offset binds at its node-tree world transform.
//    Clips hold every bone whose node-tree rest differs from its bind at the node-tree value.
//  - a Skeleton has no scale: uniform scale is folded into child translations (exact for skinning while the scale
//    is not animated); non-uniform or animated scale is approximated and reported in `warnings`.
//  - weights: the strongest 4 per vertex, renormalised; a vertex with no weight is bound rigidly to its mesh's node.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "deform/import/export.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/model.hpp"
namespace deform {

struct ImportOptions {
  // Clip time base when the file gives none (Assimp reports 0 ticks per second).
  double default_ticks_per_second = 25.0;
  // Whether imported clips loop (the formats do not say).
  bool loop_clips = true;
  // Folders besides the model's own whose files it may name (buffers, images, textures): resolve_referenced_file.
  // A file named outside both is refused (deform::Error naming the model and the key, e.g. "buffers[0].uri") before
  // it is opened. Travels to the isolated worker.
  ReferencePolicy references;
};

// A skin of the file, for listings (`deform info`): the merged Model has one skeleton and one set of weights.
struct ImportedSkin {
  std::string name;                 // glTF: the skin's name (may be empty); other formats: empty
  std::size_t joints = 0;           // glTF: the skin's joint count; other formats: the distinct bones the meshes name
  std::vector<std::string> meshes;  // the names of the meshes it deforms, each once, in scene order (may be empty)
  bool operator==(const ImportedSkin&) const = default;
};

struct ImportedModel {
  // mesh in bind pose (world space), skeleton, weights (one per point). model.name is the file's stem.
  Model model;
  // The file's animations, in skeleton space (see Animation), validated against model.skeleton.
  std::vector<Animation> clips;
  // Non-fatal findings, one line each: unweighted vertices bound rigidly, influences dropped beyond 4, scale that a
  // Skeleton cannot hold, textures missing or embedded, bones with no node, names shortened to fit .sk.
  std::vector<std::string> warnings;
  // False for a static scene (no mesh has bones): the skeleton is then one bone "root" at the origin, every point
  // weighted 1 to it, and `clips` is empty.
  bool rigged = false;
  // Per bone, the file's bind world transform with its scale (mesh-node · offset⁻¹, or the node-tree world
  // transform for bones without an offset); the skeleton holds its rigid part. For callers that handle scale.
  std::vector<glm::mat4> file_bind_world;
  // The up direction the file declares (a unit axis): its FBX `UpAxis`/`UpAxisSign`, as Assimp reports them; +Y
  // for files that declare none (glTF is +Y by definition). The data is left as the file has it: a viewer turns its
  // scene so that `up` points up.
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  // The file's skins: glTF's every skin, used or not, in file order; for other formats one entry when rigged (their
  // meshes' bones taken as one skin), none when not.
  std::vector<ImportedSkin> skins;
  // Per submesh of model.mesh (same order), the names export_native writes as its `o` and `g`: the mesh instance's
  // node (glTF, Assimp) or mesh (IQM) as `object`, its mesh as `group`.
  std::vector<ObjSubmeshNames> submesh_names;
};

// Imports the model at `path` in this process. Throws deform::Error naming the file for a file Assimp cannot read
// (missing, truncated, malformed: Assimp's message is included), a scene with no triangles, non-finite data, more than
// 65535 bones or more than 2^32 - 1 vertices. Assimp's own validation runs first, but Assimp itself can crash, hang
// or exhaust memory on hostile files (docs/reliability.md): for files from elsewhere use import_model_isolated.
// Cost: Assimp's import plus O(vertices · influences + bones + keys).
DEFORM_IMPORT_API ImportedModel import_model(const std::string& path, const ImportOptions& options = {});

// Limits of an isolated import (import_model_isolated): what the importer process may use before it is stopped.
struct IsolationLimits {
  std::uint64_t max_memory_bytes = 4ull << 30;  // its address space (in a worker built with AddressSanitizer,
                                                // whose shadow needs more: ASan's limit on resident memory)
  std::uint64_t max_stack_bytes = 64ull << 20;  // deep node hierarchies recurse inside Assimp
  double max_seconds = 60.0;                    // wall-clock time, then it is killed
  std::uint64_t max_output_bytes = 4ull << 30;  // the model it sends back
  // The importer executable (deform-import-worker). Empty: $DEFORM_IMPORT_WORKER, then the one this build made, then
  // the installed one (LIBEXECDIR/deform-import-worker).
  std::string worker;
};

// import_model in a separate process with memory, stack and time limits: the default for files libdeform did not
// write. A file that makes Assimp crash (a stack overflow on a 20,000-deep node chain), hang or allocate without
// bound becomes a deform::Error naming the file and what happened ("the importer crashed (signal 11) reading it",
// "... took more than 60 s", "... needed more than 4294967296 bytes"); the parent never sees the bad memory.
// The result is the same as import_model's, checked again on arrival. Cost: import_model's plus a process start
// (about 10 ms) and one copy of the model. Throws deform::Error of kind argument when the worker is not found.
DEFORM_IMPORT_API ImportedModel import_model_isolated(const std::string& path, const ImportOptions& options = {},
                                                      const IsolationLimits& limits = {});

// The native files export_native wrote (full paths) and what it could not copy.
struct ExportedFiles {
  std::string obj, mtl, sk, skw;
  std::vector<std::string> textures;  // copies, one per distinct source texture
  std::vector<std::string> warnings;  // textures left out (missing, outside texture_root, not an image), one line each
};

struct ExportOptions {
  // The only folder textures are copied from: a material's texture is copied when, with every symbolic link
  // resolved, it lies inside this folder and is an image file (PNG, JPEG, BMP, GIF, TGA, DDS, KTX, WebP, TIFF, HDR
  // or PSD, by its first bytes; TGA by its extension). Anything else is left out with a warning naming it, so a
  // model that names /etc/passwd or ../../secret as its texture leaks nothing. Empty: no texture is copied.
  // Each distinct texture is checked once, from its first bytes, and read once when copied.
  std::string texture_root;
  // Folders besides texture_root textures may be copied from, on purpose (ImportOptions::references).
  ReferencePolicy references;
  // The OBJ's `o`/`g` names, one per submesh of the model's mesh (ImportedModel::submesh_names, ObjNames::submeshes
  // of a native model); empty: the OBJ has none. Throws deform::Error (kind argument) for another count.
  std::span<const ObjSubmeshNames> submesh_names;
};

// Writes `model` into `folder` as STEM.obj + STEM.mtl + STEM.sk + STEM.skw, STEM = model.name with anything outside
// [A-Za-z0-9._-] replaced by '_' ("model" if empty), and copies each material's diffuse texture beside them as
// `options` allows (map_Kd then names the copy). The OBJ holds the mesh in the bind pose the .sk describes, so
// load_model(obj, sk, skw) skins exactly as `model` does. The files land as a set: they are written into a fresh
// folder beside `folder` first (.NAME.deform-tmp-N), then moved into place, so a failure (a full disk) leaves
// `folder` as it was. Throws deform::Error when a file cannot be written or the skeleton does not fit .sk.
DEFORM_IMPORT_API ExportedFiles export_native(const Model& model, const std::string& folder,
                                              const ExportOptions& options = {});

// True when `path`'s extension is one Assimp can read (case-insensitive). Cheap: no file access.
DEFORM_IMPORT_API bool is_importable(const std::string& path);

}  // namespace deform
