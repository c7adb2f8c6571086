#pragma once
// A rigged model from its native files: OBJ (+ MTL) + .sk + .skw.
#include <string>

#include "deform/io/export.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Loads OBJ + .sk + .skw and checks they belong together (weights per OBJ `v`, bone ids in the skeleton); keeps
// `influences` per point from the .skw (read_skw: 4 by default). Throws deform::Error naming the offending file.
// The files the OBJ names are confined as read_obj confines them (`policy`); `names`, when given, receives the OBJ's
// names (read_obj), for writing the mesh again as its file had it.
DEFORM_IO_API Model load_model(const std::string& obj_path, const std::string& sk_path, const std::string& skw_path,
                               Warnings* warnings = nullptr, int influences = max_influences,
                               const ReferencePolicy& policy = {}, ObjNames* names = nullptr);

}  // namespace deform
