#pragma once
// The model and its character (model.cpp): loading the model the options name, its clips and rig, building the
// deform::Character, and every change of its settings the panel, the keys or the options make. Also the clips'
// playback (the pose sampled each frame, blended with a second clip) and the morph weights.
#include <string>

#include "state.hpp"

namespace viewer {

// The model the options name, its clips and its rig; the options' starting choices (pole, limits, lattices shown,
// weight map, clip, blend, held morph weights) and the character built from them. Fails (exits) on a model, bone,
// clip or morph target the options name but the files do not have.
void load_character(ViewerState& state);
// The options' skinning, Delta Mush and GPU deformation, once the scene and its renderer exist.
void start_deformation(ViewerState& state);

// A new Character from the model and the rig as the panel tunes it (degree, elastic settings), at rest.
void rebuild_character(ViewerState& state);
// The character bound again with `weights` (one entry per point) in place of its model's: the same rig (lattices
// and spring chains as the panel tunes them), the panel's settings (skinning method, IK, mush, GPU), the clip and its
// time and the morph holds kept; a reach in progress ends. Throws deform::Error, changing nothing, when the rig does
// not bind with them.
void rebind_weights(ViewerState& state, deform::SkinWeights weights);
// Plays clip `clip` (-1: none, the bind pose) from its start.
void select_clip(ViewerState& state, int clip);
// This frame's pose of the playing clip (none: nothing), `dt` seconds on, and the held reach solved again on it.
void animate(ViewerState& state, float dt);
// The morph weights of this frame: the defaults, the playing clips' morph channels, then the panel's held weights.
void apply_morph_weights(ViewerState& state);

// The level of detail for this frame (--lod, the panel): the one asked for, or the one the character's height on
// screen picks; when it changes, the renderer and the picking take its triangles. Nothing without levels.
void choose_lod(ViewerState& state);

// The panel's settings passed to the character (each after its control changes).
void set_gpu(ViewerState& state, bool on);
void apply_mush(ViewerState& state);
void apply_motion(ViewerState& state);
void apply_shape(ViewerState& state);
void apply_reach_settings(ViewerState& state);
void apply_elastic(ViewerState& state);

// Why the GPU deformation is not available (the panel's tooltip, --gpu's message).
std::string gpu_missing(const ViewerState& state);
// The morph weights as applied now, comma-separated (the headless summary).
std::string morph_weights_text(const ViewerState& state);

}  // namespace viewer
