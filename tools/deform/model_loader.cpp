// How model-taking subcommands find their model: --builtin, the native OBJ + .sk + .skw triple, or a rigged import.
#include "model_loader.hpp"

#include "deform/extras/builtin.hpp"
#include "deform/import/import.hpp"
#include "deform/io/model_files.hpp"
#include "deform/runtime/error.hpp"
#ifdef DEFORM_HAVE_IMPORT
#include <filesystem>

#endif

namespace cli {

LoadedModel load_model(const Args& args) {
  const auto skeleton = args.value("--skeleton");
  const auto weights = args.value("--weights");
  const std::vector<std::string>& files = args.positionals();

  if (args.has("--builtin")) {
    if (!files.empty()) throw UsageError("--builtin takes no model file (got '" + files[0] + "')");
    if (skeleton || weights) throw UsageError("--builtin takes no --skeleton or --weights");
    LoadedModel loaded;
    loaded.model = deform::builtin_character();
    loaded.source = "builtin";
    return loaded;
  }
  if (files.size() != 1)
    throw UsageError(files.empty() ? "expected a model: MESH.obj --skeleton S.sk --weights W.skw, or --builtin"
                                   : "expected one model file, got " + std::to_string(files.size()));
  const std::string& path = files[0];

  // The native triple: an OBJ with its skeleton and weights.
  if (skeleton || weights) {
    if (!skeleton) throw UsageError("--skeleton S.sk is required with --weights");
    if (!weights) throw UsageError("--weights W.skw is required with --skeleton (`deform weights` computes them)");
    deform::Warnings warnings;
    LoadedModel loaded;
    loaded.model = deform::load_model(path, *skeleton, *weights, &warnings);
    loaded.source = path;
    for (const std::string& message : warnings.messages) note(message);
    return loaded;
  }

  // A rigged import: a glTF, FBX, ... file that carries its own skeleton and weights.
#ifdef DEFORM_HAVE_IMPORT
  if (deform::is_importable(path) && std::filesystem::path(path).extension() != ".obj" &&
      std::filesystem::path(path).extension() != ".OBJ") {
    deform::ImportedModel imported = deform::import_model(path);
    for (const std::string& message : imported.warnings) note(path + ": " + message);
    LoadedModel loaded;
    loaded.model = std::move(imported.model);
    loaded.source = path;
    loaded.imported = true;
    loaded.clips = std::move(imported.clips);
    return loaded;
  }
#endif

  throw UsageError("'" + path + "': a mesh needs --skeleton S.sk and --weights W.skw (or use --builtin)");
}

}  // namespace cli
