#pragma once
// The one rule for every file a model names (glTF buffers and images, OBJ `mtllib`, MTL `map_Kd`, IQM and Assimp
// texture paths, the model a rig file names): it is read only when it lies inside the referring file's folder once
// `..`, percent-encoding and symbolic links are resolved, or inside a folder the caller allows on purpose
// (ReferencePolicy). Every reader calls resolve_referenced_file before it opens such a file (docs/security.md).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "deform/io/export.hpp"

namespace deform {

// Where a model's references may lead besides its own folder.
struct ReferencePolicy {
  // Folders whose files any model may name, each taken with its symbolic links resolved (a folder that does not
  // exist allows nothing that exists). Empty: the referring file's folder only.
  std::vector<std::string> allow_outside;
};

// How the reference is written: a file path as is (OBJ, MTL, IQM, Assimp, rig files), or a URI reference whose
// %XX escapes are decoded first (glTF 2.0 §3.5: `buffers[i].uri`, `images[i].uri`).
enum class ReferenceSyntax { path, uri };

// The canonical path (absolute, no `.`, `..` or symbolic link) of the file that `reference`, written in `referrer`
// under `key` (e.g. "buffers[0].uri", "mtllib", "map_Kd"), names: `reference` relative to the referrer's folder
// unless absolute. Throws deform::Error (kind input) naming `referrer`, `line` when above 0, and `key`, when the
// reference is empty or holds a NUL byte, or when the file lies outside the referrer's folder and every folder of
// `policy`. The refused file is never opened: the message quotes the reference as written and the folder, never the
// file's size or content, and a missing file outside is refused as an existing one is. A reference inside that does
// not exist is returned as the path it would have (callers decide: a missing texture is a warning, a missing buffer
// an error). Cost: one stat per component of the path (std::filesystem::weakly_canonical); no allocation beyond the
// paths.
DEFORM_IO_API std::string resolve_referenced_file(const std::string& referrer, std::string_view reference,
                                                  const std::string& key, const ReferencePolicy& policy = {},
                                                  ReferenceSyntax syntax = ReferenceSyntax::path,
                                                  std::int64_t line = 0);

// The same for text read from memory or from a file whose references are relative to another folder (parse_obj's
// `base_folder`): `folder` is the one references are resolved in and confined to; `referrer` only names the source
// in messages.
DEFORM_IO_API std::string resolve_referenced_file_in(const std::string& folder, const std::string& referrer,
                                                     std::string_view reference, const std::string& key,
                                                     const ReferencePolicy& policy = {},
                                                     ReferenceSyntax syntax = ReferenceSyntax::path,
                                                     std::int64_t line = 0);

// Whether `path` lies inside `folder` (strictly below it) once both are made canonical; false when either cannot be
// resolved. The test resolve_referenced_file applies, for callers that hold a path already (texture copies).
DEFORM_IO_API bool lies_inside(const std::string& path, const std::string& folder);

// A URI reference with its %XX escapes decoded (a '%' not followed by two hex digits is kept as is; '+' stays '+').
DEFORM_IO_API std::string decode_uri_reference(std::string_view uri);

// The image format of the file at `path` by its first bytes, read alone (at most 32, whatever the file's size):
// "png", "jpeg", "bmp", "gif", "dds", "ktx", "tiff", "hdr", "psd", "webp", or "tga" for a file of 18 bytes or more
// named .tga (TGA has no signature); "" for anything else or a file that cannot be read. Never reads the whole file.
DEFORM_IO_API std::string image_format(const std::string& path);

}  // namespace deform
