// The mouse and the keys: picking, reaching, the pole, the keys' toggles.
#include "input.hpp"

#include <algorithm>
#include <cctype>
#include <limits>
#include <optional>
#include <string>

#include <GLFW/glfw3.h>

#include "model.hpp"
#include "view.hpp"

namespace viewer {
namespace {

// The nearest scene point under the mouse: the character's current triangles (through the BVH) or the floor.
std::optional<glm::vec3> pick(ViewerState& state, glm::vec2 pixel) {
  const glm::ivec2 size = state.window.framebuffer_size();
  const deform::Ray ray = deform::ray_from_pixel(state.camera.view(), state.camera.projection(state.window.aspect()),
                                                 pixel, glm::vec4(0, 0, size.x, size.y));
  std::optional<glm::vec3> best;
  float best_distance = std::numeric_limits<float>::infinity();
  // The character's triangles live in its node's frame: carry the ray there.
  const glm::mat4 to_local = glm::inverse(character_world(state));
  deform::Ray local{transform_point(to_local, ray.origin), glm::vec3(to_local * glm::vec4(ray.direction, 0.0f))};
  state.bvh.refit(drawn_points(state));
  const deform::RayHit hit = state.bvh.intersect(local);
  if (hit.hit) {
    const glm::vec3 p = transform_point(character_world(state), local.origin + hit.distance * local.direction);
    best_distance = glm::length(p - ray.origin);
    best = p;
  }
  const float floor_y = state.scene.node(state.floor_node).world[3].y;
  if (std::abs(ray.direction.y) > 1e-6f) {
    const float t = (floor_y - ray.origin.y) / ray.direction.y;
    if (t > 0.0f && t < best_distance) best = ray.origin + t * ray.direction;
  }
  return best;
}

void begin_reach(ViewerState& state, glm::vec3 world_target) {
  const glm::vec3 local = transform_point(glm::inverse(character_world(state)), world_target);
  // The nearest limb whose lattices stretch reaches (the rig's reach effector among them); without lattices, the
  // nearest hand.
  std::int32_t best = deform::nearest_reach_effector(*state.character, local);
  if (best < 0) {
    float best_distance = std::numeric_limits<float>::infinity();
    const deform::Skeleton& sk = state.character->skeleton();
    for (std::size_t b = 0; b < sk.bone_count(); ++b) {
      std::string name = sk.bone(std::int32_t(b)).name;
      std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
      if (name.find("hand") == std::string::npos) continue;
      const float d = glm::length(state.character->bone_position(std::int32_t(b)) - local);
      if (d < best_distance) best_distance = d, best = std::int32_t(b);
    }
  }
  if (best < 0) return;
  state.effector = best;
  state.target = local;
  state.last_reach = state.character->reach(state.effector, state.target);
  if (!state.last_reach.status.ok() && state.character->rig().reach_effector >= 0) {
    state.effector = state.character->rig().reach_effector;
    state.last_reach = state.character->reach(state.effector, state.target);
  }
  state.reaching = state.last_reach.status.ok();
}

}  // namespace

void handle_keys(ViewerState& state, int key) {
  if (key == GLFW_KEY_D) {  // LBS, DQS, DDM, LBS again
    if (state.ddm) {
      state.ddm = false;
      state.character->settings.skinning = deform::SkinningMethod::lbs;
    } else if (state.character->settings.skinning == deform::SkinningMethod::dqs) {
      state.ddm = true;
    } else {
      state.character->settings.skinning = deform::SkinningMethod::dqs;
    }
    apply_mush(state);
  }
  if (key == GLFW_KEY_S) state.show_skeleton = !state.show_skeleton;
  if (key == GLFW_KEY_L)  // active limb, all, none, active again
    state.lattice_display = state.lattice_display == LatticeDisplay::active ? LatticeDisplay::all
                            : state.lattice_display == LatticeDisplay::all  ? LatticeDisplay::none
                                                                            : LatticeDisplay::active;
  if (key == GLFW_KEY_R) rebuild_character(state);
  if (key == GLFW_KEY_G) set_gpu(state, !state.gpu);
  if (key == GLFW_KEY_C) fit_camera(state);
}

void handle_mouse(ViewerState& state, const sample::Input& in) {
  // The limb a click would move, under a mouse that moves freely over the scene: its lattices are the active ones.
  // Not in headless runs, whose pictures must not depend on where the display's cursor happens to be.
  if (state.options.screenshot.empty() && state.lattice_display == LatticeDisplay::active &&
      in.mouse_delta != glm::vec2(0.0f) && !in.left_down && !in.right_down && !in.middle_down) {
    const auto p = pick(state, in.mouse);
    state.hovered_effector =
        p ? deform::nearest_reach_effector(*state.character, transform_point(glm::inverse(character_world(state)), *p))
          : -1;
  }
  if (in.left_pressed && in.shift) {  // the pole: the point clicked, in the model's space
    if (const auto p = pick(state, in.mouse)) {
      state.pole = transform_point(glm::inverse(character_world(state)), *p);
      state.use_pole = true;
      apply_reach_settings(state);
    }
  } else if (in.left_pressed) {
    if (const auto p = pick(state, in.mouse)) {
      begin_reach(state, *p);
      state.drag_depth = glm::dot(*p - state.camera.eye(), glm::normalize(state.camera.target - state.camera.eye()));
    }
  } else if (in.left_down && state.reaching && in.mouse_delta != glm::vec2(0.0f)) {
    // Drag: the target slides on the plane facing the camera at the depth first clicked.
    const glm::ivec2 size = state.window.framebuffer_size();
    const deform::Ray ray = deform::ray_from_pixel(state.camera.view(), state.camera.projection(state.window.aspect()),
                                                   in.mouse, glm::vec4(0, 0, size.x, size.y));
    const glm::vec3 forward = glm::normalize(state.camera.target - state.camera.eye());
    const float along = glm::dot(ray.direction, forward);
    if (along > 1e-4f) {
      state.target = transform_point(
          glm::inverse(character_world(state)),
          ray.origin + ray.direction * (state.drag_depth - glm::dot(ray.origin - state.camera.eye(), forward)) / along);
      state.last_reach = state.character->reach(state.effector, state.target);
    }
  } else if (in.left_released) {
    release(state);
  }
}

void reach_world(ViewerState& state, glm::vec3 world_target) { begin_reach(state, world_target); }

void release(ViewerState& state) {
  if (state.reaching) state.character->release();
  state.reaching = false;
}

glm::vec3 effector_position(const ViewerState& state) {
  return state.effector >= 0 ? transform_point(character_world(state), state.character->bone_position(state.effector))
                             : glm::vec3(0.0f);
}

}  // namespace viewer
