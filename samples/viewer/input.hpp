#pragma once
// The mouse and the keys (input.cpp): picking a point of the scene, the reach for it (and its drag and release),
// the pole placed by shift+click, the limb under the mouse, and the keys' toggles.
#include "state.hpp"

namespace viewer {

// This frame's key (GLFW_KEY_*, 0 for none): D, S, L, G, R, C as the usage says (Esc is the main loop's).
void handle_keys(ViewerState& state, int key);
// This frame's mouse: the limb under it, the reach a left click starts, its drag and release, shift+click's pole.
void handle_mouse(ViewerState& state, const sample::Input& in);

// Headless scripting: reach for a world point, let go.
void reach_world(ViewerState& state, glm::vec3 world_target);
void release(ViewerState& state);
// The reaching bone's position in the world (the headless summary; the origin when none has reached).
glm::vec3 effector_position(const ViewerState& state);

}  // namespace viewer
