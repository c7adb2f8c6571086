#pragma once
// Rig files: the deformer set-up of a character — its lattices, their bones, degree, vertex selection, elastic
// parameters and hierarchy, and the default reach chain — saved to and loaded from JSON (the thesis' RV04F03).
// The format is in docs/formats.md ("Rig files").
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/spring_chain.hpp"

namespace deform {

// The model a rig was made for (the file's optional "model" key): the built-in character, the OBJ, .sk and .skw
// paths, or one file an importer reads (glTF, FBX, ...), as the file writes them (relative paths are relative to the
// rig file's folder). All empty: not named. At most one of builtin, obj (with skeleton and weights) and file is set.
struct RigModel {
  bool builtin = false;
  std::string obj;
  std::string skeleton;
  std::string weights;
  std::string file;  // an imported model (deform::import), e.g. "CesiumMan.glb"
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
  // Spring chains (tails, hair, ears: runtime/spring_chain.hpp), the colliders they share, and their sub-step.
  std::vector<SpringChainSpec> spring_chains;
  std::vector<SpringCollider> colliders;
  float spring_substep = SpringChains::default_substep;
  bool operator==(const Rig&) const = default;
};
// A rig for any rigged model, so an imported character stretches too: up to three lattices on the limb that ends at
// `effector` (the effector's bone and its two nearest ancestors that carry skin weight: hand, forearm, upper arm on a
// humanoid), springs as in builtin_rig(), reach chain from the bone above them. With `effector` = -1 it is chosen:
// the first bone whose name contains "hand" (a left one first), else "wrist", else the deepest bone with skin weight.
// (The built-in character has a rig of its own: builtin_rig() in extras.) Throws deform::Error when no bone carries skin weight.
DEFORM_OFFLINE_API Rig default_rig(const Model& model, std::int32_t effector = -1);
}  // namespace deform
