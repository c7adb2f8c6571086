// deform export MODEL --out DIR: a model as the native OBJ + MTL + .sk + .skw, textures copied (docs/cli.md).
#include <filesystem>

#include "cli.hpp"
#include "model_loader.hpp"
#ifdef DEFORM_HAVE_IMPORT
#include "deform/import/import.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/model.hpp"
#endif

namespace cli {
namespace {

#ifdef DEFORM_HAVE_IMPORT
using Json = nlohmann::json;  // keys in alphabetical order, as docs/cli.md shows

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = model_value_flags;
  value_flags.push_back("--out");
  const Args args(argv, value_flags, model_switch_flags);
  const std::string out = args.required("--out");

  const LoadedModel loaded = load_model(args);
  const deform::Model& model = loaded.model;
  Json clips = Json::array();
  for (const deform::Animation& clip : loaded.clips) clips.push_back(clip.name);
  // Textures are copied only from the model's own folder (deform::ExportOptions).
  deform::ExportOptions options;
  if (!args.positionals().empty())
    options.texture_root = std::filesystem::path(args.positionals()[0]).parent_path().lexically_normal().string();
  if (options.texture_root.empty()) options.texture_root = ".";
  const deform::ExportedFiles files = deform::export_native(model, out, options);
  for (const std::string& w : files.warnings) note(w);
  print_json(Json{{"obj", files.obj},
                  {"mtl", files.mtl},
                  {"sk", files.sk},
                  {"skw", files.skw},
                  {"textures", files.textures},
                  {"vertices", model.mesh.point_count()},
                  {"triangles", model.mesh.triangle_count()},
                  {"bones", loaded.rigged ? model.skeleton.bone_count() : 0},
                  {"clips", std::move(clips)}});
  return exit_ok;
}
#else
int run(const std::vector<std::string>&) {
  note("'export' needs the importer component (deform::import, Assimp), which this build lacks");
  return exit_failure;
}
#endif

}  // namespace

const Command export_command = {
    "export", "write a model (an import: glTF, FBX, .x, ...) as OBJ + MTL + .sk + .skw",
    "usage: deform export MODEL --out DIR\n"
    "       deform export MESH.obj --skeleton S.sk --weights W.skw --out DIR\n"
    "       deform export --builtin --out DIR\n"
    "\n"
    "Writes DIR/NAME.obj, NAME.mtl, NAME.sk and NAME.skw (NAME: the model file's stem) and copies each material's\n"
    "diffuse texture into DIR; every file is written atomically. The OBJ holds the mesh in the bind pose the .sk\n"
    "describes, so `deform skin DIR/NAME.obj --skeleton DIR/NAME.sk --weights DIR/NAME.skw --pose P.json` gives\n"
    "the same result as skinning MODEL with P.json. Clips are not exported (there is no native clip file).\n"
    "Prints {\"obj\", \"mtl\", \"sk\", \"skw\": paths, \"textures\": [paths], \"vertices\", \"triangles\", \"bones\"\n"
    "(0 for a static model), \"clips\": [names]}. Importer warnings go to stderr.\n"
    "\n"
    "Exit status: 0 success; 2 bad usage or a file that cannot be read (the message names it); 1 any other failure.\n",
    run};

}  // namespace cli
