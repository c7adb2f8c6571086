// How model-taking subcommands find their model: --builtin, the native OBJ + .sk + .skw triple, or a rigged import.
#include "model_loader.hpp"

namespace cli {

deform::ReferencePolicy reference_policy(const Args& args) {
  deform::ReferencePolicy policy;
  policy.allow_outside = args.values("--allow-outside");
  for (const std::string& folder : policy.allow_outside)
    if (folder.empty()) throw UsageError("--allow-outside needs a folder");
  return policy;
}

LoadedModel load_model(const Args& args) {
  const auto skeleton = args.value("--skeleton");
  const auto weights = args.value("--weights");
  const std::vector<std::string>& files = args.positionals();

  model_loading::ModelRequest request;
  request.references = reference_policy(args);
  if (args.has("--builtin")) {
    if (!files.empty()) throw UsageError("--builtin takes no model file (got '" + files[0] + "')");
    if (skeleton || weights) throw UsageError("--builtin takes no --skeleton or --weights");
  } else {
    if (files.size() != 1)
      throw UsageError(files.empty() ? "expected a model: MESH.obj --skeleton S.sk --weights W.skw, or --builtin"
                                     : "expected one model file, got " + std::to_string(files.size()));
    request.path = files[0];
    if (skeleton || weights) {  // the native triple: an OBJ with its skeleton and weights
      if (!skeleton) throw UsageError("--skeleton S.sk is required with --weights");
      if (!weights) throw UsageError("--weights W.skw is required with --skeleton (`deform weights` computes them)");
      request.skeleton = *skeleton;
      request.weights = *weights;
      if (const auto n = args.value("--max-influences"))
        request.influences =
            static_cast<int>(parse_integer(*n, "--max-influences", 1, deform::max_requested_influences));
    } else if (!model_loading::importable(request.path)) {
      throw UsageError("'" + request.path + "': a mesh needs --skeleton S.sk and --weights W.skw (or use --builtin)");
    }
  }
  if (args.value("--max-influences") && request.weights.empty())
    throw UsageError("--max-influences applies to --weights W.skw (an import keeps every influence)");
  LoadedModel loaded = model_loading::load_model(request);
  for (const std::string& message : loaded.warnings) note(message);
  return loaded;
}

}  // namespace cli
