// The viewer's command line: the usage text and the parsing of each option, with its checks.
#include "options.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace viewer {
namespace {

const char* usage =
    "usage: deform_viewer [MODEL [--skeleton S.sk] [--weights W.skw] [--rig R.json]] [--clip NAME|#N [--inertia F]]\n"
    "                     [--blend NAME|#N [--blend-weight W]] [--morph NAME:W[,NAME:W...]] [--prop P.obj]...\n"
    "                     [--screenshot OUT.png --frames N [--reach X,Y,Z --at F] [--release-at F]] [--pole X,Y,Z]\n"
    "                     [--limits euler|swing-twist] [--weight-map BONE] [--weights-tool TOOL]...\n"
    "                     [--save-weights OUT.skw]\n"
    "                     [--width W] [--height H] [--zoom F] [--bare] [--gpu] [--dqs] [--up y|z]\n"
    "                     [--lattices none|active|all]\n"
    "                     [--skinning lbs|dqs|ddm] [--mush N] [--lod-bones N | --lod 0|1|2|3|auto]\n"
    "With no MODEL: the built-in character. MODEL: an OBJ (with --skeleton, and --weights or automatic weights)\n"
    "or any rigged file the importer reads (glTF, FBX, Collada, X, ...).\n"
    "--clip NAME|#N: play a clip (by name, or the N-th) from the start: the built-in character's \"walk\" (also for\n"
    "its files in samples/data), an imported file's own. --inertia F: how much the lattices lag behind the\n"
    "playing clip, [0, 1], a scale of each lattice's tuned inertia (its body part's): 1 the tuned jiggle\n"
    "(default), 0 none (the panel's \"jiggle\").\n"
    "--blend NAME|#N: blend a second clip with the --clip one, in step with its phase; --blend-weight W: the second\n"
    "clip's weight, [0, 1] (default 0.5; the first has 1 - W; the panel's \"blend with\" and \"blend\").\n"
    "--morph NAME:W: hold morph target NAME (every target of that name) at weight W over what the clip animates\n"
    "(the panel's morph sliders; `deform info MODEL` lists the targets).\n"
    "--pole X,Y,Z: the reach's pole (the elbow's hint), in the model's space. --limits swing-twist: the reach chain's\n"
    "joints limited by swing cones and twist ranges instead of Euler boxes.\n"
    "--weight-map BONE: paint the character's surface with BONE's skin weights, blue (0) to red (1); also in the\n"
    "panel.\n"
    "--weights-tool TOOL: run a weight tool on the character's weights once it is loaded and rebind it (repeatable,\n"
    "run in order; the panel's \"Weights\" buttons; `deform weights-edit`'s tools): heat[:C] (automatic bone heat\n"
    "weights again, heat constant C, default 1), normalize, prune:T (0 to 1), limit:N (1 to 16), smooth:N[:F]\n"
    "(N passes, 1 to 100, factor F in (0, 1], default 0.5), mirror:flip|positive-to-negative|negative-to-positive,\n"
    "revert (the model's own weights). A tool that refuses (mirror on an asymmetric mesh) says why on stderr and\n"
    "keeps the weights. --save-weights OUT.skw: write the weights after the tools (atomically).\n"
    "--gpu: skinning and lattices on the GPU (OpenGL 4.3), the CPU only posing. --dqs: start with dual quaternion\n"
    "skinning. --skinning ddm: Direct Delta Mush (CPU only; --dqs is --skinning dqs). --mush N: Delta Mush with N\n"
    "iterations after the lattices (CPU only; 0, the default: off). --lod-bones N: the level of detail that skins "
    "with\n"
    "N bones, merged on the motion of the model's clips (CPU only; docs/skinning.md, \"Levels of detail\").\n"
    "--lod L: the character at level L of four levels of detail (CPU only): 0 the whole character; 1, 2 and 3 with\n"
    "3/4, 1/2 and 1/3 of the bones, the mesh simplified to 0.5, 0.25 and 0.1 of its triangles (where libdeform has\n"
    "its simplify layer), 1 with the deformers, 2 and 3 without, deformed every 2nd and 4th frame. --lod auto: the\n"
    "level from the character's height on screen (below 1/2, 1/4 and 1/8 of the window), switching as you zoom.\n"
    "--up z: "
    "the model's up axis is +Z (default: +Y, or "
    "what an imported file's metadata says).\n"
    "--zoom F: the camera F times as far as the distance that frames the character, [0.1, 100] (C frames it again\n"
    "so; the wheel zooms).\n"
    "--lattices: draw no lattice, the active limb's (default: the one reaching, else the one a click would move),\n"
    "or all of them (L cycles the three).\n"
    "Mouse: left click/drag a point to reach for it, release to let go; shift+left click places the pole (the\n"
    "elbow's hint); right drag orbits; middle drag or\n"
    "shift+right drag pans; wheel zooms. Keys: D cycles LBS/DQS/DDM, S the skeleton,\n"
    "L cycles the lattices shown (active limb, all, none), G the GPU deformation, R resets, C frames the\n"
    "character again (the camera fitted to the playing clip), Esc quits.\n";

// A number in [low, high]; `range` says so in the message.
float parse_in(const std::string& text, const char* what, float low, float high, const char* range) {
  char* end = nullptr;
  const float v = std::strtof(text.c_str(), &end);
  if (text.empty() || *end || !(v >= low && v <= high)) fail(std::string(what) + ": '" + text + "' is not in " + range);
  return v;
}

int parse_int(const std::string& s, const char* what) {
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end || v < 0 || v > 1000000) fail(std::string(what) + ": '" + s + "' is not a count");
  return int(v);
}

glm::vec3 parse_vec3(const std::string& s, const char* what) {
  glm::vec3 v;
  char tail = 0;
  if (std::sscanf(s.c_str(), "%f,%f,%f%c", &v.x, &v.y, &v.z, &tail) != 3 || !std::isfinite(v.x + v.y + v.z))
    fail(std::string(what) + ": '" + s + "' is not X,Y,Z");
  return v;
}

// A number in [lo, hi] (finite), or nullopt.
std::optional<double> number_in(const std::string& s, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end || !std::isfinite(v) || v < lo || v > hi) return std::nullopt;
  return v;
}

// The tool a --weights-tool SPEC names (the usage text lists them), or nullopt with `error` set.
std::optional<WeightTool> parse_weight_tool(const std::string& spec, std::string& error) {
  const std::size_t colon = spec.find(':');
  const std::string name = spec.substr(0, colon);
  const std::string rest = colon == std::string::npos ? std::string() : spec.substr(colon + 1);
  const bool has_rest = colon != std::string::npos;
  WeightTool tool;
  auto refuse = [&](const std::string& why) {
    error = "'" + spec + "': " + why;
    return std::nullopt;
  };
  if (name == "normalize" || name == "revert") {
    if (has_rest) return refuse(name + " takes no value");
    tool.kind = name == "normalize" ? WeightTool::Kind::normalize : WeightTool::Kind::revert;
  } else if (name == "heat") {
    tool.kind = WeightTool::Kind::heat;
    tool.value = 1.0f;
    if (has_rest) {
      const auto c = number_in(rest, 1e-6, 1e6);
      if (!c || *c <= 0.0) return refuse("the heat constant is not a number > 0 (heat:C)");
      tool.value = float(*c);
    }
  } else if (name == "prune") {
    const auto t = number_in(rest, 0.0, 1.0);
    if (!t) return refuse("the threshold is not in [0, 1] (prune:T)");
    tool.kind = WeightTool::Kind::prune, tool.value = float(*t);
  } else if (name == "limit") {
    const auto n = number_in(rest, 1.0, 16.0);
    if (!n || *n != std::floor(*n)) return refuse("the count is not 1 to 16 (limit:N)");
    tool.kind = WeightTool::Kind::limit, tool.count = int(*n);
  } else if (name == "smooth") {
    const std::size_t second = rest.find(':');
    const auto n = number_in(rest.substr(0, second), 1.0, 100.0);
    if (!n || *n != std::floor(*n)) return refuse("the passes are not 1 to 100 (smooth:N[:F])");
    tool.kind = WeightTool::Kind::smooth, tool.count = int(*n), tool.value = 0.5f;
    if (second != std::string::npos) {
      const auto f = number_in(rest.substr(second + 1), 0.0, 1.0);
      if (!f || *f <= 0.0) return refuse("the factor is not in (0, 1] (smooth:N:F)");
      tool.value = float(*f);
    }
  } else if (name == "mirror") {
    tool.kind = WeightTool::Kind::mirror;
    if (rest == "flip") tool.mirror = 0;
    else if (rest == "positive-to-negative") tool.mirror = 1;
    else if (rest == "negative-to-positive") tool.mirror = 2;
    else return refuse("the mode is not flip, positive-to-negative or negative-to-positive (mirror:MODE)");
  } else {
    return refuse("not a weight tool (heat, normalize, prune, limit, smooth, mirror, revert)");
  }
  return tool;
}

}  // namespace

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "deform_viewer: %s\n", message.c_str());
  std::exit(2);
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) fail(a + " needs a value");
      return argv[++i];
    };
    if (a == "--help" || a == "-h") std::fputs(usage, stdout), std::exit(0);
    else if (a == "--skeleton") o.skeleton = next();
    else if (a == "--weights") o.weights = next();
    else if (a == "--rig") o.rig = next();
    else if (a == "--prop") o.props.push_back(next());
    else if (a == "--clip") o.clip = next();
    else if (a == "--blend") o.blend_clip = next();
    else if (a == "--blend-weight") o.blend_weight = parse_in(next(), "--blend-weight", 0.0f, 1.0f, "[0, 1]");
    else if (a == "--inertia") o.inertia = parse_in(next(), "--inertia", 0.0f, 1.0f, "[0, 1]");
    else if (a == "--zoom") o.zoom = parse_in(next(), "--zoom", 0.1f, 100.0f, "[0.1, 100]");
    else if (a == "--morph") {
      const std::string list = next();
      std::size_t at = 0;
      while (at <= list.size()) {
        const std::size_t comma = std::min(list.find(',', at), list.size());
        const std::string item = list.substr(at, comma - at);
        const std::size_t colon = item.rfind(':');
        char* end = nullptr;
        const float w = colon == std::string::npos ? 0.0f : std::strtof(item.c_str() + colon + 1, &end);
        if (colon == std::string::npos || colon == 0 || end == item.c_str() + colon + 1 || *end || !std::isfinite(w))
          fail("--morph: '" + item + "' is not NAME:WEIGHT");
        o.morphs.emplace_back(item.substr(0, colon), w);
        at = comma + 1;
      }
    } else if (a == "--weight-map") o.weight_map = next();
    else if (a == "--weights-tool") {
      std::string error;
      const std::optional<WeightTool> tool = parse_weight_tool(next(), error);
      if (!tool) fail("--weights-tool: " + error);
      o.weight_tools.push_back(*tool);
    } else if (a == "--save-weights") o.save_weights = next();
    else if (a == "--screenshot") o.screenshot = next();
    else if (a == "--frames") o.frames = std::max(1, parse_int(next(), "--frames"));
    else if (a == "--reach") o.reach = parse_vec3(next(), "--reach");
    else if (a == "--pole") o.pole = parse_vec3(next(), "--pole");
    else if (a == "--at") o.reach_at = parse_int(next(), "--at");
    else if (a == "--release-at") o.release_at = parse_int(next(), "--release-at");
    else if (a == "--bare") o.bare = true;
    else if (a == "--gpu") o.gpu = true;
    else if (a == "--dqs") o.dqs = true;
    else if (a == "--skinning") {
      const std::string method = next();
      if (method != "lbs" && method != "dqs" && method != "ddm")
        fail("--skinning: '" + method + "' is not lbs, dqs or ddm");
      o.dqs = method == "dqs";
      o.ddm = method == "ddm";
    } else if (a == "--mush") {
      o.mush = parse_int(next(), "--mush");
      if (o.mush > 10000) fail("--mush: more than 10000 iterations");
    } else if (a == "--lod-bones") {
      o.lod_bones = parse_int(next(), "--lod-bones");
      if (o.lod_bones < 1) fail("--lod-bones: fewer than 1 bone");
    } else if (a == "--lod") {
      const std::string level = next();
      if (level == "auto") o.lod_auto = true;
      else if (level.size() == 1 && level[0] >= '0' && level[0] <= '3') o.lod = level[0] - '0';
      else fail("--lod: '" + level + "' is not 0, 1, 2, 3 or auto");
    } else if (a == "--limits") {
      const std::string limits = next();
      if (limits != "euler" && limits != "swing-twist") fail("--limits: '" + limits + "' is not euler or swing-twist");
      o.swing_twist = limits == "swing-twist";
    } else if (a == "--up") {
      const std::string up = next();
      if (up != "y" && up != "z") fail("--up: '" + up + "' is not y or z");
      o.up = up[0];
    } else if (a == "--lattices") {
      const std::string shown = next();
      if (shown != "none" && shown != "active" && shown != "all")
        fail("--lattices: '" + shown + "' is not none, active or all");
      o.lattices = shown == "none" ? 'n' : shown == "all" ? 'e' : 'a';
    } else if (a == "--width") o.width = std::max(64, parse_int(next(), "--width"));
    else if (a == "--height") o.height = std::max(64, parse_int(next(), "--height"));
    else if (a.rfind("--", 0) == 0) fail("unknown option " + a + "\n" + usage);
    else if (o.model.empty()) o.model = a;
    else fail("more than one model given");
  }
  if (o.lod_bones > 0 && (o.lod >= 0 || o.lod_auto)) fail("--lod-bones and --lod: choose one level of detail");
  return o;
}

}  // namespace viewer
