#pragma once
// Wavefront OBJ and MTL: meshes read from and written to text, faithfully (vertex i in is vertex i out).
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "deform/io/export.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"

namespace deform {

// What an OBJ file holds besides geometry: the names of its submeshes (`o`, `g`) and the MTL files it names
// (`mtllib`). File bookkeeping, kept beside the Mesh rather than in it: read_obj fills it when asked and write_obj
// writes it when given, so that an OBJ read and written again keeps its names and opens with its materials.
struct ObjSubmeshNames {
  std::string object;  // last `o` name in effect ("" if none)
  std::string group;   // last `g` name in effect ("" if none)
  bool operator==(const ObjSubmeshNames&) const = default;
};
struct ObjNames {
  std::vector<ObjSubmeshNames> submeshes;  // one per Mesh::submeshes entry, in the same order
  // The MTL files the `mtllib` lines named and read_obj read, as it opened them (resolved against the OBJ's folder),
  // in file order. write_obj does not use them by itself: see material_libraries_for.
  std::vector<std::string> material_libraries;
};

// Reads an OBJ file and the MTL files it names. Supports `v` (extra w / colour components ignored), `vn`, `vt`,
// `f` in the forms v, v/vt, v//vn, v/vt/vn with negative (relative) indices, polygons (fan-triangulated), `o`, `g`,
// `s` (ignored), `mtllib`, `usemtl`, `\` line continuation; MTL `newmtl`, `Ka`, `Kd`, `Ks`, `d`, `Tr`, `Ns`, `illum`,
// `map_Kd`. Render vertices are the distinct (v, vt, vn) triples, numbered in order of first use.
// A malformed line or an out-of-range index throws deform::Error with the file and line; a missing MTL, an unknown
// material, a missing texture or an unsupported statement (`l`, `p`, curves...) is a warning. Normals missing from
// the file are computed as compute_vertex_normals does. Linear time and memory in the file size.
// The MTL files (`mtllib`) and textures (`map_Kd`) named must lie inside the OBJ's folder, or a folder `policy`
// allows (resolve_referenced_file): anything else throws deform::Error naming the file, line and key, before the
// named file is opened. Each MTL file is read once. `names`, when given, receives the file's names (ObjNames); a new
// submesh starts where the `o`, `g` or `usemtl` in effect changes, whether `names` is given or not.
DEFORM_IO_API Mesh read_obj(const std::string& path, Warnings* warnings = nullptr, const ReferencePolicy& policy = {},
                            ObjNames* names = nullptr);

// Parses OBJ text held in memory; `name` is used in messages, MTL files are resolved relative to `base_folder` and
// confined to it (and `policy`'s folders) as read_obj confines them to the OBJ's folder.
DEFORM_IO_API Mesh parse_obj(std::string_view text, const std::string& name = "<memory>",
                             const std::string& base_folder = ".", Warnings* warnings = nullptr,
                             const ReferencePolicy& policy = {}, ObjNames* names = nullptr);

// Parses MTL text; `name` for messages, texture paths resolved relative to `base_folder` and confined to it (and
// `policy`'s folders): a `map_Kd` outside throws deform::Error.
DEFORM_IO_API std::vector<Material> parse_mtl(std::string_view text, const std::string& name,
                                              const std::string& base_folder, Warnings* warnings = nullptr,
                                              const ReferencePolicy& policy = {});

// Options for write_obj.
struct ObjWriteOptions {
  std::string mtllib{};  // written as `mtllib` when non-empty (materials are then named by `usemtl`)
  // The `o`/`g` names of the submeshes (ObjNames::submeshes), one per Mesh::submeshes entry; empty: none written.
  std::span<const ObjSubmeshNames> submesh_names{};
  bool write_normals = true;  // `vn` lines (one per render vertex) and v//vn face indices
  bool write_uvs = true;      // `vt` lines when the mesh has UVs
};

// Formats the mesh as OBJ text: one `v` per point (in order, from `positions`, which must have point_count()
// entries), then `vt`/`vn` per render vertex (normals from `normals` if not empty, else mesh.vertex_normals), then
// the faces as the file had them, with `o`/`g` (options.submesh_names) and `usemtl` where they change. Vertex i in
// means vertex i out; numbers are written in the shortest form that reads back to the same float; names and paths as
// obj_safe_name and obj_material_names give them, so that no name can inject a statement and every name reads back as
// written. Throws deform::Error (kind argument) when a span has the wrong size (submesh_names: neither empty nor one
// per submesh) or a position or normal is not finite: nothing non-finite is written.
DEFORM_IO_API std::string format_obj(const Mesh& mesh, std::span<const glm::vec3> positions,
                                     std::span<const glm::vec3> normals = {}, const ObjWriteOptions& options = {});
// Writes format_obj() to `path` atomically. Throws deform::Error on failure.
DEFORM_IO_API void write_obj(const std::string& path, const Mesh& mesh, std::span<const glm::vec3> positions,
                             std::span<const glm::vec3> normals = {}, const ObjWriteOptions& options = {});
// The ObjWriteOptions::mtllib value with which an OBJ written to `obj_path` uses the MTL files an OBJ was read with:
// each of names.material_libraries relative to obj_path's folder (absolute when no relative path exists), joined by
// spaces. Empty when there are none (a mesh built in code, or an OBJ without `mtllib`).
DEFORM_IO_API std::string material_libraries_for(const ObjNames& names, const std::string& obj_path);
// Formats the mesh's materials as MTL text (map_Kd written as given), each `newmtl` named by obj_material_names.
DEFORM_IO_API std::string format_mtl(std::span<const Material> materials);

// A name (`o`, `g`) or path (`mtllib`, `map_Kd`) as the OBJ and MTL writers write it, so that the readers read back
// exactly this string: control characters, DEL and '#' become '_', and so do blanks at either end and a final
// backslash (the reader trims blanks, and a line ending in '\\' continues on the next one). A name the readers can
// read (any name from an OBJ) is unchanged.
DEFORM_IO_API std::string obj_safe_name(std::string_view name);
// The names `usemtl` and `newmtl` give `materials`: obj_safe_name of each, "_" for an empty one, and a name an earlier
// material took suffixed "_2", "_3"... (never another material's name), so that the names read back are distinct and
// every face keeps its material.
DEFORM_IO_API std::vector<std::string> obj_material_names(std::span<const Material> materials);

}  // namespace deform
