// deform weights: automatic skin weights (.skw) for an OBJ + .sk pair, or for the built-in character.
#include <algorithm>

#include "cli.hpp"
#include "model_loading.hpp"
#include "model_loader.hpp"
#include "deform/io/sk.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/offline/voxel_weights.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
namespace cli {
namespace {

constexpr const char* usage =
    "usage: deform weights MESH.obj --skeleton S.sk --out W.skw [--method heat|voxel|distance] [OPTIONS]\n"
    "       deform weights MODEL [--skeleton S.sk] --out W.skw [--method heat|voxel|distance] [OPTIONS]\n"
    "       deform weights --builtin --out W.skw [--method heat|voxel|distance] [OPTIONS]\n"
    "\n"
    "Computes automatic skin weights for the mesh's points (one .skw line per OBJ `v`) from the skeleton's bind pose\n"
    "(docs/weights.md). --builtin uses the built-in character's mesh and skeleton; a MODEL an importer reads (glTF,\n"
    "FBX, ...), its mesh and its own skeleton (or S.sk), its file's weights left aside.\n"
    "--allow-outside DIR (repeatable): files the model names (MTL, textures, buffers) may also come from DIR; by\n"
    "default only its own folder is read, and a file named elsewhere is refused with exit 2 (docs/security.md).\n"
    "  heat (default)  bone heat diffusion over the surface (Baran & Popovic 2007): each point is heated by its\n"
    "                  nearest bone that it sees through no triangle, and the heat of each bone spreads over the\n"
    "                  surface; a hand resting against a thigh keeps its arm's weights.\n"
    "  voxel           geodesic voxel binding (after Dionne & de Lasa 2013): distances to the bones measured\n"
    "                  inside the voxelised volume, then falloff and smoothing as for distance.\n"
    "  distance        distance to each bone segment, only the nearest bone, its parent and its children competing,\n"
    "                  inverse-distance falloff, then one-ring smoothing (docs/builtin-character.md).\n"
    "Writes W.skw atomically; prints {\"method\", \"mesh\", \"vertices\", \"bones\", \"deforming\", "
    "\"max_influences\",\n"
    "\"warnings\", \"output\"}. Each warning (a bone that gets no vertex, an island of the mesh that sees no bone)\n"
    "goes to stderr.\n"
    "\n"
    "which bones deform (default: all):\n"
    "  --deform-bones LIST   only the bones whose names match one of LIST's shell-style globs (* any run, ? one\n"
    "                        character, [abc] [a-z] [!abc] one of a set, \\c the character c), comma-separated,\n"
    "                        repeatable; the word `used`: the bones the model's own weights use (an import's skin,\n"
    "                        the built-in character's shipped weights). A glob that matches no bone is an error.\n"
    "  --exclude-bones LIST  never the bones matching LIST (applied after --deform-bones)\n"
    "\n"
    "options:\n"
    "  --max-influences N   bones per vertex, 1 to 4 (default 4); heat: up to 16, the pairs past the fourth on\n"
    "                       the same .skw line (read them with deform skin --max-influences N)\n"
    "  --leaf-length L      a leaf bone's length as a multiple of its distance to its parent, >= 0 (default 1)\n"
    "heat only:\n"
    "  --heat C             heat constant of H = C / d^2, > 0 (default 1; higher = sharper joints)\n"
    "  --oblique-penalty K  how much farther a bone seen obliquely counts when the nearest is chosen, >= 0\n"
    "                       (default 0.3; 0 = plain distance)\n"
    "  --smoothing N        passes of surface smoothing after the solve, 0 to 100 (default 0): half own weights,\n"
    "                       half the neighbours' mean (deform weights-edit --smooth)\n"
    "voxel only:\n"
    "  --resolution N       voxels along the longest side of the mesh's box, 8 to 1024 (default 128)\n"
    "distance and voxel:\n"
    "  --falloff P          inverse-distance power, > 0 (default 4; higher = sharper joints)\n"
    "  --smoothing N        one-ring smoothing passes, 0 to 100 (default 2)\n"
    "distance only:\n"
    "  --behind-penalty K   weight of the distance behind a bone's head, >= 1 (default 2)\n";

// A numeric option's value, `fallback` when absent; UsageError unless it lies in [min, 1e6] (and above `min` when
// `above` is set).
float number_option(const Args& args, const char* flag, float fallback, float min, bool above = false) {
  const auto text = args.value(flag);
  if (!text) return fallback;
  const double value = parse_number(*text, flag);
  if (value < min || (above && value == min) || value > 1e6)
    throw UsageError(std::string(flag) + ": " + *text + " is out of range");
  return static_cast<float>(value);
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--skeleton", "--out", "--method", "--heat", "--oblique-penalty", "--resolution", "--falloff",
                   "--max-influences", "--smoothing", "--behind-penalty", "--leaf-length", "--allow-outside",
                   "--deform-bones", "--exclude-bones"},
                  {"--builtin"});
  const std::string out = args.required("--out");
  const std::string method = args.value("--method").value_or("heat");
  if (method != "heat" && method != "voxel" && method != "distance")
    throw UsageError("--method: '" + method + "' is not heat, voxel or distance");
  const std::vector<const char*> not_for =
      method == "heat"    ? std::vector<const char*>{"--resolution", "--falloff", "--behind-penalty"}
      : method == "voxel" ? std::vector<const char*>{"--heat", "--oblique-penalty", "--behind-penalty"}
                          : std::vector<const char*>{"--heat", "--oblique-penalty", "--resolution"};
  for (const char* flag : not_for)
    if (args.value(flag)) throw UsageError(std::string(flag) + " does not apply to --method " + method);
  deform::AutoWeightsOptions options;
  options.falloff_power = number_option(args, "--falloff", options.falloff_power, 0.0f, true);
  options.behind_head_penalty = number_option(args, "--behind-penalty", options.behind_head_penalty, 1.0f);
  options.leaf_length = number_option(args, "--leaf-length", options.leaf_length, 0.0f);
  int influences = deform::max_influences;
  if (auto n = args.value("--max-influences")) {
    const int most = method == "heat" ? deform::max_requested_influences : deform::max_influences;
    influences = static_cast<int>(parse_integer(*n, "--max-influences", 1, most));
  }
  options.max_influences = std::min(influences, deform::max_influences);
  if (auto n = args.value("--smoothing"))
    options.smoothing_iterations = static_cast<int>(parse_integer(*n, "--smoothing", 0, 100));
  deform::HeatWeightsOptions heat_options;
  heat_options.heat = number_option(args, "--heat", heat_options.heat, 0.0f, true);
  heat_options.oblique_penalty = number_option(args, "--oblique-penalty", heat_options.oblique_penalty, 0.0f);
  heat_options.leaf_length = options.leaf_length;
  heat_options.max_influences = influences;
  heat_options.smoothing_iterations = args.value("--smoothing") ? options.smoothing_iterations : 0;
  deform::VoxelWeightsOptions voxel_options;
  if (auto n = args.value("--resolution"))
    voxel_options.resolution = static_cast<int>(parse_integer(*n, "--resolution", 8, 1024));
  voxel_options.falloff_power = options.falloff_power;
  voxel_options.smoothing_iterations = options.smoothing_iterations;
  voxel_options.leaf_length = options.leaf_length;
  voxel_options.max_influences = options.max_influences;

  LoadedModel loaded = load_mesh_and_skeleton(args);
  const deform::Mesh& mesh = loaded.model.mesh;
  const deform::Skeleton& skeleton = loaded.model.skeleton;
  const std::string& source = loaded.source;

  // --- which bones deform: every bone, or those the globs name; `used`: those the model's own weights use ---
  std::vector<std::string> include = list_values(args, "--deform-bones");
  const std::vector<std::string> exclude = list_values(args, "--exclude-bones");
  std::vector<std::uint8_t> deforming, also;
  const auto used = std::find(include.begin(), include.end(), "used");
  if (used != include.end()) {
    if (loaded.model.weights.size() == 0)
      throw UsageError("--deform-bones used: '" + source +
                       "' has no weights of its own to take the bones from (an import or --builtin has)");
    include.erase(std::remove(include.begin(), include.end(), "used"), include.end());
    also = deform::weighted_bones(loaded.model.weights, skeleton.bone_count());
  }
  if (!include.empty() || !exclude.empty() || !also.empty())
    deforming = deform::select_bones(skeleton, include, exclude, also);
  options.deforming = deforming;
  heat_options.deforming = deforming;
  voxel_options.deforming = deforming;
  std::size_t deforming_count = skeleton.bone_count();
  if (!deforming.empty()) deforming_count = static_cast<std::size_t>(std::count(deforming.begin(), deforming.end(), 1));

  deform::WeightsResult result;
  if (method == "heat") {
    result = deform::compute_heat_weights(mesh, skeleton, heat_options);
  } else if (method == "voxel") {
    result = deform::compute_voxel_weights(mesh, skeleton, voxel_options);
  } else {
    result.weights = deform::compute_automatic_weights(mesh, skeleton, options);
    result.warnings = deform::bones_without_vertices(result.weights, skeleton, deforming);
  }
  const deform::SkinWeights& weights = result.weights;
  deform::write_skw(out, weights);
  for (const std::string& w : result.warnings) note(w);

  std::size_t most = 0;
  for (std::size_t p = 0; p < weights.size(); ++p) most = std::max(most, deform::influence_count(weights, p));
  print_json({{"method", method},
              {"mesh", source},
              {"vertices", mesh.point_count()},
              {"bones", skeleton.bone_count()},
              {"deforming", deforming_count},
              {"max_influences", most},
              {"warnings", result.warnings.size()},
              {"output", out}});
  return exit_ok;
}

}  // namespace

const Command weights_command = {"weights", "compute automatic skin weights (.skw)", usage, run};

}  // namespace cli
