// Wavefront MTL reader: the statements a rasteriser of OBJ models uses (colours, opacity, shininess, diffuse map).
#include <array>
#include <filesystem>

#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/offline/topology.hpp"
#include "obj_text.hpp"
#include "utf8_path.hpp"

namespace deform {

std::string obj_text::resolve_path(const std::string& folder, std::string_view name) {
  const std::filesystem::path file = utf8_path::from_utf8(name);
  if (file.is_absolute()) return utf8_path::generic_utf8(file.lexically_normal());
  return utf8_path::generic_utf8((utf8_path::from_utf8(folder) / file).lexically_normal());
}

namespace {

using obj_text::Place;
using obj_text::Tokens;

// MTL statements this reader knows but does not use (PBR extensions, other maps, refraction): skipped silently.
constexpr std::array<std::string_view, 28> ignored_statements = {
    "Ke",   "Ni",       "Tf",     "sharpness", "map_Ka", "map_Ks", "map_Ns", "map_d",  "map_Tr", "map_bump",
    "bump", "map_Bump", "disp",   "decal",     "refl",   "norm",   "Pr",     "Pm",     "Ps",     "Pc",
    "Pcr",  "aniso",    "anisor", "map_Pr",    "map_Pm", "map_Ps", "map_Ke", "map_RMA"};

// `Ka`/`Kd`/`Ks`: one grey value or r g b.
glm::vec3 parse_colour(Tokens& tokens, const Place& place, std::string_view element) {
  float rgb[3] = {};
  const int count = obj_text::parse_floats(tokens, rgb, 1, 3, place, element);
  if (count == 2) place.fail(element, "expected 1 or 3 numbers, found 2");
  return count == 1 ? glm::vec3(rgb[0]) : glm::vec3(rgb[0], rgb[1], rgb[2]);
}

// Number of arguments of a texture map option, or -1 for "one to three numbers" (-o, -s, -t), 0 if unknown.
int option_arguments(std::string_view option) {
  if (option == "-o" || option == "-s" || option == "-t") return -1;
  if (option == "-mm") return 2;
  if (option == "-blendu" || option == "-blendv" || option == "-cc" || option == "-clamp" || option == "-bm" ||
      option == "-boost" || option == "-texres" || option == "-imfchan" || option == "-type")
    return 1;
  return 0;
}

// `map_Kd [options] file`: the options are checked and skipped (libdeform draws the texture as is); the file name
// is the rest of the line and may contain blanks.
std::string_view parse_map_file(Tokens& tokens, const Place& place, std::string_view element) {
  for (;;) {
    Tokens look_ahead = tokens;
    std::string_view token;
    if (!look_ahead.next(token)) place.fail(element, "missing texture file name");
    if (token.size() < 2 || token.front() != '-') return tokens.rest();
    const int arguments = option_arguments(token);
    if (arguments == 0) place.fail(element, "unknown texture option " + obj_text::quoted(token));
    tokens = look_ahead;
    if (arguments > 0) {
      for (int i = 0; i < arguments; ++i)
        if (!tokens.next(token)) place.fail(element, "texture option is missing its argument");
      continue;
    }
    for (int i = 0; i < 3; ++i) {  // -o/-s/-t u [v [w]]: numbers until the first token that is not one
      look_ahead = tokens;
      if (!look_ahead.next(token)) break;
      float unused = 0.0f;
      const auto [stop, error] = detail::read_decimal(token.data(), token.data() + token.size(), unused);
      if (error != std::errc() || stop != token.data() + token.size()) {
        if (i == 0) place.fail(element, "texture option is missing its numbers");
        break;
      }
      tokens = look_ahead;
    }
  }
}

}  // namespace

std::vector<Material> parse_mtl(std::string_view text, const std::string& name, const std::string& base_folder,
                                Warnings* warnings, const ReferencePolicy& policy) {
  return obj_text::parse_mtl_confined(text, name, base_folder, base_folder, warnings, policy);
}

std::vector<Material> obj_text::parse_mtl_confined(std::string_view text, const std::string& name,
                                                   const std::string& base_folder, const std::string& root,
                                                   Warnings* warnings, const ReferencePolicy& policy) {
  std::vector<Material> materials;
  obj_text::LineReader lines(text);
  obj_text::SkippedStatements skipped;
  std::string_view statement;
  while (lines.next(statement)) {
    Tokens tokens(statement);
    std::string_view keyword;
    if (!tokens.next(keyword)) continue;
    const Place place{name, lines.line()};

    if (keyword == "newmtl") {
      const std::string_view material_name = tokens.rest();
      if (material_name.empty()) place.fail(keyword, "missing material name");
      materials.emplace_back().name = std::string(material_name);
      continue;
    }
    const bool used = keyword == "Ka" || keyword == "Kd" || keyword == "Ks" || keyword == "d" || keyword == "Tr" ||
                      keyword == "Ns" || keyword == "illum" || keyword == "map_Kd";
    if (!used) {
      bool ignored = false;
      for (const auto known : ignored_statements) ignored = ignored || keyword == known;
      if (!ignored) skipped.add(keyword, place.line);
      continue;
    }
    if (materials.empty()) place.fail(keyword, "statement before the first newmtl");
    Material& material = materials.back();
    float value = 0.0f;
    if (keyword == "Ka") {
      material.ambient = parse_colour(tokens, place, keyword);
    } else if (keyword == "Kd") {
      material.diffuse = parse_colour(tokens, place, keyword);
    } else if (keyword == "Ks") {
      material.specular = parse_colour(tokens, place, keyword);
    } else if (keyword == "d") {
      std::string_view option;
      if (Tokens look_ahead = tokens; look_ahead.next(option) && option == "-halo") tokens = look_ahead;
      obj_text::parse_floats(tokens, &value, 1, 1, place, keyword);
      material.opacity = value;
    } else if (keyword == "Tr") {
      obj_text::parse_floats(tokens, &value, 1, 1, place, keyword);
      material.opacity = 1.0f - value;
    } else if (keyword == "Ns") {
      obj_text::parse_floats(tokens, &value, 1, 1, place, keyword);
      material.shininess = value;
    } else if (keyword == "illum") {
      std::string_view token;
      if (!tokens.next(token)) place.fail(keyword, "missing illumination model");
      const std::int64_t model = obj_text::parse_integer(token, place, keyword);
      if (model < 0 || model > 10)
        place.fail(keyword, "illumination model " + std::to_string(model) + " is not 0 to 10");
      if (tokens.next(token)) place.fail(keyword, "unexpected " + obj_text::quoted(token));
      material.illum = static_cast<int>(model);
    } else {  // map_Kd
      const std::string_view file = parse_map_file(tokens, place, keyword);
      try {
        material.diffuse_map = obj_text::resolve_path(base_folder, file);
      } catch (const Error&) {  // only on Windows, where a path is the wide name its UTF-8 spells
        place.fail(keyword, "the file name is not UTF-8");
      }
      // Confined to the model's folder (a texture is read later, by a copy or a renderer): refused here, at once.
      // (An MTL file in a subfolder of the model's: its names are made absolute, relative to the MTL's folder.)
      const std::string named =
          base_folder == root
              ? std::string(file)
              : utf8_path::to_utf8(std::filesystem::absolute(utf8_path::from_utf8(material.diffuse_map)));
      const std::string real =
          resolve_referenced_file_in(root, name, named, "map_Kd", policy, ReferenceSyntax::path, place.line);
      std::error_code error;
      if (!std::filesystem::is_regular_file(utf8_path::from_utf8(real), error))
        obj_text::warn(warnings, name, place.line,
                       "texture " + obj_text::quoted(file) + " not found (looked for '" + material.diffuse_map + "')");
    }
  }
  skipped.report(warnings, name);
  return materials;
}

}  // namespace deform
