#pragma once
// Everything the viewer shows and edits, in one struct that each part takes by reference: the model and its
// character (model.cpp), the scene, camera and renderers (view.cpp), the reach and the mouse (input.cpp) and the
// panel's choices (panel.cpp). The options and the window outlive it.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "framework.hpp"  // epoxy before any other GL header

#include "deform/character/character.hpp"
#include "deform/gpu/lattice.hpp"
#include "deform/gpu/skinning.hpp"
#include "deform/offline/picking.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include "options.hpp"
#include "scene.hpp"

namespace viewer {

using Clock = std::chrono::steady_clock;

// Which lattices the overlay draws: none, the active limb's (the one reaching, else the one a click at the mouse
// would move, else the one that reached last), or all (with a dozen lattices they cage the whole body).
enum class LatticeDisplay { none, active, all };

// Marks "take the rig's elastic settings" until the first character is built.
inline deform::ElasticSettings unset_elastic() {
  deform::ElasticSettings s;
  s.oscillator.stiffness = 0.0f;
  return s;
}

struct ViewerState {
  // Whether the window's context runs the GPU deformation is asked here, once; the rest starts empty and is filled
  // by load_character, build_scene and start_deformation (main.cpp), in that order.
  ViewerState(const Options& o, sample::Window& w)
      : options(o), window(w), gpu_available(w.has_compute() && deform::GpuBezierLattice::supported()) {}

  const Options& options;
  sample::Window& window;
  deform::Model base_model;
  deform::Rig rig;
  std::vector<deform::Animation> clips;
  std::unique_ptr<deform::Character> character;
  std::unique_ptr<sample::MeshRenderer> renderer;
  glm::vec3 up{0.0f, 1.0f, 0.0f};  // the model's up direction, turned onto +Y by the model node
  const bool gpu_available;        // OpenGL 4.3 compute shaders: the GPU deformation can run
  bool gpu = false;                // skinning and lattices on the GPU
  deform::GpuSkinning gpu_skinning;
  deform::GpuLatticeFields gpu_fields;
  std::vector<glm::vec3> gpu_bind_normals;  // the character's bind normals per render vertex (set_gpu)
  std::vector<glm::vec3> gpu_points;        // drawn_points()' read back
  std::vector<glm::vec3> gpu_normals;       // ... and the render vertices' normals (the weight map's shading)
  std::vector<std::uint32_t> triangle_points;
  std::vector<glm::vec3> render_positions;
  deform::TriangleBvh bvh;
  sample::Scene scene;
  int world_node = -1, floor_node = -1, character_node = -1, model_node = -1, ball_node = -1;
  std::vector<int> prop_nodes;
  deform::Mesh floor_mesh, ball_mesh;
  std::vector<std::unique_ptr<deform::Mesh>> props;
  sample::MeshRenderer floor_renderer, ball_renderer;
  std::vector<std::unique_ptr<sample::MeshRenderer>> prop_renderers;
  sample::OverlayRenderer overlay;
  sample::OrbitCamera camera;
  sample::OrbitCamera fitted_camera;  // the camera fit_camera() chose last (C fits again)
  float panel_right = 350.0f;         // pixels: the right edge of the panel over the window's left (0: none)
  deform::ElasticSettings elastic = unset_elastic();
  int degree = 0;
  bool ddm = false;         // Direct Delta Mush skinning (the panel's DDM, D, --skinning ddm)
  int mush_iterations = 0;  // Delta Mush after the lattices (the panel's slider, --mush); 0: off
  bool reaching = false, show_skeleton = true;
  LatticeDisplay lattice_display = LatticeDisplay::active;
  std::vector<char> lattice_shown;     // per lattice: drawn this frame (lattice_display; sized by rebuild_character)
  std::int32_t hovered_effector = -1;  // the limb a click at the mouse would move (-1: none)
  int weight_bone = -1;                // the bone whose weights the weight map shows; -1: none
  std::vector<float> weight_values;    // per point, weight_bone's weight (draw_weight_map's scratch)
  // The weight tools (weights.cpp): the model's own weights (what "revert" gives back), the panel's settings of
  // each tool, and what the last tool did or why it refused (shown in the panel; refused: in red).
  deform::SkinWeights own_weights;
  WeightTool heat_tool{WeightTool::Kind::heat, 1.0f, 0, 0};
  WeightTool prune_tool{WeightTool::Kind::prune, 0.02f, 0, 0};
  WeightTool limit_tool{WeightTool::Kind::limit, 0.0f, 4, 0};
  WeightTool smooth_tool{WeightTool::Kind::smooth, 0.5f, 2, 0};
  std::string weights_message;
  bool weights_refused = false;
  int weight_tools_run = 0, weight_tools_refused = 0;  // the headless summary's counts
  bool playing = true;
  deform::StretchShape shape;        // the panel's rubber shape, for every lattice
  float max_stretch = -1.0f;         // the panel's stretch bound (-1: the rig's, taken at the first build)
  glm::vec3 pole{0.0f, 0.0f, 1.0f};  // the reach pole, model space (--pole, the panel, shift+click)
  bool use_pole = false;
  deform::Character::JointLimits reach_limits = deform::Character::JointLimits::euler;
  deform::Character::ReachSolver reach_solver = deform::Character::ReachSolver::ccd;  // (two-bone: Euler limits only)
  float soften = 0.0f;
  std::vector<glm::quat> world_rotations;  // draw_swing_twist_cones' scratch
  int clip = -1;
  Clock::time_point long_frame_at{};  // the last frame longer than the clamp: when, how long, simulated as
  float long_frame_ms = 0.0f, long_frame_simulated_ms = 0.0f;
  std::vector<const char*> clip_names;      // "(none)", then each clip's name (the panel's list)
  deform::Pose bind_pose, pose, later;      // the clip sampled now and a millisecond later, over the bind pose
  deform::Pose first, second;               // the two clips of a blend, before blending (sample_clip's scratch)
  int blend_clip = -1;                      // the clip blended with `clip` (-1: none)
  float blend_weight = 0.5f;                // its weight; `clip` has 1 - blend_weight
  float speed = 1.0f;                       // playback rate
  bool jiggle = true;                       // lattices with inertia while a clip plays
  float inertia = 1.0f;                     // the scale of each lattice's tuned inertia
  bool cut = true;                          // the next frame's pose is a jump, not motion (see main.cpp's frame())
  deform::Bounds rest_bounds;               // the bind pose, upright: its floor, its framing
  std::vector<deform::Bounds> clip_bounds;  // each clip's sampled poses, upright (posed_bounds)
  float floor_height = 0.0f;                // the eye's height above a floor
  std::vector<char> morph_held;             // per morph target: the panel (or --morph) holds its weight
  std::vector<float> morph_hold;            // ... at this weight
  std::vector<float> morph_second;          // the blended second clip's morph weights (sized once)
  std::vector<float> clip_floors;           // the floor under each clip (lowest_height)
  float clip_time = 0.0f, deform_ms = 0.0f, drag_depth = 1.0f, pick_radius = 1.0f;
  // Levels of detail (--lod, the panel; model.cpp's apply_lod): the character's four levels when set, the mesh each
  // level draws (per level, render vertex ids and their submeshes; empty: the whole mesh), the level asked for (-1:
  // picked from the character's height on screen) and the level whose triangles the renderer and picking have.
  bool lod_levels = false;
  std::vector<std::vector<std::uint32_t>> lod_triangles;
  std::vector<std::vector<deform::Submesh>> lod_submeshes;
  int lod_choice = -1;
  int lod_drawn = 0;
  glm::vec3 lod_centre{0.0f};  // the bind pose's box centre, model space: where the camera's distance is taken to
  std::int32_t effector = -1;
  glm::vec3 target{0.0f};
  deform::ReachResult last_reach;
};

}  // namespace viewer
