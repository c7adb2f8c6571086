// deform weights-edit: the weight tools a rigger applies after binding (mirror, smooth, prune, limit, normalise) on a
// .skw or a model's own weights, written as a new .skw (docs/weights.md, "Weight tools").
#include <algorithm>
#include <cmath>

#include "cli.hpp"
#include "model_loader.hpp"
#include "deform/io/sk.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
namespace cli {
namespace {

constexpr const char* usage =
    "usage: deform weights-edit MESH.obj --skeleton S.sk --weights W.skw TOOLS... --out OUT.skw\n"
    "       deform weights-edit MODEL [--skeleton S.sk --weights W.skw] TOOLS... --out OUT.skw\n"
    "       deform weights-edit --builtin [--weights W.skw] TOOLS... --out OUT.skw\n"
    "\n"
    "Applies weight tools to skin weights (docs/weights.md, \"Weight tools\"): those of W.skw, or without --weights\n"
    "the model's own (an import's skin, the built-in character's shipped weights). The mesh gives the surface to\n"
    "smooth over and the points to mirror, the skeleton the bone names. The tools given run in this order, each at\n"
    "most once, and each leaves every point's weights summing to 1:\n"
    "  --mirror MODE         left <-> right by bone names (.L/.R, _l/_r, L_/R_, Left/Right, any case form):\n"
    "                        flip (each point takes its mirror point's weights, sides swapped; twice = unchanged),\n"
    "                        positive-to-negative or negative-to-positive (one side's weights copied, mirrored,\n"
    "                        onto the other along the axis; the points on the plane are kept)\n"
    "  --smooth N            N passes of surface smoothing (half own weights, half the neighbours' mean), 1 to 100\n"
    "  --prune T             drop the influences below T (0 to 1) and renormalise; a point keeps its strongest\n"
    "  --limit N             keep the N strongest influences per point (1 to 16), renormalised\n"
    "  --normalize           renormalise every point (every tool does; alone: a hand-edited .skw made to sum to 1)\n"
    "Writes OUT.skw atomically (the pairs past the fourth on the same line); prints {\"mesh\", \"weights\",\n"
    "\"vertices\", \"bones\", \"tools\", \"max_influences\", \"output\"} and, per tool, what it did.\n"
    "\n"
    "options:\n"
    "  --axis x|y|z          --mirror's axis (default: the one along which the left/right bone pairs lie apart)\n"
    "  --plane C             --mirror's plane coordinate on the axis (default: the bone pairs' mean midpoint)\n"
    "  --tolerance D         --mirror: how near its reflection a point's mirror must lie, > 0 (default 0.1% of\n"
    "                        the mesh's bounding-box diagonal)\n"
    "  --pattern A,B         --mirror: swap the texts A and B in bone names instead of the built-in rules;\n"
    "                        repeatable\n"
    "  --smooth-factor F     --smooth: the neighbours' share per pass, > 0 to 1 (default 0.5)\n"
    "  --allow-outside DIR   files the model names may also come from DIR (repeatable; docs/security.md)\n";

int run(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--skeleton", "--weights", "--out", "--mirror", "--smooth", "--prune", "--limit", "--axis",
                   "--plane", "--tolerance", "--pattern", "--smooth-factor", "--allow-outside"},
                  {"--builtin", "--normalize"});
  const std::string out = args.required("--out");

  // --- the tools and their options, checked before anything is read ---
  std::vector<std::string> tools;
  deform::MirrorWeightsOptions mirror;
  if (const auto mode = args.value("--mirror")) {
    if (*mode == "flip") {
      mirror.mode = deform::MirrorMode::flip;
    } else if (*mode == "positive-to-negative") {
      mirror.mode = deform::MirrorMode::from_positive;
    } else if (*mode == "negative-to-positive") {
      mirror.mode = deform::MirrorMode::from_negative;
    } else {
      throw UsageError("--mirror: '" + *mode + "' is not flip, positive-to-negative or negative-to-positive");
    }
    tools.push_back("mirror");
  }
  for (const char* flag : {"--axis", "--plane", "--tolerance", "--pattern"})
    if (args.has(flag) && !args.has("--mirror")) throw UsageError(std::string(flag) + " applies to --mirror");
  if (const auto axis = args.value("--axis")) {
    if (*axis != "x" && *axis != "y" && *axis != "z") throw UsageError("--axis: '" + *axis + "' is not x, y or z");
    mirror.axis = (*axis)[0] - 'x';
  }
  if (const auto plane = args.value("--plane")) {
    const double c = parse_number(*plane, "--plane");
    if (!(std::abs(c) <= 1e18)) throw UsageError("--plane: " + *plane + " is out of range");
    mirror.plane = static_cast<float>(c);
  }
  if (const auto tolerance = args.value("--tolerance")) {
    const double d = parse_number(*tolerance, "--tolerance");
    if (!(d > 0.0 && d <= 1e18)) throw UsageError("--tolerance: " + *tolerance + " is out of range (> 0)");
    mirror.tolerance = static_cast<float>(d);
  }
  for (const std::string& pair : args.values("--pattern")) {
    const auto comma = pair.find(',');
    if (comma == std::string::npos || pair.find(',', comma + 1) != std::string::npos || comma == 0 ||
        comma + 1 == pair.size() || pair.compare(0, comma, pair, comma + 1) == 0)
      throw UsageError("--pattern: '" + pair + "' is not two different texts A,B");
    mirror.name_pairs.emplace_back(pair.substr(0, comma), pair.substr(comma + 1));
  }
  deform::SmoothWeightsOptions smooth;
  if (const auto n = args.value("--smooth")) {
    smooth.iterations = static_cast<int>(parse_integer(*n, "--smooth", 1, 100));
    tools.push_back("smooth");
  }
  if (const auto f = args.value("--smooth-factor")) {
    if (!args.has("--smooth")) throw UsageError("--smooth-factor applies to --smooth");
    const double factor = parse_number(*f, "--smooth-factor");
    if (!(factor > 0.0 && factor <= 1.0)) throw UsageError("--smooth-factor: " + *f + " is outside (0, 1]");
    smooth.factor = static_cast<float>(factor);
  }
  float threshold = 0.0f;
  if (const auto t = args.value("--prune")) {
    const double value = parse_number(*t, "--prune");
    if (!(value >= 0.0 && value <= 1.0)) throw UsageError("--prune: " + *t + " is outside [0, 1]");
    threshold = static_cast<float>(value);
    tools.push_back("prune");
  }
  int limit = 0;
  if (const auto n = args.value("--limit")) {
    limit = static_cast<int>(parse_integer(*n, "--limit", 1, deform::max_requested_influences));
    tools.push_back("limit");
  }
  if (args.has("--normalize")) tools.push_back("normalize");
  if (tools.empty()) throw UsageError("no tool given: --mirror, --smooth, --prune, --limit or --normalize");

  // --- the model, and the weights: --weights W.skw, or the model's own ---
  LoadedModel loaded = load_mesh_and_skeleton(args);
  const deform::Mesh& mesh = loaded.model.mesh;
  const deform::Skeleton& skeleton = loaded.model.skeleton;
  deform::SkinWeights weights;
  std::string weights_source;
  if (const auto path = args.value("--weights")) {
    weights = deform::read_skw(*path, mesh.point_count(), skeleton.bone_count(), deform::max_requested_influences);
    weights_source = *path;
  } else if (loaded.model.weights.size() == mesh.point_count() && mesh.point_count() > 0) {
    weights = std::move(loaded.model.weights);
    weights_source = loaded.source;
  } else {
    throw UsageError("--weights W.skw is required: '" + loaded.source + "' has no weights of its own" +
                     (args.has("--skeleton") && !args.positionals().empty() ? " for that skeleton" : ""));
  }
  std::size_t most_before = 0;
  for (std::size_t p = 0; p < weights.size(); ++p)
    most_before = std::max(most_before, deform::influence_count(weights, p));

  nlohmann::json report = {{"mesh", loaded.source},
                           {"weights", weights_source},
                           {"vertices", mesh.point_count()},
                           {"bones", skeleton.bone_count()},
                           {"tools", tools},
                           {"output", out}};
  if (args.has("--mirror")) {
    deform::MirrorWeightsResult result = deform::mirror_weights(weights, mesh, skeleton, mirror);
    weights = std::move(result.weights);
    report["mirror"] = {{"axis", std::string(1, static_cast<char>('x' + result.axis))},
                        {"plane", result.plane},
                        {"bone_pairs", result.bone_pairs},
                        {"points", result.points}};
  }
  if (args.has("--smooth")) {
    // Smoothing spreads each bone to the neighbours; it keeps as many influences as the input had, at least four.
    smooth.max_influences = static_cast<int>(std::max<std::size_t>(most_before, deform::max_influences));
    deform::smooth_weights(weights, mesh, smooth);
    report["smooth"] = {{"iterations", smooth.iterations}, {"factor", smooth.factor}};
  }
  if (args.has("--prune")) report["pruned"] = deform::prune_weights(weights, threshold);
  if (args.has("--limit")) report["limited"] = deform::limit_influences(weights, limit);
  if (args.has("--normalize")) deform::normalize_weights(weights);

  deform::write_skw(out, weights);
  std::size_t most = 0;
  for (std::size_t p = 0; p < weights.size(); ++p) most = std::max(most, deform::influence_count(weights, p));
  report["max_influences"] = most;
  print_json(report);
  return exit_ok;
}

}  // namespace

const Command weights_edit_command = {"weights-edit", "apply weight tools: mirror, smooth, prune, limit, normalize",
                                      usage, run};

}  // namespace cli
