// The scene: nodes, floor, props and camera framing; drawing the character and its overlays.
#include "view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "deform/extras/builtin.hpp"
#include "deform/io/obj.hpp"
#include "model.hpp"
#include "model_loading.hpp"
#include "shapes.hpp"

namespace viewer {
namespace {

// The rotation that stands a model whose up direction is `up` (a unit basis vector) upright, +Y.
glm::quat upright(glm::vec3 up) {
  const glm::vec3 y(0.0f, 1.0f, 0.0f);
  if (glm::dot(up, y) > 0.5f) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  if (glm::dot(up, y) < -0.5f) return glm::angleAxis(glm::pi<float>(), glm::vec3(1.0f, 0.0f, 0.0f));
  return glm::angleAxis(glm::half_pi<float>(), glm::normalize(glm::cross(up, y)));
}

glm::vec3 heat(float t) {  // 0 blue, 0.5 green, 1 red
  t = std::clamp(t, 0.0f, 1.0f);
  return t < 0.5f ? glm::mix(glm::vec3(0.2f, 0.4f, 1.0f), glm::vec3(0.2f, 1.0f, 0.3f), 2.0f * t)
                  : glm::mix(glm::vec3(0.2f, 1.0f, 0.3f), glm::vec3(1.0f, 0.2f, 0.1f), 2.0f * t - 1.0f);
}

void upload_static(sample::MeshRenderer& r, const deform::Mesh& m) {
  std::vector<glm::vec3> positions(m.vertex_count());
  for (std::size_t v = 0; v < m.vertex_count(); ++v) positions[v] = m.positions[m.vertex_point[v]];
  r.upload(positions, m.vertex_normals);
}

// The box the camera frames (upright model space): the playing clip's sampled poses (with a second clip blended
// in, both clips'), else the bind pose.
deform::Bounds framed_bounds(const ViewerState& state) {
  if (state.clip < 0) return state.rest_bounds;
  deform::Bounds box = state.clip_bounds[std::size_t(state.clip)];
  if (state.blend_clip >= 0 && state.blend_weight > 0.0f) {
    box.min = glm::min(box.min, state.clip_bounds[std::size_t(state.blend_clip)].min);
    box.max = glm::max(box.max, state.clip_bounds[std::size_t(state.blend_clip)].max);
  }
  return box;
}

// The side the fitted camera looks from (its yaw): across the character's broad side, a little to its right. A
// box longer than tall (a four-legged character, a bind pose lying down) is seen across its length. A standing
// figure is seen across its bind pose's broader horizontal axis, its shoulders (or arms) broader than it is deep
// whether it faces +Z as glTF's do or +X as IQM's do; the clip's box would mislead here, as a walk's stride is
// deeper than its shoulders are broad. A bind pose lying down (CesiumMan's) that its clip stands up lies along the
// axis that stands up: across the other one.
float fitted_yaw(const ViewerState& state, const deform::Bounds& framed) {
  const glm::vec3 f = framed.max - framed.min, b = state.rest_bounds.max - state.rest_bounds.min;
  const float across_x = 0.35f, across_z = glm::half_pi<float>() - 0.35f;  // from +Z (a little +X), from +X
  if (f.y < std::max(f.x, f.z)) return f.x >= f.z ? across_x : across_z;
  if (b.y >= 0.5f * std::max(b.x, b.z)) return b.x >= b.z ? across_x : across_z;
  return b.x >= b.z ? across_z : across_x;
}

// The lattices to draw this frame (state.lattice_shown): all, none, or the active limb's: the lattices on the effector
// and on the bones above it up to the first bone without one (hand, forearm and upper arm, not the spine's). The
// active limb is the one reaching, else the one a click at the mouse would move, else the one that reached last.
// No allocation.
void mark_shown_lattices(ViewerState& state) {
  const deform::DeformerHierarchy& deformers = state.character->deformers();
  const bool all = state.lattice_display == LatticeDisplay::all;
  std::fill(state.lattice_shown.begin(), state.lattice_shown.end(), char(all));
  if (state.lattice_display != LatticeDisplay::active) return;
  const std::int32_t limb = state.reaching                ? state.effector
                            : state.hovered_effector >= 0 ? state.hovered_effector
                                                          : state.effector;
  bool found = false;
  for (std::int32_t b = limb; b >= 0; b = state.character->skeleton().bone(b).parent) {
    bool here = false;
    for (std::size_t l = 0; l < deformers.lattice_count(); ++l)
      if (deformers.spec(l).bone == b) state.lattice_shown[l] = 1, here = true;
    if (found && !here) break;
    found |= here;
  }
}

// The swing cones of the reach chain's joints (Character::reach_swing_twist): from each joint's head, lines to the
// cone's rim — the directions its bone may point in — turned by its parent's current rotation (the pose's; what the
// lattices carry is left out).
void draw_swing_twist_cones(ViewerState& state, const glm::mat4& to_world) {
  const std::span<const std::int32_t> chain = state.character->reach_chain();
  if (chain.empty() || state.character->reach_swing_twist(0) == nullptr) return;
  const deform::Skeleton& sk = state.character->skeleton();
  const deform::Pose& pose = state.character->pose();
  state.world_rotations.resize(sk.bone_count());
  for (const std::int32_t b : sk.order()) {
    const std::int32_t parent = sk.bone(b).parent;
    state.world_rotations[std::size_t(b)] =
        (parent >= 0 ? state.world_rotations[std::size_t(parent)] : glm::quat(1, 0, 0, 0)) *
        pose.rotations[std::size_t(b)];
  }
  const glm::vec3 cyan(0.2f, 0.9f, 1.0f);
  for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
    const deform::SwingTwistLimits* limits = state.character->reach_swing_twist(k);
    if (limits == nullptr) continue;
    const std::int32_t parent = sk.bone(chain[k]).parent;
    const glm::quat frame = parent >= 0 ? state.world_rotations[std::size_t(parent)] : glm::quat(1, 0, 0, 0);
    const glm::vec3 head = state.character->bone_position(chain[k]);
    const float length = 0.6f * glm::length(sk.bone(chain[k + 1]).bind_translation);
    const glm::vec3 side = glm::cross(limits->axis, limits->reference);
    glm::vec3 previous(0.0f);
    constexpr int steps = 24;
    for (int i = 0; i <= steps; ++i) {
      const float phi = glm::two_pi<float>() * float(i) / float(steps);
      const glm::vec3 swing =
          limits->swing1 * std::cos(phi) * limits->reference + limits->swing2 * std::sin(phi) * side;
      const float angle = glm::length(swing);
      const glm::quat turn = angle > 1e-6f ? glm::angleAxis(angle, swing / angle) : glm::quat(1, 0, 0, 0);
      const glm::vec3 rim = transform_point(to_world, head + frame * (turn * limits->axis) * length);
      if (i > 0) state.overlay.line(previous, rim, cyan);
      if (i % 6 == 0) state.overlay.line(transform_point(to_world, head), rim, cyan);
      previous = rim;
    }
  }
}

// The character's vertices this frame: deformed on the GPU into the renderer's vertex buffer, or uploaded from the
// CPU's points and `normals` (empty: the character's).
void update_character_vertices(ViewerState& state, std::span<const glm::vec3> normals) {
  const deform::Mesh& mesh = state.character->model().mesh;
  if (state.gpu) {
    // Only the palette and the lattices' control points travel; the vertices never leave the GPU.
    const GLuint vertex_buffer = state.renderer->vertex_buffer();
    deform::Status status =
        state.gpu_skinning.skin_into(state.character->settings.skinning, state.character->palette(), vertex_buffer);
    if (status) status = state.gpu_fields.apply_into(state.character->deformers(), vertex_buffer);
    if (!status) {
      std::fprintf(stderr, "deform_viewer: GPU deformation refused: %s; deforming on the CPU\n", status.reason());
      set_gpu(state, false);
    }
  }
  if (!state.gpu) {
    state.render_positions.resize(mesh.vertex_count());
    const auto points = state.character->positions();
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) state.render_positions[v] = points[mesh.vertex_point[v]];
    state.renderer->upload(state.render_positions, normals.empty() ? state.character->normals() : normals);
  }
}

// The lattices lattice_shown marks: control points and edges, coloured by how far each point moved along the bone.
void draw_lattices(ViewerState& state, const glm::mat4& to_world) {
  for (std::size_t l = 0; l < state.character->deformers().lattice_count(); ++l) {
    if (!state.lattice_shown[l]) continue;
    const auto cps = state.character->control_points(l);
    const glm::ivec3 n = state.character->deformers().spec(l).degree + 1;
    const float stretch =
        state.character->deformers().stretch(l) / std::max(1e-6f, state.character->deformers().length(l));
    auto at = [&](int i, int j, int k) { return transform_point(to_world, cps[std::size_t(i + n.x * (j + n.y * k))]); };
    for (int k = 0; k < n.z; ++k)
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i) {
          // Control point i of a stretched lattice moves by stretch · i/l along the bone: colour by that.
          const glm::vec3 c = heat(0.5f + 0.5f * stretch * float(i) / float(std::max(1, n.x - 1)) * 2.0f);
          state.overlay.point(at(i, j, k), c, 6.0f);
          if (i + 1 < n.x) state.overlay.line(at(i, j, k), at(i + 1, j, k), c);
          if (j + 1 < n.y) state.overlay.line(at(i, j, k), at(i, j + 1, k), c);
          if (k + 1 < n.z) state.overlay.line(at(i, j, k), at(i, j, k + 1), c);
        }
  }
}

// The weight-paint ramp riggers know: 0 blue, 0.25 cyan, 0.5 green, 0.75 yellow, 1 red.
glm::vec3 weight_colour(float w) {
  static const glm::vec3 ramp[] = {
      {0.0f, 0.0f, 1.0f}, {0.0f, 1.0f, 1.0f}, {0.0f, 1.0f, 0.0f}, {1.0f, 1.0f, 0.0f}, {1.0f, 0.0f, 0.0f}};
  const float at = std::clamp(w, 0.0f, 1.0f) * 4.0f;
  const int i = std::min(3, int(at));
  return glm::mix(ramp[i], ramp[i + 1], at - float(i));
}

// The weight map: the character's surface painted with weight_bone's weight at each point (all its influences, the
// extras past the fourth included), interpolated across the triangles, and shaded by a light near the eye
// (two-sided: a model wound inwards reads the same), in place of its textured surface. `normals`: the render vertices'
// (with the GPU deformation, those read back from its vertex buffer with the points; each triangle's own, flat, when
// they are missing). Per frame O(points × influences + triangles), into storage kept from frame to frame.
void draw_weight_map(ViewerState& state, const glm::mat4& to_world, const glm::mat4& view, glm::vec3 eye,
                     std::span<const glm::vec3> normals) {
  const auto points = drawn_points(state);
  if (state.gpu) normals = state.gpu_normals;  // read back with the points
  const deform::SkinWeights& w = state.character->model().weights;
  const deform::Mesh& mesh = state.character->model().mesh;
  const auto bone = std::uint16_t(state.weight_bone);
  state.weight_values.assign(points.size(), 0.0f);
  for (std::size_t i = 0; i < points.size() && i < w.size(); ++i)
    for (int k = 0; k < deform::max_influences; ++k)
      if (w.bones[i][k] == bone) state.weight_values[i] += w.weights[i][k];
  for (std::size_t e = 0; e < w.extra_points.size(); ++e)
    for (std::uint32_t j = w.extra_offsets[e]; j < w.extra_offsets[e + 1]; ++j)
      if (w.extra_bones[j] == bone && w.extra_points[e] < points.size())
        state.weight_values[w.extra_points[e]] += w.extra_weights[j];
  const glm::mat3 turn(to_world);
  // A light above and to the right of the eye, so that the shape reads on a surface of flat colours.
  const glm::mat4 camera = glm::inverse(view);
  const glm::vec3 light_offset = 1.2f * glm::vec3(camera[1]) + 0.8f * glm::vec3(camera[0]);
  const bool smooth = normals.size() == mesh.vertex_count();
  const std::vector<std::uint32_t>& triangles = drawn_triangles(state);
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    glm::vec3 corner[3], colour[3];
    for (int c = 0; c < 3; ++c) corner[c] = transform_point(to_world, points[mesh.vertex_point[triangles[t + c]]]);
    const glm::vec3 face = glm::cross(corner[1] - corner[0], corner[2] - corner[0]);
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t r = triangles[t + c];
      glm::vec3 n = smooth ? turn * normals[r] : face;
      const glm::vec3 to_eye = glm::normalize(eye - corner[c]);
      if (glm::dot(n, to_eye) < 0.0f) n = -n;  // two-sided: the side the eye sees
      const float length = glm::length(n);
      const glm::vec3 light = glm::normalize(to_eye + light_offset);
      const float lit = length > 0.0f ? std::max(0.0f, glm::dot(n, light)) / length : 1.0f;
      colour[c] = weight_colour(state.weight_values[mesh.vertex_point[r]]) * (0.15f + 0.85f * lit);
    }
    state.overlay.triangle(corner[0], corner[1], corner[2], colour[0], colour[1], colour[2]);
  }
}

// The skeleton's bones from each head to its parent's, the reaching bone's head in red.
void draw_skeleton(ViewerState& state, const glm::mat4& to_world) {
  const deform::Skeleton& sk = state.character->skeleton();
  for (std::size_t b = 0; b < sk.bone_count(); ++b) {
    const glm::vec3 head = transform_point(to_world, state.character->bone_position(std::int32_t(b)));
    const std::int32_t parent = sk.bone(std::int32_t(b)).parent;
    if (parent >= 0)
      state.overlay.line(transform_point(to_world, state.character->bone_position(parent)), head,
                         glm::vec3(1.0f, 0.9f, 0.3f));
    state.overlay.point(head, std::int32_t(b) == state.effector ? glm::vec3(1, 0.3f, 0.2f) : glm::vec3(1, 1, 1), 7.0f);
  }
}

// The spring chains as simulated, in green: first head, then each bone's tail.
void draw_springs(ViewerState& state, const glm::mat4& to_world) {
  const deform::SpringChains& springs = state.character->springs();
  const glm::vec3 green(0.3f, 1.0f, 0.4f);
  for (std::size_t c = 0; c < springs.chain_count(); ++c) {
    const auto chain = springs.points(c);
    for (std::size_t i = 0; i < chain.size(); ++i) {
      const glm::vec3 p = transform_point(to_world, chain[i]);
      if (i > 0) state.overlay.line(transform_point(to_world, chain[i - 1]), p, green);
      state.overlay.point(p, green, 6.0f);
    }
  }
}

// The reach's target, the swing-twist cones (with the skeleton) and the pole gizmo.
void draw_reach_gizmos(ViewerState& state, const glm::mat4& to_world) {
  if (state.reaching) state.overlay.point(transform_point(to_world, state.target), glm::vec3(1.0f, 0.5f, 0.0f), 12.0f);
  if (state.show_skeleton && !state.options.bare) draw_swing_twist_cones(state, to_world);
  // The pole gizmo: a point, and a line to the chain's middle while reaching.
  if (state.use_pole && !state.options.bare) {
    const glm::vec3 pole = transform_point(to_world, state.pole);
    state.overlay.point(pole, glm::vec3(0.9f, 0.2f, 0.9f), 11.0f);
    if (state.reaching) {
      const deform::Skeleton& sk = state.character->skeleton();
      const std::int32_t middle = sk.bone(state.effector).parent;
      if (middle >= 0)
        state.overlay.line(transform_point(to_world, state.character->bone_position(middle)), pole,
                           glm::vec3(0.9f, 0.2f, 0.9f));
    }
  }
}

}  // namespace

void build_scene(ViewerState& state) {
  // The scene (the thesis' version 1): the world holds the floor, the character and the props. The character node
  // (moved and turned from the panel) holds the model node, which stands the model upright (its up axis onto +Y)
  // and is the model's own space; the target ball is its child, so moving the character carries its target along.
  state.world_node = state.scene.add("world");
  state.floor_node = state.scene.add("floor", state.world_node);
  state.character_node = state.scene.add("character", state.world_node);
  state.model_node = state.scene.add("model", state.character_node);
  state.scene.node(state.model_node).rotation = upright(state.up);
  state.ball_node = state.scene.add("target", state.model_node, glm::vec3(0.0f), glm::vec3(1.0f));
  std::vector<glm::vec3> standing(state.base_model.mesh.positions);  // framing, floor and props see the upright model
  for (glm::vec3& p : standing) p = state.scene.node(state.model_node).rotation * p;
  const deform::Bounds b = deform::compute_bounds(standing);
  const float height = std::max(1e-3f, b.max.y - b.min.y);
  const float extent = std::max({b.max.x - b.min.x, height, b.max.z - b.min.z});
  state.scene.node(state.floor_node).translation =
      glm::vec3(0.5f * (b.min.x + b.max.x), b.min.y, 0.5f * (b.min.z + b.max.z));
  // What each clip shows, sampled once here: the box around its skinned poses (upright), which the camera frames,
  // and the lowest any point reaches, where the floor goes, not the bind pose's lowest point: an imported file's
  // bind pose can stand elsewhere than its animated stance (mrfixit.iqm's idle crouches below its bind pose's
  // feet; a glTF character can lie on its back until its clip stands it up), and the character must stand on the
  // floor, never sink into it, and stay in frame.
  state.rest_bounds = b;
  state.floor_height = 0.01f * height;
  for (const deform::Animation& clip : state.clips) {
    state.clip_bounds.push_back(
        model_loading::posed_bounds(state.base_model, clip, state.scene.node(state.model_node).rotation));
    state.clip_floors.push_back(state.clip_bounds.back().min.y);
  }
  state.floor_mesh = sample::make_floor(extent * 4.0f, 16);
  state.ball_mesh = sample::make_sphere(extent * 0.025f, 12, 24, glm::vec3(1.0f, 0.55f, 0.1f));
  for (const std::string& path : state.options.props) {
    state.props.push_back(std::make_unique<deform::Mesh>(deform::read_obj(path)));
    state.prop_nodes.push_back(
        state.scene.add(path, state.world_node, glm::vec3(extent * 0.6f * float(state.props.size()), b.min.y, 0.0f)));
  }
  place_floor(state);  // --clip and --blend chose clips before the floor existed
  state.scene.update();
  fit_camera(state);
  state.pick_radius = extent;

  state.floor_renderer.create(state.floor_mesh);
  upload_static(state.floor_renderer, state.floor_mesh);
  state.ball_renderer.create(state.ball_mesh);
  upload_static(state.ball_renderer, state.ball_mesh);
  for (auto& prop : state.props) {
    state.prop_renderers.push_back(std::make_unique<sample::MeshRenderer>());
    state.prop_renderers.back()->create(*prop);
    upload_static(*state.prop_renderers.back(), *prop);
  }
  state.overlay.create();
  state.scene.update();
}

void create_character_renderer(ViewerState& state) {
  const deform::Mesh& mesh = state.character->model().mesh;
  state.renderer = std::make_unique<sample::MeshRenderer>();
  state.renderer->create(mesh);
  // The in-memory built-in character names builtin.png without a folder: draw its texture from memory.
  if (state.options.model.empty() && !mesh.materials.empty()) {
    const int size = 512;
    const std::vector<std::uint8_t> pixels = deform::builtin_texture(size);
    state.renderer->set_texture_rgb(0, size, size, pixels.data());
  }
}

// The floor under what plays: the bind pose's lowest point with no clip, else the clip's floor, the lower of the
// two clips' floors while a second one is blended in (a blend of two poses stays close to their range). Cheap:
// called on every frame, as the panel can change the clips at any time. Before the scene exists it does nothing.
void place_floor(ViewerState& state) {
  if (state.floor_node < 0) return;
  float floor = state.clip < 0 ? state.rest_bounds.min.y : state.clip_floors[std::size_t(state.clip)];
  if (state.clip >= 0 && state.blend_clip >= 0 && state.blend_weight > 0.0f)
    floor = std::min(floor, state.clip_floors[std::size_t(state.blend_clip)]);
  state.scene.node(state.floor_node).translation.y = floor;
  state.camera.floor = floor + state.floor_height;
}

// The camera that frames what plays (framed_bounds, where the character node puts it) from a little above, on the
// side fitted_yaw chooses: every corner of the box within `fill` of the view's height and width, the box centred
// on the screen (right of the panel). Corners nearer the eye look bigger, so the distance is the largest any corner
// needs (|offset across the view| / (tan(fov/2) · fill) in front of it) and the centre is found in a few passes.
// `C` comes back here; choosing another clip in the panel refits while the camera has not been moved.
void fit_camera(ViewerState& state) {
  const deform::Bounds local = framed_bounds(state);
  const glm::mat4 to_world = state.scene.node(state.character_node).world;
  glm::vec3 corners[8];
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c((i & 1 ? local.max : local.min).x, (i & 2 ? local.max : local.min).y,
                      (i & 4 ? local.max : local.min).z);
    corners[i] = transform_point(to_world, c);
  }
  sample::OrbitCamera camera = state.camera;  // its field of view and floor
  camera.yaw = fitted_yaw(state, local);
  camera.pitch = 0.12f;
  const glm::vec3 back(std::cos(camera.pitch) * std::sin(camera.yaw), std::sin(camera.pitch),
                       std::cos(camera.pitch) * std::cos(camera.yaw));  // target to eye
  const glm::vec3 right = glm::normalize(glm::cross(-back, glm::vec3(0.0f, 1.0f, 0.0f)));
  const glm::vec3 up = glm::cross(right, -back);
  constexpr float fill = 0.8f;
  // The panel over the left of the window (`hidden`, a share of its width): the box is made to fit the rest and
  // is drawn right of the panel (a lens shift), centred in the window when it is clear of the panel there.
  const float width = float(std::max(1, state.window.framebuffer_size().x));
  const float hidden = state.options.bare ? 0.0f : std::min(state.panel_right, 0.5f * width) / width;
  const float tan_y = std::tan(0.5f * camera.fov_y), tan_x = tan_y * state.window.aspect() * (1.0f - hidden);
  glm::vec3 centre = 0.5f * (corners[0] + corners[7]);
  float distance = 1e-3f;
  for (int pass = 0; pass < 4; ++pass) {
    distance = 1e-3f;
    for (const glm::vec3& c : corners) {
      const glm::vec3 o = c - centre;
      const float toward = glm::dot(o, back);
      distance = std::max({distance, toward + std::abs(glm::dot(o, up)) / (tan_y * fill),
                           toward + std::abs(glm::dot(o, right)) / (tan_x * fill)});
    }
    // The corners' extent on the screen (tangents from the eye), and the centre moved to its middle.
    glm::vec2 low(std::numeric_limits<float>::infinity()), high(-std::numeric_limits<float>::infinity());
    for (const glm::vec3& c : corners) {
      const glm::vec3 o = c - centre;
      const glm::vec2 seen = glm::vec2(glm::dot(o, right), glm::dot(o, up)) / (distance - glm::dot(o, back));
      low = glm::min(low, seen), high = glm::max(high, seen);
    }
    centre += (0.5f * (low.x + high.x) * right + 0.5f * (low.y + high.y) * up) * distance;
  }
  // The box's half width on the screen (NDC), then the shift that puts its left side a little right of the panel's
  // edge (NDC -1 + 2 · hidden), when centred it would be under the panel. It still ends within the window's right
  // edge: the box is at most `fill` of the free width.
  float half_width = 0.0f;
  for (const glm::vec3& c : corners) {
    const glm::vec3 o = c - centre;
    half_width = std::max(half_width, std::abs(glm::dot(o, right)) / (distance - glm::dot(o, back)));
  }
  half_width /= tan_y * state.window.aspect();
  camera.shift_x = hidden > 0.0f ? std::max(0.0f, -1.0f + 2.0f * hidden + 0.1f * (1.0f - hidden) + half_width) : 0.0f;
  camera.target = centre;
  camera.distance = distance * state.options.zoom;
  state.camera = state.fitted_camera = camera;
}

bool camera_fitted(const ViewerState& state) {
  return state.camera.target == state.fitted_camera.target && state.camera.distance == state.fitted_camera.distance &&
         state.camera.shift_x == state.fitted_camera.shift_x && state.camera.yaw == state.fitted_camera.yaw &&
         state.camera.pitch == state.fitted_camera.pitch;
}

// The model's space in the world (the character node, then the upright turn).
glm::mat4 character_world(const ViewerState& state) { return state.scene.node(state.model_node).world; }

const std::vector<std::uint32_t>& drawn_triangles(const ViewerState& state) {
  const std::size_t level = std::size_t(state.lod_drawn);
  if (level < state.lod_triangles.size() && !state.lod_triangles[level].empty()) return state.lod_triangles[level];
  return state.character->model().mesh.triangles;
}

// The deformed points as drawn: the character's, or with the GPU deformation, read back from the vertex buffer
// (for picking and the weight map only: a GPU-to-CPU copy, not done for drawing).
std::span<const glm::vec3> drawn_points(ViewerState& state) {
  if (!state.gpu) return state.character->positions();
  const deform::Mesh& mesh = state.character->model().mesh;
  constexpr deform::GpuVertexLayout layout{};
  std::vector<float> data(mesh.vertex_count() * std::size_t(layout.floats_per_vertex));
  glBindBuffer(GL_ARRAY_BUFFER, state.renderer->vertex_buffer());
  glGetBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(data.size() * sizeof(float)), data.data());
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  state.gpu_points.resize(mesh.point_count());
  state.gpu_normals.resize(mesh.vertex_count());
  for (std::size_t r = 0; r < mesh.vertex_count(); ++r) {
    const float* p = data.data() + r * std::size_t(layout.floats_per_vertex) + layout.position_offset;
    state.gpu_points[mesh.vertex_point[r]] = glm::vec3(p[0], p[1], p[2]);
    const float* n = data.data() + r * std::size_t(layout.floats_per_vertex) + layout.normal_offset;
    state.gpu_normals[r] = glm::vec3(n[0], n[1], n[2]);
  }
  return state.gpu_points;
}

void draw(ViewerState& state, std::span<const glm::vec3> normals) {
  state.scene.node(state.ball_node).translation = state.target;
  state.scene.update();
  const glm::mat4 view = state.camera.view(), projection = state.camera.projection(state.window.aspect());
  const glm::vec3 eye = state.camera.eye();
  if (!state.options.bare) {
    state.floor_renderer.draw(state.scene.node(state.floor_node).world, view, projection, eye);
    for (std::size_t i = 0; i < state.props.size(); ++i)
      state.prop_renderers[i]->draw(state.scene.node(state.prop_nodes[i]).world, view, projection, eye);
  }

  update_character_vertices(state, normals);
  const bool weight_map =
      state.weight_bone >= 0 && std::size_t(state.weight_bone) < state.character->skeleton().bone_count();
  if (weight_map) {  // the surface painted with one bone's weights, instead of its texture (also when --bare)
    draw_weight_map(state, character_world(state), view, eye, normals);
    state.overlay.flush(projection * view, false);
  } else {
    state.renderer->draw(character_world(state), view, projection, eye);
  }
  if (state.options.bare) return;
  if (state.reaching) state.ball_renderer.draw(state.scene.node(state.ball_node).world, view, projection, eye);

  const glm::mat4 to_world = character_world(state);
  mark_shown_lattices(state);
  if (state.lattice_display != LatticeDisplay::none) {
    draw_lattices(state, to_world);
    state.overlay.flush(projection * view, false);
  }
  if (state.show_skeleton) draw_skeleton(state, to_world);
  if (state.show_skeleton) draw_springs(state, to_world);
  draw_reach_gizmos(state, to_world);
  state.overlay.flush(projection * view, true);
}

// The floor's height, and the lowest height of the character as drawn now (both along the upright +Y).
float floor_y(const ViewerState& state) { return state.scene.node(state.floor_node).translation.y; }

float lowest_y(const ViewerState& state) {
  float lowest = std::numeric_limits<float>::infinity();
  for (const glm::vec3& p : state.character->positions()) lowest = std::min(lowest, glm::dot(p, state.up));
  return lowest;
}

// The lattices drawn in the last frame (the overlay; 0 with --bare).
int lattices_shown(const ViewerState& state) {
  return state.options.bare || state.lattice_display == LatticeDisplay::none
             ? 0
             : int(std::count(state.lattice_shown.begin(), state.lattice_shown.end(), char(1)));
}

// The image row (from the top) of the floor under the point drawn lowest on the screen, through the camera: the
// row of the silhouette's lowest pixels when the character stands on the floor, below it when the character
// floats, above it when it sinks (headless pixel tests). Projects every point: for the headless summary only.
float floor_row(const ViewerState& state) {
  const glm::ivec2 size = state.window.framebuffer_size();
  const glm::mat4 view = state.camera.view(), projection = state.camera.projection(state.window.aspect());
  const glm::vec4 viewport(0.0f, 0.0f, float(size.x), float(size.y));
  glm::vec3 lowest(0.0f);
  float lowest_window_y = std::numeric_limits<float>::infinity();
  for (const glm::vec3& p : state.character->positions()) {
    const glm::vec3 world = transform_point(character_world(state), p);
    const float window_y = glm::project(world, view, projection, viewport).y;
    if (window_y < lowest_window_y) lowest_window_y = window_y, lowest = world;
  }
  lowest.y = floor_y(state);
  return float(size.y) - glm::project(lowest, view, projection, viewport).y;
}

}  // namespace viewer
