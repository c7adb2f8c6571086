#pragma once
// Model: a rigged mesh — the mesh, its skeleton and per-point skin weights — as one value.
// What the OBJ + .sk + .skw triple, the built-in character and the importer all produce.
#include <string>

#include "deform/mesh.hpp"
#include "deform/skeleton.hpp"

namespace deform {

struct Model {
  std::string name;      // for messages and output names ("builtin", a file stem)
  Mesh mesh;
  Skeleton skeleton;
  SkinWeights weights;   // one entry per mesh point (mesh.point_count())
};

// Loads OBJ + .sk + .skw and checks they belong together (weights per OBJ `v`, bone ids in the skeleton).
// Throws deform::Error naming the offending file.
DEFORM_API Model load_model(const std::string& obj_path, const std::string& sk_path, const std::string& skw_path,
                            Warnings* warnings = nullptr);

}  // namespace deform
