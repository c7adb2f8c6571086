// deform export MODEL --out DIR: a model as the native OBJ + MTL + .sk + .skw, textures copied; with --format gltf,
// as one glTF 2.0 file (.gltf + .bin or .glb) with its skin and clips (docs/cli.md, docs/gltf-export.md).
#include <filesystem>
#include <optional>
#include <vector>

#include "cli.hpp"
#include "model_loader.hpp"
#include "shared_steps.hpp"
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/model.hpp"
#include "deform/version.hpp"
#ifdef DEFORM_HAVE_IMPORT
#include "deform/import/import.hpp"
#endif

namespace cli {
namespace {

using Json = nlohmann::json;  // keys in alphabetical order, as docs/cli.md shows

// Textures are taken only from the model's own folder (the current folder for --builtin).
std::string texture_root(const Args& args) {
  std::string root;
  if (!args.positionals().empty())
    root = std::filesystem::path(args.positionals()[0]).parent_path().lexically_normal().string();
  return root.empty() ? "." : root;
}

// With --rig, the rig's pose-space corrective shapes join the model's morph targets and each clip gets the weights
// its pose drivers give, keyed --fps times a second (deform::with_driven_weights), so that the file's correctives
// play in any glTF viewer; the rig's lattices and spring chains need a bake.
int run_gltf(const Args& args, const std::string& out) {
  std::optional<RiggedModel> rigged;
  if (args.has("--rig")) rigged = load_rigged_model(args);
  LoadedModel loaded = rigged ? std::move(rigged->loaded) : load_model(args);
  if (loaded.builtin) loaded.clips = deform::builtin_clips(loaded.model);  // idle, walk, run, wave
  embed_builtin_texture(loaded);
  std::vector<deform::Animation> clips = loaded.clips;
  std::optional<deform::Character> character;
  if (rigged) {
    const double fps = parse_number(args.value("--fps").value_or("30"), "--fps");
    if (!(fps > 0.0 && fps <= 1000.0)) throw UsageError("--fps must be in (0, 1000]");
    character.emplace(loaded.model, rigged->rig);
    for (deform::Animation& clip : clips) clip = deform::with_driven_weights(*character, clip, float(fps));
    if (!rigged->rig.lattices.empty() || !rigged->rig.spring_chains.empty())
      note("the rig's lattices and spring chains are not in a skinned file: `deform bake` records them");
  } else if (args.has("--fps")) {
    throw UsageError("--fps keys the weights of a rig's correctives: give --rig");
  }
  const deform::Model& model = character ? character->model() : loaded.model;
  deform::GltfExportOptions options;
  options.clips = clips;
  options.generator = "libdeform " DEFORM_VERSION_STRING;
  options.texture_root = rigged ? rigged->texture_root : texture_root(args);
  options.references = reference_policy(args);
  options.up = loaded.up;  // a Z-up import stands upright in glTF's +Y
  const deform::GltfWritten written = deform::write_gltf(out, model, options);
  for (const std::string& w : written.warnings) note(w);
  Json names = Json::array();
  for (const deform::Animation& clip : clips) names.push_back(clip.name);
  Json result{{"gltf", written.gltf},
              {"bin", written.bin.empty() ? Json(nullptr) : Json(written.bin)},
              {"bytes", written.bytes},
              {"textures", written.textures},
              {"vertices", model.mesh.point_count()},
              {"render_vertices", written.vertices},
              {"triangles", model.mesh.triangle_count()},
              {"bones", loaded.rigged ? model.skeleton.bone_count() : 0},
              {"clips", std::move(names)}};
  if (!model.morph_targets.empty()) result["morph_targets"] = model.morph_targets.size();
  print_json(result);
  return exit_ok;
}

#ifdef DEFORM_HAVE_IMPORT
int run_native(const Args& args, const std::string& out) {
  const LoadedModel loaded = load_model(args);
  const deform::Model& model = loaded.model;
  Json clips = Json::array();
  for (const deform::Animation& clip : loaded.clips) clips.push_back(clip.name);
  // Textures are copied only from the model's own folder (deform::ExportOptions).
  deform::ExportOptions options;
  options.texture_root = texture_root(args);
  options.references = reference_policy(args);
  options.submesh_names = loaded.names.submeshes;
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
int run_native(const Args&, const std::string&) {
  note(
      "'export' to native files needs the importer component (deform::import, Assimp), which this build lacks; "
      "--format gltf works without it");
  return exit_failure;
}
#endif

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = model_value_flags;
  value_flags.push_back("--out");
  value_flags.push_back("--format");
  value_flags.push_back("--rig");
  value_flags.push_back("--fps");
  const Args args(argv, value_flags, model_switch_flags);
  const std::string out = args.required("--out");
  const std::string format = args.value("--format").value_or("native");
  if (format == "gltf") {
    std::string ext = std::filesystem::path(out).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".gltf" && ext != ".glb") throw UsageError("--format gltf: --out must name a .gltf or .glb file");
    return run_gltf(args, out);
  }
  if (format != "native") throw UsageError("--format must be native or gltf");
  if (args.has("--rig") || args.has("--fps")) throw UsageError("--rig and --fps go with --format gltf");
  return run_native(args, out);
}

}  // namespace

const Command export_command = {
    "export", "write a model as OBJ + MTL + .sk + .skw, or as glTF 2.0 (--format gltf)",
    "usage: deform export MODEL --out DIR\n"
    "       deform export MESH.obj --skeleton S.sk --weights W.skw --out DIR\n"
    "       deform export --builtin --out DIR\n"
    "       deform export (MODEL | MESH.obj --skeleton S.sk --weights W.skw | --builtin) --format gltf --out FILE\n"
    "                     [--rig RIG.json [--fps N]]\n"
    "\n"
    "Writes DIR/NAME.obj, NAME.mtl, NAME.sk and NAME.skw (NAME: the model file's stem) and copies each material's\n"
    "diffuse texture into DIR; every file is written atomically. The OBJ holds the mesh in the bind pose the .sk\n"
    "describes, so `deform skin DIR/NAME.obj --skeleton DIR/NAME.sk --weights DIR/NAME.skw --pose P.json` gives\n"
    "the same result as skinning MODEL with P.json. Clips are not exported (there is no native clip file).\n"
    "Prints {\"obj\", \"mtl\", \"sk\", \"skw\": paths, \"textures\": [paths], \"vertices\", \"triangles\", \"bones\"\n"
    "(0 for a static model), \"clips\": [names]}. Importer warnings go to stderr.\n"
    "--max-influences N (1 to 16, default 4): influences kept per point from W.skw.\n"
    "--allow-outside DIR (repeatable): files the model names (MTL, textures, buffers) may also come from DIR; by\n"
    "default only its own folder is read, and a file named elsewhere is refused with exit 2 (docs/security.md).\n"
    "\n"
    "--format gltf: writes FILE as glTF 2.0 (docs/gltf-export.md): FILE.glb as one binary file, FILE.gltf plus\n"
    "NAME.bin beside it; the mesh with normals, the skeleton as nodes, the skin and every clip as an animation\n"
    "(the built-in character's: idle, walk, run, wave). Diffuse textures (PNG, JPEG) from the model's folder are\n"
    "embedded, and the built-in character's own. Prints {\"gltf\": FILE, \"bin\": path or\n"
    "null, \"bytes\", \"textures\": images embedded, \"vertices\", \"render_vertices\", \"triangles\", \"bones\",\n"
    "\"clips\": [names]}. Needs no importer for --builtin or native files.\n"
    "--rig RIG.json: the rig's pose-space correctives (docs/skinning.md) become morph targets, and each clip a\n"
    "weights track of what their drivers give, keyed --fps N times a second (default 30); prints \"morph_targets\"\n"
    "too. The rig's lattices and spring chains are not written (deform bake records them).\n"
    "\n"
    "Exit status: 0 success; 2 bad usage or a file that cannot be read (the message names it); 1 any other failure.\n",
    run};

}  // namespace cli
