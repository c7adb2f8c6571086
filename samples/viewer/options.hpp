#pragma once
// The viewer's command line (options.cpp): what it asks for, checked as it is read. A wrong option ends the viewer
// with a message naming it (fail), before any window opens.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace viewer {

// One weight tool run on the character's weights (weights.cpp): --weights-tool on the command line, or the panel's
// "Weights" buttons. The names are `deform weights-edit`'s.
struct WeightTool {
  enum class Kind { heat, normalize, prune, limit, smooth, mirror, revert };
  Kind kind = Kind::normalize;
  float value = 0.0f;  // heat: the heat constant (> 0); prune: the threshold [0, 1]; smooth: the factor (0, 1]
  int count = 0;       // limit: the influences kept (1 .. 16); smooth: the passes (1 .. 100)
  int mirror = 0;      // 0 flip, 1 positive-to-negative, 2 negative-to-positive
};

struct Options {
  std::string model, skeleton, weights, rig, screenshot, clip, blend_clip, weight_map;
  std::vector<WeightTool> weight_tools;  // --weights-tool, run in order once the model is loaded
  std::string save_weights;              // --save-weights: the weights written there (.skw) after the tools
  std::vector<std::string> props;
  std::vector<std::pair<std::string, float>> morphs;  // --morph NAME:W: held morph weights
  int frames = 120, reach_at = 0, release_at = -1, width = 1280, height = 800;
  float zoom = 1.0f;          // the camera this many times as far as the distance that frames the character
  float inertia = 1.0f;       // while a clip plays, the scale of each lattice's tuned inertia (scaled_inertia)
  float blend_weight = 0.5f;  // the second clip's weight
  bool bare = false;          // the character alone: no floor, props, overlays or panel (for pixel tests)
  bool gpu = false;           // start with the deformation (skinning and lattices) on the GPU
  bool dqs = false;           // start with dual quaternion skinning
  bool ddm = false;           // start with Direct Delta Mush skinning (--skinning ddm)
  int mush = 0;               // Delta Mush iterations after the lattices (--mush; 0: off)
  int lod_bones = 0;          // --lod-bones N: skin with N bones merged on the clips' motion (0: every bone)
  int lod = -1;               // --lod L: show level L (0 to 3) of the viewer's levels of detail; -1: none
  bool lod_auto = false;      // --lod auto: the level from the character's height on screen
  bool swing_twist = false;   // reach with swing-twist joint limits
  char up = 0;                // the model's up axis: 'y', 'z', or 0 for the file's own (+Y when it says nothing)
  char lattices = 'a';        // which lattices are drawn: 'n'one, the 'a'ctive limb's, or 'e'very one (--lattices)
  std::optional<glm::vec3> reach, pole;
};

// Prints "deform_viewer: MESSAGE" on stderr and exits with status 2.
[[noreturn]] void fail(const std::string& message);

// The options of the command line; --help prints the usage and exits 0, a wrong option fails.
Options parse_options(int argc, char** argv);

}  // namespace viewer
