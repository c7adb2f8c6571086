#pragma once
// How every `deform` subcommand that takes a model finds it:
//   --builtin                              the built-in character
//   MESH.obj --skeleton S.sk --weights W.skw   the native triple
//   MODEL.(gltf|fbx|x|dae|...)             a rigged import (when built with deform::import)
#include <string>
#include <vector>

#include "cli.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/model.hpp"
#include "deform/io/model_files.hpp"
namespace cli {

struct LoadedModel {
  deform::Model model;
  std::string source;   // what was loaded, for messages ("builtin" or the path)
  bool imported = false;
  std::vector<deform::Animation> clips;  // an import's animation clips (empty otherwise)
};

// Value flags a model-taking command must accept: --skeleton, --weights.  Switch: --builtin.
inline const std::vector<std::string> model_value_flags = {"--skeleton", "--weights"};
inline const std::vector<std::string> model_switch_flags = {"--builtin"};

// Loads the model named by `args` (first positional, or --builtin). Throws UsageError or deform::Error.
LoadedModel load_model(const Args& args);

}  // namespace cli
