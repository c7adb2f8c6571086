// Native export of a Model (import.hpp): OBJ + MTL + .sk + .skw, textures copied beside them.
#include <cctype>
#include <filesystem>
#include <map>

#include "deform/io/atomic_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/import/import.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/sk.hpp"
namespace deform {

ExportedFiles export_native(const Model& model, const std::string& folder) {
  namespace fs = std::filesystem;
  std::string stem = model.name.empty() ? std::string("model") : model.name;
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '_';
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw Error::in_file(folder, "", "cannot create the folder: " + error.message());
  const fs::path base(folder);
  ExportedFiles files;
  files.obj = (base / (stem + ".obj")).string();
  files.mtl = (base / (stem + ".mtl")).string();
  files.sk = (base / (stem + ".sk")).string();
  files.skw = (base / (stem + ".skw")).string();

  // Textures: one copy per distinct source; a name already taken by another source gets an index prefix.
  std::vector<Material> materials = model.mesh.materials;
  std::map<std::string, std::string> copy_of;  // source -> file name in `folder`
  for (Material& material : materials) {
    if (material.diffuse_map.empty()) continue;
    auto found = copy_of.find(material.diffuse_map);
    if (found == copy_of.end()) {
      if (!fs::is_regular_file(material.diffuse_map, error)) {
        files.warnings.push_back("material '" + material.name + "': texture '" + material.diffuse_map +
                                 "' not found, map_Kd left out");
        material.diffuse_map.clear();
        continue;
      }
      std::string name = fs::path(material.diffuse_map).filename().string();
      for (const auto& [source, taken] : copy_of)
        if (taken == name) name = std::to_string(copy_of.size()) + "_" + name;
      const std::string target = (base / name).string();
      write_file_atomic(target, read_file_bytes(material.diffuse_map));
      files.textures.push_back(target);
      found = copy_of.emplace(material.diffuse_map, name).first;
    }
    material.diffuse_map = found->second;
  }

  write_file_atomic(files.mtl, format_mtl(materials));
  write_skw(files.skw, model.weights);
  write_sk(files.sk, model.skeleton);
  ObjWriteOptions options;
  options.mtllib = stem + ".mtl";
  Mesh mesh_with_copies = model.mesh;
  mesh_with_copies.materials = std::move(materials);
  write_obj(files.obj, mesh_with_copies, model.mesh.positions, {}, options);
  return files;
}

}  // namespace deform
