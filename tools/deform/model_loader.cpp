// How model-taking subcommands find their model: --builtin, the native OBJ + .sk + .skw triple, or a rigged import.
#include "model_loader.hpp"

#include "deform/extras/builtin.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/sk.hpp"
#include "deform/runtime/error.hpp"

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

LoadedModel load_mesh_and_skeleton(const Args& args) {
  LoadedModel loaded;
  if (args.has("--builtin")) {
    if (!args.positionals().empty() || args.has("--skeleton"))
      throw UsageError("--builtin takes no MESH and no --skeleton");
    loaded.model = deform::builtin_character();
    loaded.source = "builtin";
    loaded.builtin = true;
    return loaded;
  }
  if (args.positionals().size() != 1) throw UsageError("expected one MESH.obj or MODEL (or --builtin)");
  const std::string source = args.positionals()[0];
  if (model_loading::importable(source)) {  // an import's mesh and skeleton, and its own weights
    model_loading::ModelRequest request;
    request.path = source;
    request.references = reference_policy(args);
    loaded = model_loading::load_model(request);
    for (const std::string& w : loaded.warnings) note(w);
    if (!loaded.rigged && !args.has("--skeleton"))
      throw deform::Error::in_file(source, "", "the model has no skeleton: give --skeleton S.sk");
    if (args.has("--skeleton")) {  // the file's weights name its own bones: they go with its skeleton
      loaded.model.skeleton = deform::read_sk(args.required("--skeleton"));
      loaded.model.weights = {};
    }
  } else {
    const std::string sk = args.required("--skeleton");
    deform::Warnings warnings;
    loaded.model.mesh = deform::read_obj(source, &warnings, reference_policy(args));
    for (const std::string& w : warnings.messages) note(w);
    loaded.model.skeleton = deform::read_sk(sk);
  }
  loaded.source = source;
  return loaded;
}

std::vector<std::string> list_values(const Args& args, std::string_view flag) {
  std::vector<std::string> items;
  for (const std::string& value : args.values(flag)) {
    std::string item;
    bool bracket = false;
    auto finish = [&] {
      if (item.empty()) throw UsageError(std::string(flag) + ": an empty item in '" + value + "'");
      items.push_back(item);
      item.clear();
    };
    for (std::size_t i = 0; i < value.size(); ++i) {
      const char c = value[i];
      if (c == '\\' && i + 1 < value.size()) {
        item += c;
        item += value[++i];
        continue;
      }
      if (c == ',' && !bracket) {
        finish();
        continue;
      }
      if (c == '[' && !bracket) {
        bracket = true;
        item += c;
        // A ']' right after '[', '[!' or '[^' is listed, not the end (glob_match's rule).
        if (i + 1 < value.size() && (value[i + 1] == '!' || value[i + 1] == '^')) item += value[++i];
        if (i + 1 < value.size() && value[i + 1] == ']') item += value[++i];
        continue;
      }
      if (c == ']' && bracket) bracket = false;
      item += c;
    }
    finish();
  }
  return items;
}

}  // namespace cli
