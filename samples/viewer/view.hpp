#pragma once
// The scene (view.cpp): its nodes (world, floor, character, the upright model, the target ball, props), the floor
// under what plays, the camera fitted to it, and the drawing of the character, its lattices, weight map, skeleton,
// spring chains and reach gizmos. (Not scene.hpp: that is the framework's scene graph.)
#include <span>

#include "state.hpp"

namespace viewer {

inline glm::vec3 transform_point(const glm::mat4& m, glm::vec3 p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

// The scene's nodes, floor, props and their renderers, the overlay and the fitted camera, around the loaded model.
void build_scene(ViewerState& state);
// The renderer of the character's mesh (again after each rebuild), with the built-in character's texture.
void create_character_renderer(ViewerState& state);

// The floor under what plays: the bind pose's lowest point with no clip, else the clip's floor, the lower of the
// two clips' floors while a second one is blended in (a blend of two poses stays close to their range). Cheap:
// called on every frame, as the panel can change the clips at any time. Before the scene exists it does nothing.
void place_floor(ViewerState& state);
// The camera that frames what plays (framed_bounds, where the character node puts it) from a little above, on the
// side fitted_yaw chooses: every corner of the box within `fill` of the view's height and width, the box centred
// on the screen (right of the panel). Corners nearer the eye look bigger, so the distance is the largest any corner
// needs (|offset across the view| / (tan(fov/2) · fill) in front of it) and the centre is found in a few passes.
// `C` comes back here; choosing another clip in the panel refits while the camera has not been moved.
void fit_camera(ViewerState& state);
// Whether the camera is where fit_camera put it (not moved since).
bool camera_fitted(const ViewerState& state);
// The model's space in the world (the character node, then the upright turn).
glm::mat4 character_world(const ViewerState& state);
// The character's triangles the renderer draws (render vertex ids): the level of detail's own (choose_lod), else the
// mesh's.
const std::vector<std::uint32_t>& drawn_triangles(const ViewerState& state);
// The deformed points as drawn: the character's, or with the GPU deformation, read back from the vertex buffer with
// the render vertices' normals (state.gpu_normals) (for picking and the weight map only: a GPU-to-CPU copy, not done
// for drawing).
std::span<const glm::vec3> drawn_points(ViewerState& state);
// The frame: the floor and props, the character deformed (on the CPU with `normals`, else on the GPU; painted with
// one bone's weights instead of its texture while the weight map shows one, --bare included), the overlays.
void draw(ViewerState& state, std::span<const glm::vec3> normals);

// The headless summary: the floor's height, and the lowest height of the character as drawn now (both along the
// upright +Y); the lattices drawn in the last frame; the image row of the floor under the lowest point drawn.
float floor_y(const ViewerState& state);
float lowest_y(const ViewerState& state);
int lattices_shown(const ViewerState& state);
float floor_row(const ViewerState& state);

}  // namespace viewer
