#pragma once
// Model: a rigged mesh — the mesh, its skeleton and per-point skin weights — as one value.
// What the OBJ + .sk + .skw triple, the built-in character and the importer all produce.
#include <string>
#include <vector>
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/morph.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

struct Model {
  std::string name;  // for messages and output names ("builtin", a file stem)
  Mesh mesh;
  Skeleton skeleton;
  SkinWeights weights;  // one entry per mesh point (mesh.point_count())
  // Morph targets over the mesh's points, applied before skinning (MorphJob); an Animation's morph channels name
  // them by index. Empty for models without blend shapes.
  std::vector<MorphTarget> morph_targets;
};
}  // namespace deform
