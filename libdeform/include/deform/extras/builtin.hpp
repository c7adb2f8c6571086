#pragma once
// The built-in character: a rigged humanoid built by code, so every sample, test, benchmark and CLI command has a
// model without any file (docs/builtin-character.md). samples/data/builtin.{obj,mtl,png,sk,skw} hold the same
// character, written by tools/make_builtin, and a test keeps them equal to what this library builds.
//
// Conventions: metres, Y up, facing +Z, the character's left on +X, T-pose, 1.8 m tall. Every bone except the root
// points along its local +Y axis: its first child's head lies on its local +Y axis (the direction an elastic stretch
// pushes). The root (hips) has its local +Y pointing forward (+Z), so that both the spine and the legs hang off it
// with bind rotations of ±90° rather than 180° and every joint's DOF range is a plain [min, max] around its bind angle.
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "deform/character/character.hpp"
#include "deform/extras/export.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/model.hpp"

namespace deform {

// The character: name "builtin", 2,850 points and 5,696 triangles, one closed surface (a box-modelled cage refined by
// two Catmull–Clark subdivisions) in 14 body parts (triangles only, UVs in an atlas, normals), one material "skin" with
// map_Kd "builtin.png", 33 bones with anatomical DOF limits (the body's 29, then a ponytail's 4: ids 29–32), and the
// weights compute_automatic_weights() gives with default options. Deterministic: every call gives the same values
// (across platforms, to within the rounding of their sin/exp/pow). Cost: about 4 ms; allocates the model.
DEFORM_EXTRAS_API Model builtin_character();
// The names of the character's 14 body parts, one per submesh of builtin_character()'s mesh, in order ("torso",
// "neck", "head", ... "hair"): the OBJ groups of samples/data/builtin.obj (all in object "builtin").
DEFORM_EXTRAS_API std::span<const std::string_view> builtin_part_names() noexcept;

// The texture the material names: `size` × `size` RGB pixels (row 0 = top, i.e. v = 1), 8 bits per channel, painted
// by code per body-part atlas cell: skin tones and a face, hair, a shirt with short sleeves, trousers and shoes, soft
// shading (lighter in front or on top), value-noise brush strokes (docs/builtin-character.md).
// `size` must be a power of two from 16 to 4096 (throws deform::Error otherwise). Cost O(size²).
DEFORM_EXTRAS_API std::vector<std::uint8_t> builtin_texture(int size = 512);

// The rig of the built-in character (builtin_character(); model.builtin set): three lattices on the left arm — upper
// arm, forearm, hand — with under-damped springs, reach chain clavicle_l → hand_l — and the ponytail as a spring chain
// (2.75 Hz, damping ratio 0.4, gravity) kept out of capsules on the head, neck and chest. Throws deform::Error when
// `model` lacks those bones. Tests, benchmarks and docs pin numbers from it: builtin_full_rig() is the rig with every
// limb.
DEFORM_EXTRAS_API Rig builtin_rig(const Model& model);
// The built-in rig on every limb: builtin_rig()'s three left-arm lattices first (same names, same order), then the
// same three mirrored on the right arm (upperarm_r, forearm_r, hand_r) and three on each leg (thigh, shin, foot: _l,
// then _r), every one with builtin_rig()'s springs; reach chain clavicle_l → hand_l and the ponytail's spring chain
// and colliders as there. Character::reach with
// hand_l, hand_r, foot_l or foot_r stretches that limb's two upper lattices (nearest_reach_effector picks the limb
// for a target); a foot's chain starts at the hips, the root. Throws deform::Error when `model` lacks those bones.
DEFORM_EXTRAS_API Rig builtin_full_rig(const Model& model);
// What each lattice bone of the built-in character is, for default_lattice_motion: upper arms and thighs
// upper_limb, forearms and shins lower_limb, hands hand, feet foot, any other bone torso.
DEFORM_EXTRAS_API BodyPart builtin_body_part(std::string_view bone) noexcept;
// A walk for the built-in character (builtin_character()): "walk", 1 s, looping, cubic-spline keys every 1/16 s
// (tangents from the swing itself: smooth through the keys) on the spine, neck, arms and legs (within their limits)
// and a bob of the hips; for SamplingJob, the benchmarks of a whole
// frame and a crowd. Throws deform::Error when `model` lacks those bones.
DEFORM_EXTRAS_API Animation builtin_walk(const Model& model);
// Every clip of the built-in character, made like builtin_walk() (looping, cubic-spline keys with the motion's own
// derivatives as tangents, 16 keys per swing or more, every angle within the bones' limits, so set_pose's clamp
// leaves a sampled pose unchanged): "idle" (4 s: breathing, arms hanging), "walk" (builtin_walk()), "run" (0.7 s:
// leaning forward, knees high, arms pumping) and "wave" (2 s: the right hand raised, waving at 1.5 Hz), in that
// order. Throws deform::Error when `model` lacks their bones. Allocates the clips.
DEFORM_EXTRAS_API std::vector<Animation> builtin_clips(const Model& model);
// The built-in character with builtin_rig(): the Character every sample starts from.
DEFORM_EXTRAS_API Character make_builtin_character();

}  // namespace deform
