#pragma once
// How every `deform` subcommand that takes a model finds it:
//   --builtin                              the built-in character
//   MESH.obj --skeleton S.sk --weights W.skw   the native triple
//   MODEL.(gltf|fbx|x|dae|...)             a rigged import (when built with deform::import)
// The flags are checked here, in the CLI's words; the loading itself is model_loading (tools/model_loading), which
// the viewer shares.
#include <string>
#include <string_view>
#include <vector>

#include "cli.hpp"
#include "model_loading.hpp"
#include "deform/io/referenced_file.hpp"
namespace cli {

using model_loading::LoadedModel;

// Value flags a model-taking command must accept: --skeleton, --weights, --allow-outside.  Switch: --builtin.
inline const std::vector<std::string> model_value_flags = {"--skeleton", "--weights", "--max-influences",
                                                           "--allow-outside"};

// The folders --allow-outside DIR (repeatable) names: files a model names may be read there too
// (deform::resolve_referenced_file, docs/security.md). UsageError for an empty DIR.
deform::ReferencePolicy reference_policy(const Args& args);
inline const std::vector<std::string> model_switch_flags = {"--builtin"};

// Loads the model named by `args` (first positional, or --builtin) and prints its warnings (note()). Throws
// UsageError or deform::Error.
LoadedModel load_model(const Args& args);

// The mesh and skeleton `deform weights` and `deform weights-edit` work on: --builtin (the built-in character, its
// shipped weights), MESH.obj --skeleton S.sk (no weights: model.weights empty), or a MODEL an importer reads (its
// own weights, or none with --skeleton S.sk, which replaces its skeleton). Prints the loading's warnings (note()).
// Throws UsageError or deform::Error naming the file.
LoadedModel load_mesh_and_skeleton(const Args& args);

// The values of a repeatable list flag (`--flag A,B --flag C`), split at commas outside `[...]` and not escaped by
// a backslash (the escape is kept, for glob_match): {"A", "B", "C"}. UsageError for an empty item.
std::vector<std::string> list_values(const Args& args, std::string_view flag);

}  // namespace cli
