#pragma once
// A rigged model from its native files: OBJ (+ MTL) + .sk + .skw.
#include <string>

#include "deform/io/export.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/model.hpp"

namespace deform {

// Loads OBJ + .sk + .skw and checks they belong together (weights per OBJ `v`, bone ids in the skeleton).
// Throws deform::Error naming the offending file.
DEFORM_IO_API Model load_model(const std::string& obj_path, const std::string& sk_path, const std::string& skw_path,
                            Warnings* warnings = nullptr);

}  // namespace deform
