// deform_viewer: the rubber-arm character on screen. Click a point of the scene: the nearest arm reaches for it by
// IK and, when it is out of reach, stretches elastically; let go and it springs back. Everything deforming is the
// libdeform facade (deform::Character); this file only draws it and turns mouse and keys into calls.
//
//   deform_viewer [MODEL [--skeleton S.sk] [--weights W.skw] [--rig R.json]] [--clip NAME|#N [--inertia F]]
//                 [--blend NAME|#N [--blend-weight W]] [--morph NAME:W[,...]] [--prop P.obj]... [--gpu] [--dqs]
//                 [--skinning lbs|dqs|ddm] [--mush N]
//                 [--up y|z] [--lattices none|active|all] [--weight-map BONE] [--weights-tool TOOL]...
//                 [--save-weights OUT.skw]
//   deform_viewer --screenshot out.png --frames N [--reach X,Y,Z --at F] [--release-at F] [--pole X,Y,Z]
//
// Clips (the built-in character's walk, an imported file's clips) play with secondary motion: each frame samples
// the clip now and a millisecond later (Character::set_pose(pose, later, lead)), so the lattices' inertia and the
// rig's spring chains follow the motion between frames; a reach is solved again on every frame's pose. A second
// clip blends with the first (deform::BlendingJob, the panel's "blend with" and its weight), following the first
// clip's phase so that clips of different lengths (a walk and a run) stay in step.
//
// Morph targets (an imported file's blend shapes) morph the character (Character::set_morph_weights): each target's
// weight follows the playing clip's morph channels (blended like the poses with a second clip), else its default;
// the panel shows each weight as a slider, and moving one (or --morph NAME:W) holds it until "follow the clip".
//
// Deformation on the GPU (--gpu, the panel or G; OpenGL 4.3): the character only poses on the CPU
// (Character::settings.deform_on_cpu = false); deform::GpuSkinning skins it into the vertex buffer from the palette and
// deform::GpuLatticeFields::apply_into adds the lattices' carried points and fields there. --up z stands a
// Z-up model upright by turning its scene node; imported files say their up axis themselves where Assimp reads it.
//
// Framing: the camera fits the box of what plays (the bind pose, or the poses of the playing clip sampled when the
// model loads), so a clip that stands a character elsewhere than its bind pose keeps it in frame; C fits it again.
// The lattice overlay draws the active limb's lattices (reaching, or under the mouse), all of them on request (L).
//
// Weights (--weight-map BONE, the panel's "Weights"): one bone's weights painted on the surface; the weight tools
// (--weights-tool, the panel's buttons) change the weights offline and bind the character again with them.
//
// The parts (samples/README.md): options.cpp reads the command line, model.cpp loads the model and drives the
// Character, view.cpp builds the scene and draws it, input.cpp turns the mouse and keys into reaches and toggles,
// panel.cpp is the ImGui panel, weights.cpp runs the weight tools on the character's weights; they share one
// ViewerState (state.hpp). This file runs the frames.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <span>

#include "framework.hpp"  // epoxy before any other GL header

#include <GLFW/glfw3.h>

#include "deform/runtime/error.hpp"
#include "input.hpp"
#include "model.hpp"
#include "options.hpp"
#include "panel.hpp"
#include "state.hpp"
#include "view.hpp"
#include "weights.hpp"

namespace viewer {
namespace {

// One frame of `dt` seconds: the camera, keys and mouse, the floor, the clip's pose, the morph weights, the
// character's update (timed: the panel's deformation time), then the drawing.
void frame(ViewerState& state, float dt) {
  const sample::Input& in = state.window.input();
  state.camera.handle(in, state.window.framebuffer_size());
  handle_keys(state, in.key_pressed);
  handle_mouse(state, in);
  place_floor(state);
  animate(state, dt);
  apply_morph_weights(state);
  choose_lod(state);
  if (state.cut) {  // a new clip, a rebuilt character: the pose jumps, which a zero step takes as a cut, not motion
                    // (a reach that begins or ends is one the character takes care of itself)
    state.character->update(0.0f);
    state.cut = false;
  }
  const auto start = Clock::now();
  state.character->update(dt);
  const auto normals = state.gpu ? std::span<const glm::vec3>{} : state.character->normals();
  state.deform_ms =
      0.9f * state.deform_ms + 0.1f * std::chrono::duration<float, std::milli>(Clock::now() - start).count();
  draw(state, normals);
}

// The headless run (--screenshot): fixed 60 Hz steps, the scripted reach and release, the last frame written as a
// PNG and a JSON line of what the tests check on stdout. Returns the exit status.
int run_headless(ViewerState& state) {
  const Options& options = state.options;
  sample::Window& window = state.window;
  // Fixed 60 Hz steps: the same command gives the same picture.
  for (int f = 0; f < options.frames; ++f) {
    if (options.reach && f == options.reach_at) reach_world(state, *options.reach);
    if (f == options.release_at) release(state);
    window.begin_frame();
    frame(state, 1.0f / 60.0f);
    panel(state, 0.0f);
    if (f + 1 == options.frames) {
      if (!window.save_png(options.screenshot)) {
        std::fprintf(stderr, "deform_viewer: cannot write %s\n", options.screenshot.c_str());
        return 1;
      }
    }
    window.end_frame();
  }
  const glm::vec3 e = effector_position(state);
  const glm::vec3 up = state.up;
  std::printf(
      "{\"screenshot\": \"%s\", \"frames\": %d, \"renderer\": \"%s\", \"gpu_lattices\": %s, "
      "\"up\": [%g, %g, %g], \"effector\": [%.5f, %.5f, %.5f], \"floor\": %.6f, \"lowest\": %.6f, "
      "\"morph_weights\": [%s], \"lattices_shown\": %d, \"floor_row\": %.1f, \"weight_tools_run\": %d, "
      "\"weight_tools_refused\": %d, \"lod_level\": %zu, \"lod_triangles\": %zu}\n",
      options.screenshot.c_str(), options.frames, window.renderer_name().c_str(), state.gpu ? "true" : "false",
      double(up.x), double(up.y), double(up.z), e.x, e.y, e.z, double(floor_y(state)), double(lowest_y(state)),
      morph_weights_text(state).c_str(), lattices_shown(state), double(floor_row(state)), state.weight_tools_run,
      state.weight_tools_refused, state.character->level(), state.renderer->triangle_count());
  return 0;
}

// The interactive loop, until the window closes or Esc.
void run_interactive(ViewerState& state) {
  sample::Window& window = state.window;
  // A frame longer than max_dt (a stall, a dragged window) is simulated as max_dt, so a stall never lands as one
  // big jump of the clip and the springs; the panel reports each such frame instead of it passing as slow motion.
  constexpr float max_dt = 0.1f;
  auto last = Clock::now();
  float frame_ms = 16.0f;
  while (!window.should_close()) {
    const auto now = Clock::now();
    const float took = std::chrono::duration<float>(now - last).count();
    const float dt = std::min(max_dt, took);
    last = now;
    frame_ms = 0.95f * frame_ms + 0.05f * took * 1000.0f;
    window.begin_frame();
    if (window.input().key_pressed == GLFW_KEY_ESCAPE) break;
    if (took > max_dt) note_long_frame(state, took, dt);
    frame(state, dt);
    panel(state, frame_ms);
    window.end_frame();
  }
}

}  // namespace
}  // namespace viewer

int main(int argc, char** argv) {
  const viewer::Options options = viewer::parse_options(argc, argv);
  const bool headless = !options.screenshot.empty();
  sample::Window window;
  if (!window.open({"libdeform viewer", options.width, options.height, headless})) {
    std::fprintf(stderr, "deform_viewer: cannot open an OpenGL 3.3 window%s\n",
                 std::getenv("DISPLAY") ? "" : " (no DISPLAY: run under xvfb-run, or use --screenshot with xvfb-run)");
    return 1;
  }
  try {
    viewer::ViewerState state(options, window);
    viewer::load_character(state);
    viewer::build_scene(state);
    viewer::start_deformation(state);
    viewer::run_option_weight_tools(state);  // last, as a click in the panel would: every setting is in place
    if (headless) return viewer::run_headless(state);
    viewer::run_interactive(state);
  } catch (const deform::Error& e) {
    std::fprintf(stderr, "deform_viewer: %s\n", e.what());
    return 2;
  }
  return 0;
}
