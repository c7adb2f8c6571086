// deform simplify MODEL --ratio R --out FILE: a level-of-detail mesh of a model (deform::simplify_model), written as
// glTF 2.0 with its skeleton, skin and clips (docs/cli.md, docs/skinning.md "Levels of detail").
#include <cctype>
#include <filesystem>
#include <string>
#include <vector>

#include "cli.hpp"
#include "model_loader.hpp"
#include "shared_steps.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/version.hpp"
#ifdef DEFORM_HAVE_SIMPLIFY
#include "deform/simplify/simplify.hpp"
#endif

namespace cli {
namespace {

using Json = nlohmann::json;  // keys in alphabetical order, as docs/cli.md shows

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = model_value_flags;
  value_flags.push_back("--out");
  value_flags.push_back("--ratio");
  value_flags.push_back("--max-error");
  const Args args(argv, value_flags, model_switch_flags);
  const std::string out = args.required("--out");
  std::string ext = std::filesystem::path(out).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".gltf" && ext != ".glb") throw UsageError("--out must name a .gltf or .glb file");
  const double ratio = parse_number(args.required("--ratio"), "--ratio");
  if (!(ratio > 0.0 && ratio <= 1.0)) throw UsageError("--ratio must be in (0, 1]");
  const double max_error = parse_number(args.value("--max-error").value_or("0.05"), "--max-error");
  if (!(max_error >= 0.0 && max_error <= 1.0)) throw UsageError("--max-error must be in [0, 1]");

  // The model is read (and its references confined to its folder) before a build without the simplify layer says
  // so, so that every build refuses the same files the same way.
  LoadedModel loaded = load_model(args);
#ifdef DEFORM_HAVE_SIMPLIFY
  if (loaded.builtin) loaded.clips = deform::builtin_clips(loaded.model);  // idle, walk, run, wave
  embed_builtin_texture(loaded);
  deform::SimplifySettings settings;
  settings.triangle_ratio = static_cast<float>(ratio);
  settings.max_error = static_cast<float>(max_error);
  const deform::SimplifiedModel simplified = deform::simplify_model(loaded.model, settings);
  const deform::Model& model = simplified.model;

  deform::GltfExportOptions gltf;
  gltf.clips = loaded.clips;
  gltf.generator = "libdeform " DEFORM_VERSION_STRING;
  std::string root;
  if (!args.positionals().empty())
    root = std::filesystem::path(args.positionals()[0]).parent_path().lexically_normal().string();
  gltf.texture_root = root.empty() ? "." : root;  // textures only from the model's own folder
  gltf.references = reference_policy(args);
  gltf.up = loaded.up;
  const deform::GltfWritten written = deform::write_gltf(out, model, gltf);
  for (const std::string& w : written.warnings) note(w);
  // Short of the ratio by more than a rounding: say why, so that a mesh written back unchanged is not a surprise.
  const std::size_t source = loaded.model.mesh.triangle_count(), kept = model.mesh.triangle_count();
  const double asked = ratio * double(source);
  if (double(kept) > 1.25 * asked + 2.0)
    note("kept " + std::to_string(kept) + " of " + std::to_string(source) + " triangles where --ratio asks for about " +
         std::to_string(std::size_t(asked + 0.5)) +
         (double(simplified.error) >= 0.9 * max_error
              ? ": the collapses stopped at --max-error"
              : ": the others lie on UV or normal seams and open borders, which stay (a faceted mesh, each triangle "
                "with UVs or normals of its own, keeps them all)"));
  print_json(Json{{"gltf", written.gltf},
                  {"bin", written.bin.empty() ? Json(nullptr) : Json(written.bin)},
                  {"bytes", written.bytes},
                  {"source_vertices", loaded.model.mesh.point_count()},
                  {"source_triangles", loaded.model.mesh.triangle_count()},
                  {"vertices", model.mesh.point_count()},
                  {"render_vertices", written.vertices},
                  {"triangles", model.mesh.triangle_count()},
                  {"error", simplified.error},
                  {"clips", loaded.clips.size()}});
  return exit_ok;
#else
  note("'simplify' needs the simplify component (deform::simplify, meshoptimizer), which this build lacks");
  return exit_failure;
#endif
}

}  // namespace

const Command simplify_command = {
    "simplify", "write a level-of-detail mesh of a model, skin and clips kept, as glTF 2.0",
    "usage: deform simplify (MODEL | MESH.obj --skeleton S.sk --weights W.skw | --builtin) --ratio R\n"
    "                       [--max-error E] --out FILE\n"
    "\n"
    "Simplifies the model's mesh to about R (0 < R <= 1) of its triangles by edge collapses onto its own points\n"
    "(deform::simplify_model, meshoptimizer; docs/skinning.md): the kept points keep their place, skin weights and\n"
    "morph deltas, UV seams close only along themselves, submesh and open borders stay. --max-error E (a fraction\n"
    "of the mesh's largest extent, default 0.05) stops the collapses short of R where the surface would move more.\n"
    "Writes FILE (.gltf plus NAME.bin beside it, or .glb) atomically as `deform export --format gltf` does, with the\n"
    "skeleton, the skin and the clips (the built-in character's: idle, walk, run, wave). Prints {\"gltf\": FILE,\n"
    "\"bin\": path or null, \"bytes\", \"source_vertices\", \"source_triangles\", \"vertices\", \"render_vertices\",\n"
    "\"triangles\", \"error\": the largest surface error meshoptimizer reports, as a fraction of the largest extent,\n"
    "\"clips\": count}. Short of R by more than a quarter, it says why on stderr (--max-error, or seams).\n"
    "\n"
    "Exit status: 0 success; 2 bad usage or a file that cannot be read (the message names it); 1 any other failure\n"
    "(a build without the simplify component).\n",
    run};

}  // namespace cli
