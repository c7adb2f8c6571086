#pragma once
// How libdeform's programs (the `deform` CLI and deform_viewer) turn the model a user names into a
// deform::Model, and which rig such a model starts with: the built-in character, the native OBJ + .sk + .skw, or any
// rigged file Assimp reads (when built with deform::import).
//
// This is front-end policy, not SDK: an engine loads its own assets and links only the layers it needs, so nothing
// here is installed. It is one small static library (deform_model_loading) that both front ends link, rather than a
// function in deform::import, because it must work in a build without Assimp (built-in character, native files) and
// it chooses the built-in character's rig (deform::extras), which the importer layer has no business knowing about.
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "deform/io/obj.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"

namespace model_loading {

// The model to load. The caller turns its own flags into this and reports their misuse in its own words.
struct ModelRequest {
  std::string path;      // the model file; empty: the built-in character
  std::string skeleton;  // with an OBJ `path`: its .sk (giving it, or `weights`, means "native files")
  std::string weights;   // with an OBJ `path`: its .skw; empty: see automatic_weights
  int influences = deform::max_influences;  // kept per point from the .skw (deform::read_skw)
  // An OBJ with a skeleton but no weights gets compute_heat_weights() (default options, docs/weights.md; about a
  // second for 40k points), its warnings added to the loaded model's; false: such a request is an error.
  bool automatic_weights = false;
  // Folders besides the model's own whose files it may name (MTL, textures, buffers): resolve_referenced_file.
  deform::ReferencePolicy references;
};

struct LoadedModel {
  deform::Model model;
  std::string source;                    // "builtin" or the path, for messages
  bool builtin = false;                  // the built-in character (builtin_character())
  bool imported = false;                 // read through deform::import: `clips` and `up` come from the file
  bool rigged = true;                    // false for a static import (one bone "root", every point weighted to it)
  std::vector<deform::Animation> clips;  // an import's animation clips; empty otherwise
  glm::vec3 up{0.0f, 1.0f, 0.0f};        // the up axis an imported file declares; +Y otherwise
  std::vector<std::string> warnings;     // non-fatal findings, one line each, naming their file
  // What an OBJ written of this model names, as its source had it: an OBJ's `o`/`g` names and MTL files, an
  // import's node and mesh names (ImportedModel::submesh_names), the built-in character's object "builtin" and
  // body parts (builtin_part_names).
  deform::ObjNames names;
};

// Whether `path` would be imported (this build has deform::import, Assimp reads the extension, and it is not an
// OBJ, which is read natively). No file access.
bool importable(const std::string& path);

// Loads what `request` names: the built-in character when `path` is empty; the native files when `skeleton` or
// `weights` is given; an import when importable(path). Throws deform::Error naming the file when a file cannot be
// read or the files do not belong together, and deform::Error (kind argument, element the path) when the request
// names nothing loadable: a mesh without a skeleton, weights without a skeleton, a format this build cannot import.
LoadedModel load_model(const ModelRequest& request);

// The rig a model starts with when the user gives none: builtin_rig() for the built-in character, default_rig()
// (the heuristic arm rig) for any other. Throws deform::Error as those do.
deform::Rig starting_rig(const LoadedModel& loaded);

// The lowest height along `up` (a unit vector) that the model's skinned points reach over `samples` (at least 2)
// evenly spaced times of `clip`, both ends included: LBS of the mesh with the clip sampled over the bind pose. A floor
// at that height carries the character through the whole clip without a foot sinking into it, where a floor under
// the bind pose would not (a clip that crouches, or a file whose bind pose is not its animated stance). Allocates;
// for load time. Throws what the jobs report for a clip that does not fit the model (validated clips always do).
float lowest_height(const deform::Model& model, const deform::Animation& clip, glm::vec3 up, int samples = 48);

// The box around the model's skinned points over the same samples of `clip` as lowest_height, each point turned by
// `frame` first (a viewer's upright turn, after which +Y is up): what a camera must see to keep the character in frame
// through the whole clip. An empty mesh gives a zero box at the origin. Allocates; for load time; throws as
// lowest_height does.
deform::Bounds posed_bounds(const deform::Model& model, const deform::Animation& clip, glm::quat frame,
                            int samples = 48);

}  // namespace model_loading
