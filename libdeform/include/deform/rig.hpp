#pragma once
// Rig files: the deformer set-up of a character — its lattices, their bones, degree, vertex selection, elastic
// parameters and hierarchy, and the default reach chain — saved to and loaded from JSON (the thesis' RV04F03).
// The format is in docs/formats.md ("Rig files").
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "deform/export.hpp"
#include "deform/hierarchy.hpp"
#include "deform/model.hpp"

namespace deform {

// The model a rig was made for (the file's optional "model" key): the built-in character, or the OBJ, .sk and .skw
// paths as the file writes them (relative paths are relative to the rig file's folder). All empty: not named.
struct RigModel {
  bool builtin = false;
  std::string obj;
  std::string skeleton;
  std::string weights;
  bool operator==(const RigModel&) const = default;
};

struct Rig {
  RigModel model;
  std::vector<LatticeSpec> lattices;
  // The chain reach() uses by default: effector bone and chain root (-1: none / chosen from the lattices).
  std::int32_t reach_effector = -1;
  std::int32_t reach_root = -1;
  // Largest stretch reach() asks of a lattice, as a multiple of its length (>= 0).
  float max_stretch = 3.0f;
  bool operator==(const Rig&) const = default;
};

// The rig of the built-in character (builtin_character(); model.builtin set): three lattices on the left arm — upper
// arm, forearm, hand — with under-damped springs, reach chain clavicle_l → hand_l. Throws deform::Error when `model`
// lacks those bones.
DEFORM_API Rig builtin_rig(const Model& model);

// A rig for any rigged model, so an imported character stretches too: up to three lattices on the limb that ends at
// `effector` (the effector's bone and its two nearest ancestors that carry skin weight: hand, forearm, upper arm on a
// humanoid), springs as in builtin_rig(), reach chain from the bone above them. With `effector` = -1 it is chosen:
// the first bone whose name contains "hand" (a left one first), else "wrist", else the deepest bone with skin weight.
// For the built-in character it is builtin_rig(). Throws deform::Error when no bone carries skin weight.
DEFORM_API Rig default_rig(const Model& model, std::int32_t effector = -1);

// Reads only the "model" key of a rig file, so the caller can load the model the rest of the file refers to.
// Throws deform::Error (naming `name` and the key) for malformed JSON or a malformed "model".
DEFORM_API RigModel parse_rig_model(std::string_view json, const std::string& name = "<memory>");

// Parses a rig for `skeleton` (bones are named as Skeleton::key names them) and a mesh of `point_count` points.
// Throws deform::Error naming `name`, the JSON key (e.g. "key 'lattices[1].elastic.stiffness'") and what is wrong:
// malformed JSON, a missing, unknown or mistyped key, an unknown bone, a non-finite number, a value out of range, a
// vertex out of range or repeated, a repeated lattice name, or a "parent" that is not the lattice the bones imply.
DEFORM_API Rig parse_rig_json(std::string_view json, const Skeleton& skeleton, std::size_t point_count,
                              const std::string& name = "<memory>");
DEFORM_API Rig read_rig_json(const std::string& path, const Skeleton& skeleton, std::size_t point_count);
// The rig as JSON text (every field written, floats shortest-exact): parse_rig_json(format_rig_json(r)) == r.
DEFORM_API std::string format_rig_json(const Rig& rig, const Skeleton& skeleton);
DEFORM_API void write_rig_json(const std::string& path, const Rig& rig, const Skeleton& skeleton);  // atomic

}  // namespace deform
