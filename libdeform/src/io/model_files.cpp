// deform::load_model: the native OBJ + .sk + .skw triple as one Model.
#include "deform/io/model_files.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/model_files.hpp"
#include <filesystem>

#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"
namespace deform {

Model load_model(const std::string& obj_path, const std::string& sk_path, const std::string& skw_path,
                 Warnings* warnings, int influences, const ReferencePolicy& policy, ObjNames* names) {
  Model model;
  model.name = utf8_path::to_utf8(utf8_path::from_utf8(obj_path).stem());
  model.mesh = read_obj(obj_path, warnings, policy, names);
  model.skeleton = read_sk(sk_path);
  // read_skw rejects a vertex count other than the mesh's and bone ids outside the skeleton, naming the line; the
  // checks below hold the Model invariant whatever the reader does.
  model.weights = read_skw(skw_path, model.mesh.point_count(), model.skeleton.bone_count(), influences);
  if (model.weights.size() != model.mesh.point_count() || model.weights.weights.size() != model.weights.size())
    throw Error::in_file(skw_path, "",
                         "has " + std::to_string(model.weights.size()) + " vertices, " + obj_path + " has " +
                             std::to_string(model.mesh.point_count()));
  for (std::size_t v = 0; v < model.weights.size(); ++v)
    for (int k = 0; k < max_influences; ++k)
      if (model.weights.bones[v][k] >= model.skeleton.bone_count())
        throw Error::in_file(skw_path, "vertex " + std::to_string(v),
                             "bone " + std::to_string(model.weights.bones[v][k]) + " is not in " + sk_path);
  return model;
}

}  // namespace deform
