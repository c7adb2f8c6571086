// Native export of a Model (import.hpp): OBJ + MTL + .sk + .skw, textures copied beside them, landing as a set.
#include <cstdio>
#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <map>
#include <random>
#include <string_view>
#include <system_error>

#include "deform/import/import.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/io/sk.hpp"
#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"

namespace deform {
namespace {

namespace fs = std::filesystem;
using utf8_path::from_utf8;
using utf8_path::to_utf8;

// The UTF-8 path of `name` (UTF-8) in `folder`.
std::string path_in(const fs::path& folder, const std::string& name) { return to_utf8(folder / from_utf8(name)); }

// Where a texture may be copied from: inside `root` or a folder `policy` allows once links are resolved
// (lies_inside, the rule every reader applies), and an image by its first bytes alone (image_format: a 100 MB file
// that is not one is never read). Empty = allowed. `real` receives the canonical path to copy.
std::string refusal(const std::string& texture, const std::string& root, const ReferencePolicy& policy,
                    std::string& real) {
  std::error_code error;
  if (root.empty()) return "no texture folder was given";
  fs::path named;
  try {
    named = from_utf8(texture);
  } catch (const Error&) {  // only on Windows, where a path is the wide name its UTF-8 spells
    return "its name is not UTF-8";
  }
  const fs::path canonical = fs::canonical(named, error);
  if (error || !fs::is_regular_file(canonical, error)) return "not found";
  if (!fs::is_directory(from_utf8(root), error)) return "the texture folder '" + root + "' does not exist";
  const std::string canonical_utf8 = to_utf8(canonical);
  bool allowed = lies_inside(canonical_utf8, root);
  for (const std::string& other : policy.allow_outside) allowed = allowed || lies_inside(canonical_utf8, other);
  if (!allowed) return "it lies outside the model's folder '" + root + "'";
  if (image_format(canonical_utf8).empty()) return "it is not an image file";
  real = canonical_utf8;
  return {};
}

// Removes the staging folder on every path out, unless it was moved into place.
struct Staging {
  fs::path path;
  ~Staging() {
    std::error_code ignored;
    if (!path.empty()) fs::remove_all(path, ignored);
  }
};

}  // namespace

ExportedFiles export_native(const Model& model, const std::string& folder, const ExportOptions& options) {
  if (!options.submesh_names.empty() && options.submesh_names.size() != model.mesh.submeshes.size())
    throw Error::invalid_argument("submesh_names", std::to_string(options.submesh_names.size()) + " names for " +
                                                       std::to_string(model.mesh.submeshes.size()) + " submeshes");
  std::string stem = model.name.empty() ? std::string("model") : model.name;
  for (char& c : stem)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '_';
  std::error_code error;
  const fs::path base = from_utf8(folder).lexically_normal();
  const fs::path target = base.filename().empty() ? base.parent_path() : base;  // without a trailing separator
  const std::string leaf = to_utf8(target.filename());
  const fs::path parent = target.parent_path();
  Staging staging;
  std::random_device entropy;
  for (int attempt = 0; attempt < 16 && staging.path.empty(); ++attempt) {
    const fs::path candidate =
        (parent.empty() ? fs::path(".") : parent) / from_utf8("." + leaf + ".deform-tmp-" + std::to_string(entropy()));
    if (fs::create_directories(candidate, error)) staging.path = candidate;
  }
  if (staging.path.empty()) {  // a missing parent folder is the user's; permissions or a full disk the system's
    const std::string why = "cannot create a folder beside it: " + error.message();
    if (error == std::errc::no_such_file_or_directory || error == std::errc::not_a_directory)
      throw Error::in_file(folder, "", why);
    throw Error::environment(folder, why);
  }

  ExportedFiles files;
  std::vector<std::string> names = {stem + ".obj", stem + ".mtl", stem + ".sk", stem + ".skw"};

  // Textures: one copy per distinct source; a name already taken by another source gets an index prefix.
  std::vector<Material> materials = model.mesh.materials;
  std::map<std::string, std::string> copy_of;                             // source -> file name in `folder`
  std::map<const std::vector<std::uint8_t>*, std::string> file_of_image;  // embedded image -> file name in `folder`
  std::map<std::string, std::string> checked;  // source -> why refused ("" if not): each is checked once per export
  for (Material& material : materials) {
    if (material.diffuse_image) {  // an embedded image becomes a file of its own, named after its first material
      const std::vector<std::uint8_t>& bytes = *material.diffuse_image;
      auto found = file_of_image.find(&bytes);
      if (found == file_of_image.end()) {
        std::string name = stem + "_" + material.name;
        for (char& c : name)
          if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) c = '_';
        name += bytes.size() >= 2 && bytes[0] == 0xFF && bytes[1] == 0xD8 ? ".jpg" : ".png";
        while (std::find(names.begin(), names.end(), name) != names.end())
          name = std::to_string(file_of_image.size()) + "_" + name;
        write_file_atomic(path_in(staging.path, name), bytes);
        names.push_back(name);
        found = file_of_image.emplace(&bytes, name).first;
      }
      material.diffuse_map = found->second;
      material.diffuse_image.reset();
      continue;
    }
    if (material.diffuse_map.empty()) continue;
    auto found = copy_of.find(material.diffuse_map);
    if (found == copy_of.end()) {
      auto known = checked.find(material.diffuse_map);
      std::string real;
      if (known == checked.end())
        known = checked
                    .emplace(material.diffuse_map,
                             refusal(material.diffuse_map, options.texture_root, options.references, real))
                    .first;
      if (!known->second.empty()) {
        files.warnings.push_back(escape_control_characters("material '" + material.name + "': texture '" +
                                                           material.diffuse_map + "' not copied (" + known->second +
                                                           "), map_Kd left out"));
        material.diffuse_map.clear();
        continue;
      }
      const std::vector<std::uint8_t> bytes = read_file_bytes(real);
      std::string name = to_utf8(from_utf8(material.diffuse_map).filename());
      while (std::find(names.begin(), names.end(), name) != names.end())
        name = std::to_string(copy_of.size()) + "_" + name;
      write_file_atomic(path_in(staging.path, name), bytes);
      names.push_back(name);
      found = copy_of.emplace(material.diffuse_map, name).first;
    }
    material.diffuse_map = found->second;
  }

  write_file_atomic(path_in(staging.path, names[1]), format_mtl(materials));
  SkinWeights folded;  // .skw readers keep four influences by default: the file holds what reloads
  if (model.weights.has_extra()) {
    folded = model.weights;
    float largest = 0.0f;
    const std::size_t points = drop_extra_influences(folded, &largest);
    char dropped[32];
    std::snprintf(dropped, sizeof dropped, "%.4g", double(largest));
    files.warnings.push_back(
        names[3] + ": " + std::to_string(points) +
        " vertices have more than 4 influences, more than .skw readers keep by default: the strongest 4 "
        "written, renormalised (largest weight dropped: " +
        std::string(dropped) + " of the vertex's total); the model skins differently from the import there");
  }
  if (!model.morph_targets.empty())
    files.warnings.push_back(names[0] + ": " + std::to_string(model.morph_targets.size()) +
                             " morph targets are not written (OBJ, .sk and .skw have no blend shapes); the mesh is "
                             "the base shape");
  write_skw(path_in(staging.path, names[3]), model.weights.has_extra() ? folded : model.weights);
  write_sk(path_in(staging.path, names[2]), model.skeleton);
  ObjWriteOptions obj_options;
  obj_options.mtllib = names[1];
  obj_options.submesh_names = options.submesh_names;
  Mesh mesh_with_copies = model.mesh;
  mesh_with_copies.materials = std::move(materials);
  write_obj(path_in(staging.path, names[0]), mesh_with_copies, model.mesh.positions, {}, obj_options);

  // Every file is written: move the set into place, a new folder in one rename, else as one FileTransaction (every
  // previous file of the set kept until all the new ones are in, and put back if any step fails).
  if (!fs::exists(target, error)) {
    fs::rename(staging.path, target, error);
    if (error) throw Error::environment(folder, "cannot move the exported files into place: " + error.message());
    staging.path.clear();
  } else {
    if (!fs::is_directory(target, error)) throw Error::in_file(folder, "", "exists and is not a folder");
    FileTransaction landing;
    for (std::size_t i = names.size(); i-- > 0;)  // textures, .skw, .sk, .mtl, then the OBJ
      landing.stage_written(path_in(base, names[i]), path_in(staging.path, names[i]));
    landing.commit();
  }
  files.obj = path_in(base, names[0]);
  files.mtl = path_in(base, names[1]);
  files.sk = path_in(base, names[2]);
  files.skw = path_in(base, names[3]);
  for (std::size_t i = 4; i < names.size(); ++i) files.textures.push_back(path_in(base, names[i]));
  return files;
}

}  // namespace deform
