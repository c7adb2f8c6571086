#pragma once
// Rig files (JSON): a character's deformer set-up saved and loaded; the format is in docs/formats.md ("Rig files").
#include <cstdint>
#include <string>
#include <string_view>

#include "deform/io/export.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Reads only the "model" key of a rig file, so the caller can load the model the rest of the file refers to.
// Throws deform::Error (naming `name` and the key) for malformed JSON or a malformed "model".
DEFORM_IO_API RigModel parse_rig_model(std::string_view json, const std::string& name = "<memory>");

// Parses a rig for `skeleton` (bones are named as Skeleton::key names them) and a mesh of `point_count` points.
// Throws deform::Error naming `name`, the JSON key (e.g. "key 'lattices[1].elastic.stiffness'") and what is wrong:
// malformed JSON, a missing, unknown or mistyped key, an unknown bone, a non-finite number, a value out of range, a
// vertex out of range or repeated, a repeated lattice name, or a "parent" that is not the lattice the bones imply.
DEFORM_IO_API Rig parse_rig_json(std::string_view json, const Skeleton& skeleton, std::size_t point_count,
                                 const std::string& name = "<memory>");
DEFORM_IO_API Rig read_rig_json(const std::string& path, const Skeleton& skeleton, std::size_t point_count);
// The rig as JSON text (every field written, except a lattice's min_length_fraction and volume where they have
// StretchShape's defaults; floats shortest-exact): parse_rig_json(format_rig_json(r)) == r.
DEFORM_IO_API std::string format_rig_json(const Rig& rig, const Skeleton& skeleton);
DEFORM_IO_API void write_rig_json(const std::string& path, const Rig& rig, const Skeleton& skeleton);  // atomic

}  // namespace deform
