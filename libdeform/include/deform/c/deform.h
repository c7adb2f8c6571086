/* libdeform's C API (target deform::c): a Character (load or import, play its clips, pose, reach, release, update, read
 * the deformed mesh, or pose only and hand a GPU its palette, bind arrays and lattice data to deform it there),
 * linear-blend skinning and Direct Delta Mush over caller arrays, and Bezier lattices (bind points once, move control
 * points, evaluate), for any language that calls C (C#, Rust, Zig, Python's ctypes, engine scripting). docs/c-api.md
 * walks through it.
 *
 * Conventions:
 *  - Objects are opaque handles made by a *_create / *_load / *_import function and freed by the matching *_destroy
 * (NULL is accepted there and ignored).
 *  - Every function that can fail returns a deform_status; DEFORM_OK is 0. On failure nothing is changed and
 *    deform_last_error() says why, with the file, line or byte and element for input errors, as the C++ API does.
 *  - Vectors are float[3] (x, y, z); arrays of them are packed, 3 floats per element. Matrices are float[16],
 *    column-major (as GLM and OpenGL). Quaternions are float[4] as (x, y, z, w).
 *  - Nothing here keeps a caller's pointer after it returns, except where stated.
 *  - A handle is used by one thread at a time; distinct handles are independent. deform_last_error is per thread.
 *  - The per-frame functions (update, reach, release, skinning, lattice evaluation, the GPU route's palette and
 *    lattice frames) allocate nothing. */
#ifndef DEFORM_C_DEFORM_H
#define DEFORM_C_DEFORM_H

#include <stddef.h>
#include <stdint.h>

#include "deform/c/export.hpp"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum deform_status {
  DEFORM_OK = 0,
  DEFORM_ERROR_INPUT = 1,    /* a file or data that is malformed (the message names it) */
  DEFORM_ERROR_ARGUMENT = 2, /* a call that is not well formed: a NULL handle, a size that does not match, ... */
  DEFORM_ERROR_REFUSED = 3,  /* a per-frame call that refused its inputs (a non-finite target, a bad dt) */
  DEFORM_ERROR_INTERNAL = 4  /* anything else (out of memory, the system refusing a file) */
} deform_status;

/* Why the last call on this thread failed: a NUL-terminated UTF-8 message, valid until the next failing call on this
 * thread. "" when no call has failed. */
DEFORM_C_API const char* deform_last_error(void);

/* The library's version, "MAJOR.MINOR.PATCH". */
DEFORM_C_API const char* deform_version(void);

/* ---- Character: a rigged mesh with its elastic lattices (deform/character/character.hpp) ---- */

typedef struct deform_character deform_character;

/* The built-in character with its rig (three elastic lattices on the left arm) and its four clips. */
DEFORM_C_API deform_status deform_character_create_builtin(deform_character** out);
/* A character from native files: OBJ mesh, .sk skeleton, .skw weights, and optionally a rig (JSON; NULL: no
 * lattices, skinning and IK only). */
DEFORM_C_API deform_status deform_character_load(const char* obj_path, const char* sk_path, const char* skw_path,
                                                 const char* rig_path, deform_character** out);
/* deform_character_load, with `allow_count` folders (`allow_outside`, NUL-terminated paths) from which the OBJ may
 * also name its MTL files and textures. By default, and with deform_character_load, only the OBJ's own folder is
 * read: a file named elsewhere fails the call with DEFORM_ERROR_INPUT, naming the OBJ and the key (docs/security.md).
 * `allow_outside` may be NULL when `allow_count` is 0. */
DEFORM_C_API deform_status deform_character_load_allowing(const char* obj_path, const char* sk_path,
                                                          const char* skw_path, const char* rig_path,
                                                          const char* const* allow_outside, size_t allow_count,
                                                          deform_character** out);
DEFORM_C_API void deform_character_destroy(deform_character* character);
/* Another character of the same model and rig that shares this one's immutable data (mesh, skin, bindings, levels
 * and clips) and has its own pose, springs, clip cursors and deformed mesh: what a crowd makes per member (about 142 KB
 * each for the built-in character), far cheaper than loading again. Destroy each with deform_character_destroy, in any
 * order. */
DEFORM_C_API deform_status deform_character_instance(const deform_character* character, deform_character** out);

/* ---- Importing a model (deform/import/import.hpp; docs/import.md, docs/security.md) ---- */

/* The rig an imported character gets. */
typedef enum deform_import_rig {
  DEFORM_IMPORT_RIG_NONE = 0,    /* no lattices: skinning and IK only (as deform_character_load with no rig) */
  DEFORM_IMPORT_RIG_DEFAULT = 1, /* the rig the `deform` CLI gives an imported model (deform::default_rig: lattices
                                  * on the limbs it finds, reach chains); the call fails if it cannot be made or
                                  * bound, as the CLI does */
  DEFORM_IMPORT_RIG_FILE = 2     /* the rig JSON at `rig_path` */
} deform_import_rig;

/* How deform_character_import reads a model. Fill it with deform_import_options_init, then change what differs:
 * `struct_size` lets later versions add fields at the end without breaking callers built against this one. */
typedef struct deform_import_options {
  size_t struct_size; /* sizeof(deform_import_options), set by _init */
  deform_import_rig rig;
  const char* rig_path; /* with DEFORM_IMPORT_RIG_FILE: the rig JSON (its bones named as the model's); else unused */
  /* `allow_count` folders besides the model's own from which the model may name files (glTF buffers and images,
   * textures). By default only the model's folder is read: a file named elsewhere fails the call with
   * DEFORM_ERROR_INPUT naming the model and the key, before it is opened (docs/security.md). */
  const char* const* allow_outside;
  size_t allow_count;
  /* The importer runs in its own process (deform-import-worker) with these limits; 0 keeps the default (4 GiB of
   * memory, 60 s). A model that exceeds one, or crashes the importer, fails the call with DEFORM_ERROR_INPUT. */
  uint64_t max_memory_bytes;
  double max_seconds;
  /* The importer executable; NULL: $DEFORM_IMPORT_WORKER, then the one this build made, then the installed one
   * (LIBEXECDIR/deform-import-worker). A plugin that ships the worker beside itself names it here. */
  const char* worker_path;
  /* Nonzero: each point keeps its four strongest influences, renormalised (as a .skw file holds them), which the GPU
   * route's four slots need (deform_character_skin_bind refuses more); the points that lost some are counted in a
   * warning. 0 (the default): every influence the file gives, more than four skinned on the CPU. */
  int four_influences;
} deform_import_options;

/* Sets `options` to the defaults: struct_size, no rig, the model's folder only, the default limits and worker, every
 * influence. */
DEFORM_C_API void deform_import_options_init(deform_import_options* options);

/* A character from any model the import component reads: glTF 2.0 (.gltf, .glb), IQM, FBX, Collada, DirectX .x and
 * the other formats Assimp reads (docs/import.md), with the model's own animation clips (deform_character_clip_*),
 * its morph targets, and the rig `options` asks for (NULL: deform_import_options_init's defaults). The importer runs
 * isolated in deform-import-worker (import_model_isolated), so a hostile file cannot crash or hang the host.
 * Errors: DEFORM_ERROR_ARGUMENT for a NULL `path` or `out`, a NULL folder among `allow_outside`, a `struct_size`
 * smaller than this version's, an unknown `rig`, DEFORM_IMPORT_RIG_FILE without `rig_path`, or a `max_seconds`
 * negative or not finite; DEFORM_ERROR_INPUT naming the file (and the element) for a model that is missing,
 * malformed, names a file outside the allowed folders or exceeds a limit, and for a rig that does not fit it;
 * DEFORM_ERROR_INTERNAL for a build without the import component (Assimp and tinygltf were not found:
 * deform_last_error says so) or a worker that is not found. On failure `*out` is left as it was.
 * Allocates and takes time (a process start plus the import): call it at load time, not per frame. With a static
 * libdeform, a program that calls it links deform::import too (CMake: find_package(libdeform COMPONENTS import)). */
DEFORM_C_API deform_status deform_character_import(const char* path, const deform_import_options* options,
                                                   deform_character** out);
/* The import's non-fatal findings (unweighted vertices bound rigidly, influences dropped, scale a skeleton cannot
 * hold, textures missing), one line each naming the file; none for the other characters. `_warning` is a view valid
 * as long as the handle, or NULL for an index out of range. */
DEFORM_C_API size_t deform_character_warning_count(const deform_character* character);
DEFORM_C_API const char* deform_character_warning(const deform_character* character, size_t warning);

/* ---- Animation clips (deform/runtime/animation.hpp) ---- */

/* The clips the character has: an imported model's own, the built-in character's ("idle", "walk", "run", "wave"),
 * none for deform_character_load's. Instances share them (nothing is copied). `_clip_name` is a view valid as long
 * as the handle ("" for an unnamed clip), NULL for a clip out of range; `_clip_duration` is in seconds (>= 0; 0 for
 * a clip out of range); `_clip_loops` is nonzero when sampling wraps the time (every imported clip loops). */
DEFORM_C_API size_t deform_character_clip_count(const deform_character* character);
DEFORM_C_API const char* deform_character_clip_name(const deform_character* character, size_t clip);
DEFORM_C_API float deform_character_clip_duration(const deform_character* character, size_t clip);
DEFORM_C_API int deform_character_clip_loops(const deform_character* character, size_t clip);
/* The index of the first clip named `name`, or -1. */
DEFORM_C_API int32_t deform_character_find_clip(const deform_character* character, const char* name);
/* Clip `clip` at `seconds` into the caller's pose arrays (bone_count rotations (x, y, z, w) and translations, as
 * deform_character_set_pose takes them): every bone the clip animates gets its sampled local rotation and
 * translation, every other bone its bind pose, so the arrays hold a whole pose to blend with others or pass straight
 * to deform_character_set_pose. The time maps into the clip as the C++ SamplingJob maps it: a looping clip wraps it
 * into [0, duration) (negative times too), another clamps it into [0, duration]. Morph-weight tracks are not sampled
 * here. The handle keeps a key cursor per clip, so playing forwards costs O(channels) a frame. DEFORM_ERROR_ARGUMENT
 * for a NULL argument, a clip out of range or a bone_count that differs from the skeleton's; DEFORM_ERROR_REFUSED for
 * a time that is not finite. On failure nothing is written. No allocation. */
DEFORM_C_API deform_status deform_character_sample_clip(deform_character* character, size_t clip, float seconds,
                                                        float* rotations_xyzw, float* translations, size_t bone_count);

/* Mesh points (OBJ `v`) and bones. */
DEFORM_C_API size_t deform_character_point_count(const deform_character* character);
DEFORM_C_API size_t deform_character_bone_count(const deform_character* character);
/* The id of the first bone named `name`, or -1. */
DEFORM_C_API int32_t deform_character_find_bone(const deform_character* character, const char* name);

/* The held pose: each bone's local rotation (quaternions, bone_count * 4 floats) and translation (bone_count * 3
 * floats), clamped into the joint limits. `bone_count` must equal the skeleton's. */
DEFORM_C_API deform_status deform_character_set_pose(deform_character* character, const float* rotations_xyzw,
                                                     const float* translations, size_t bone_count);

/* The skeleton's bind pose, the pose to start a clip's sampling from: each bone's local rotation (x, y, z, w) and
 * translation into the caller's arrays (bone_count * 4 and bone_count * 3 floats). */
DEFORM_C_API deform_status deform_character_bind_pose(const deform_character* character, float* rotations_xyzw,
                                                      float* translations, size_t bone_count);
/* The held pose and where it is heading: the same arrays for the pose `lead` seconds later (`later_*`: the clip
 * sampled a millisecond ahead; lead > 0). update() takes the bones' velocities from the two, which the lattices'
 * inertia and the rig's spring chains follow between frames: the same motion at any frame rate
 * (Character::set_pose(pose, later, lead), docs/elasticity.md "Secondary motion"). DEFORM_ERROR_REFUSED for a pose
 * set_pose refuses or a lead that is not finite and > 0. No allocation. */
DEFORM_C_API deform_status deform_character_set_pose_moving(deform_character* character, const float* rotations_xyzw,
                                                            const float* translations,
                                                            const float* later_rotations_xyzw,
                                                            const float* later_translations, float lead,
                                                            size_t bone_count);
/* The character's elastic lattices (the rig's) and spring chains (the rig's "springs"). */
DEFORM_C_API size_t deform_character_lattice_count(const deform_character* character);
DEFORM_C_API size_t deform_character_spring_chain_count(const deform_character* character);
/* Secondary motion of lattice `lattice`, or of every lattice when `lattice` is DEFORM_ALL_LATTICES: `inertia` in
 * [0, 1] (how much its control points lag behind their bone's motion), `gravity` in m/s² in model space (3 floats;
 * NULL: none), `units_per_metre` > 0 (model units in a metre). For one lattice `inertia` is its inertia; with
 * DEFORM_ALL_LATTICES it is a scale of each lattice's tuned inertia, its body part's (the rig's "motion.part";
 * deform::scaled_inertia): 1 gives every part its tuned jiggle, in which limbs keep their length, 0 none; a lattice
 * with no part takes `inertia` itself. Each lattice keeps its rig's along-bone bound and far-face share
 * (docs/elasticity.md). DEFORM_ERROR_ARGUMENT for a value out of its range or a lattice out of range, changing
 * nothing. */
#define DEFORM_ALL_LATTICES ((size_t)-1)
DEFORM_C_API deform_status deform_character_set_lattice_motion(deform_character* character, size_t lattice,
                                                               float inertia, const float gravity[3],
                                                               float units_per_metre);

/* Delta Mush after the lattices (Character::set_delta_mush, docs/skinning.md "Delta Mush"): `iterations` smoothing
 * steps in [0, 10000] (0: off, the default), `step` in (0, 1], `mask` NULL (every point fully mushed) or `mask_count`
 * = point_count weights in [0, 1] (0 keeps a point as skinned). Binds at once (allocates: call it at set-up); from the
 * next update() the positions are mushed. DEFORM_ERROR_ARGUMENT naming the value for one out of range, changing
 * nothing. */
DEFORM_C_API deform_status deform_character_set_delta_mush(deform_character* character, int iterations, float step,
                                                           const float* mask, size_t mask_count);

/* Direct Delta Mush as the character's skinning (Character::set_direct_delta_mush, docs/skinning.md "Direct Delta
 * Mush"), in place of LBS while bound: `iterations` smoothing steps in [0, 100] (0: off, the default: LBS again),
 * `step` > 0 (2 is the usual); the other settings keep their defaults. Binds at once (allocates and takes time, a
 * sparse factorisation: call it at set-up); from the next update() the points are skinned by it. DEFORM_ERROR_ARGUMENT
 * naming the value for one out of range, changing nothing. */
DEFORM_C_API deform_status deform_character_set_direct_delta_mush(deform_character* character, int iterations,
                                                                  float step);
/* The same with the reduced-storage form (docs/skinning.md "Reduced storage": 4 floats an influence, the bones'
 * rotations blended; Character's DirectDeltaMushVariant::reduced). Either call replaces what the other bound. */
DEFORM_C_API deform_status deform_character_set_direct_delta_mush_reduced(deform_character* character, int iterations,
                                                                          float step);

/* Morph targets (blend shapes: the model's, and the shapes of the rig's pose-space corrective groups, appended after
 * them) and their weights, as the next update() applies them (Character::morph_weights). A weight set here holds
 * until changed, except on the targets a pose driver owns: update() sets those from the pose (docs/skinning.md
 * "Pose-space correctives"), so reading them after an update gives the driven weights. `_name` is the target's name
 * ("" when unnamed), a view valid as long as the handle, or NULL for a target out of range. `_morph_weights` copies
 * morph_target_count weights into `out` (`capacity` at least that: DEFORM_ERROR_ARGUMENT otherwise).
 * `_set_morph_weight` refuses (DEFORM_ERROR_REFUSED, changing nothing) a target out of range or a weight that is not
 * finite; `_set_morph_weight_named` sets every target of that name, and refuses a name no target has. No
 * allocation. */
DEFORM_C_API size_t deform_character_morph_target_count(const deform_character* character);
DEFORM_C_API const char* deform_character_morph_target_name(const deform_character* character, size_t target);
DEFORM_C_API deform_status deform_character_morph_weights(const deform_character* character, float* out,
                                                          size_t capacity);
DEFORM_C_API deform_status deform_character_set_morph_weight(deform_character* character, size_t target, float weight);
DEFORM_C_API deform_status deform_character_set_morph_weight_named(deform_character* character, const char* name,
                                                                   float weight);
/* The pose drivers the character runs each update(): one per corrective group of its rig. */
DEFORM_C_API size_t deform_character_pose_driver_count(const deform_character* character);

typedef struct deform_reach_result {
  float residual; /* |target - effector| after IK alone (model units) */
  float stretch;  /* stretch asked of the chain's lattices (model units) */
  float distance; /* |target - effector| once the stretch has settled */
  int iterations; /* IK + stretch rounds */
} deform_reach_result;

/* Reaches for `target` (model space) with bone `effector`: IK, then elastic stretch for what remains. `result` may be
 * NULL. DEFORM_ERROR_REFUSED for an effector out of range or the root, or a target not finite or beyond 1e18 on an
 * axis (distances to it would overflow: no result is ever infinite with DEFORM_OK). */
DEFORM_C_API deform_status deform_character_reach(deform_character* character, int32_t effector, const float target[3],
                                                  deform_reach_result* result);
/* Lets go: the stretch springs back, a damped oscillation. */
DEFORM_C_API void deform_character_release(deform_character* character);
/* Advances the springs by `dt` seconds and deforms the held pose. DEFORM_ERROR_REFUSED for a negative or non-finite
 * dt. */
DEFORM_C_API deform_status deform_character_update(deform_character* character, float dt);

/* The deformed positions (point_count * 3 floats) as of the last update: a view into the character, valid until
 * the next update or destroy. */
DEFORM_C_API const float* deform_character_positions(const deform_character* character);
/* Copies them: `capacity` floats at `out`, at least point_count * 3. */
DEFORM_C_API deform_status deform_character_copy_positions(const deform_character* character, float* out,
                                                           size_t capacity);
/* The render mesh the positions are drawn with: render vertices (a point may have several, at UV and normal seams),
 * each with its point; triangles of render vertex ids; UVs. Views into the character, valid until destroy. */
DEFORM_C_API size_t deform_character_vertex_count(const deform_character* character);
/* The point of each render vertex (vertex_count ids below point_count): positions[3 * vertex_points[v]] is vertex v's
 * position. */
DEFORM_C_API const uint32_t* deform_character_vertex_points(const deform_character* character);
DEFORM_C_API size_t deform_character_triangle_count(const deform_character* character);
/* triangle_count * 3 render vertex ids, in the mesh's own winding. */
DEFORM_C_API const uint32_t* deform_character_triangles(const deform_character* character);
/* vertex_count * 2 floats (u, v), or NULL when the mesh has no UVs. */
DEFORM_C_API const float* deform_character_uvs(const deform_character* character);
/* The unit normals of the last update, one per render vertex (vertex_count * 3 floats): carried through skinning and
 * the lattices (the default) or recomputed from the positions, as Character::normals() gives them. A view into the
 * character, valid until the next update or destroy; call it after each update that is drawn. Allocates nothing. */
DEFORM_C_API const float* deform_character_normals(deform_character* character);

/* A bone's world head, including what the lattices carry it by. */
DEFORM_C_API deform_status deform_character_bone_position(const deform_character* character, int32_t bone,
                                                          float out[3]);
/* The stretch the lattices have now (model units). */
DEFORM_C_API float deform_character_stretch(const deform_character* character);

/* ---- Levels of detail (docs/skinning.md, "Levels of detail"; Character::set_levels) ---- */

/* How one level deforms. Level 0 is the whole character: its `bones` is ignored (every bone) and its `points` should
 * be NULL. */
typedef struct deform_level {
  /* The bones the level skins with (levels after 0: non-increasing, raised to the roots where smaller): bones merged
   * into their kept ancestors, leaves and fingers first, by the weight they move (and the motion of the poses given
   * to deform_character_set_levels). The root motion is kept. */
  size_t bones;
  /* Nonzero: the lattices, spring chains and Delta Mush run at this level; 0: it skins the animated pose alone. */
  int deformers;
  /* The level deforms on every Nth update (1 to 64) and moves the points a share of the way in between: the springs
   * take the longer step, no pop. */
  uint32_t update_interval;
  /* The full mesh's point ids the level deforms (each once), e.g. those of a simplified mesh made for this level;
   * NULL: all. The other points keep stale positions and normals at this level: draw the level's own triangles.
   * With `deformers`, such a level runs the spring chains alone (the lattices and Delta Mush need the whole mesh). */
  const uint32_t* points;
  size_t point_count;
} deform_level;

/* Binds `level_count` levels (level 0 first) and shows level 0. Bones are merged on the motion of `pose_count` poses
 * of the skeleton (e.g. the clips the character plays, sampled over their length; bone_count rotations (x, y, z, w)
 * and translations each, pose after pose), or by weight alone when `pose_count` is 0 (the pointers may then be
 * NULL). A switch blends over `blend_frames` deformed updates (0 to 1000; 0: at once). DEFORM_ERROR_ARGUMENT, naming
 * the level, for no level, bones increasing, an interval outside [1, 64], a point id out of range or listed twice.
 * Allocates and takes time: call it at set-up. */
DEFORM_C_API deform_status deform_character_set_levels(deform_character* character, const deform_level* levels,
                                                       size_t level_count, const float* pose_rotations_xyzw,
                                                       const float* pose_translations, size_t pose_count,
                                                       uint32_t blend_frames);
/* How many levels (1 without levels), and the one the next update shows. */
DEFORM_C_API size_t deform_character_level_count(const deform_character* character);
DEFORM_C_API size_t deform_character_level(const deform_character* character);
/* Shows `level` from the next update on, with the switch's blend. DEFORM_ERROR_REFUSED for a level out of range.
 * Allocates nothing: call it per frame with what deform_pick_level gives. */
DEFORM_C_API deform_status deform_character_set_level(deform_character* character, size_t level);
/* Nonzero when the next update deforms; 0 while a level with an update interval is between its deformed updates
 * (that update reads no pose: a crowd may skip sampling the clip for it). */
DEFORM_C_API int deform_character_next_update_deforms(const deform_character* character);

typedef struct deform_level_cost {
  size_t points;     /* points skinned */
  size_t influences; /* the sum over them of their bone influences */
  size_t bones;      /* bones the skin uses */
  int deformers;
  uint32_t update_interval;
} deform_level_cost;
/* What a level's deformed update costs, for a caller that budgets a crowd. DEFORM_ERROR_ARGUMENT for a level out of
 * range. */
DEFORM_C_API deform_status deform_character_level_cost(const deform_character* character, size_t level,
                                                       deform_level_cost* out);
/* The fraction of the viewport's height that a height of `extent` at `distance` from a perspective camera with
 * `vertical_fov` (radians) covers; 0 for an argument not finite or not positive. */
DEFORM_C_API float deform_screen_height(float extent, float distance, float vertical_fov);
/* The level for that height: how many of `thresholds` (decreasing fractions, one per level after 0) it is below. */
DEFORM_C_API size_t deform_pick_level(const float* thresholds, size_t count, float height);

/* ---- The whole deformation on the GPU (docs/c-api.md, "Deforming on the GPU"; docs/gpu.md) ----
 *
 * With deform_on_cpu off, update() only poses and the host deforms each point p itself (a shader) from what the calls
 * below hand it, in this order:
 *  1. skinning: p = (sum_k weights[4p+k] * palette[bones[4p+k]]) * rest[p] / sum_k weights[4p+k], the matrices
 *     blended, then applied (linear blend skinning, as deform_skin_lbs);
 *  2. for every active lattice: each of its carried points += carried_weights[n] * far_displacement;
 *  3. for every active lattice, in index order: each bound point += weights[n] * sum_ijk D_ijk B_i(u) B_j(v) B_k(w),
 *     D its displacements (i-fastest: D_ijk = displacements[3 * (i + (du + 1) * (j + (dv + 1) * k))]) and B the
 *     Bernstein polynomials of its degrees (du, dv, dw): B_i(u) = C(du, i) u^i (1 - u)^(du - i).
 * That gives the points a deforming update() gives, to float rounding (the order of 3 matters only for rounding).
 * Normals: skinning the bind normals by the cofactor of the blended 3x3 gives the skinned ones; this API does not hand
 * out the lattices' normal maps, so with this route the normals are those of the skinned surface (the C++
 * GpuLatticeFields turns them by the lattices too). What only the CPU does stays out of it: morph targets and pose
 * correctives (rest[] is the bind pose unmorphed), Delta Mush and Direct Delta Mush, and the levels' reduced skins
 * (the bind arrays are the whole character's; the palette covers every bone). */

/* 1 (the default): update() deforms on the CPU. 0: update() only poses — forward kinematics, the spring chains, the
 * lattices' springs and their control points — and deform_character_positions and _normals keep the last deforming
 * update's points and normals (the bind pose before any); bone_position and stretch follow the pose as always, and
 * with levels every update poses at the level set (no update_interval). Takes effect at the next update; instances
 * made later copy it. No allocation. */
DEFORM_C_API deform_status deform_character_set_deform_on_cpu(deform_character* character, int on);
/* The skinning palette of the last update (deforming or not): bone_count matrices, 16 floats each, column-major,
 * T_world * T_bind^-1 with the spring chains' bending included (what deform_skin_lbs takes). Identity before any
 * update. A view into the character, valid until destroy; its content changes at each update. NULL for a NULL handle
 * (deform_last_error says so). No allocation. */
DEFORM_C_API const float* deform_character_palette(const deform_character* character);

/* What a GPU binds once for skinning: views into the character (shared by its instances), valid until destroy. */
typedef struct deform_skin_bind {
  size_t point_count;     /* mesh points (deform_character_point_count) */
  const float* positions; /* point_count * 3: the bind positions */
  const float* normals;   /* point_count * 3: the bind-pose unit normals (angle-weighted), which the CPU skins */
  const uint16_t* bones;  /* point_count * 4 bone ids */
  const float* weights;   /* point_count * 4 weights, unused slots 0, summing to 1 */
} deform_skin_bind;
/* Fills `out`. DEFORM_ERROR_ARGUMENT for a NULL argument; DEFORM_ERROR_REFUSED for a skin with points of more than
 * four influences, which four slots cannot hold: deform_character_load keeps the four strongest, an imported model
 * may have more (`deform info` prints max_influences) unless imported with deform_import_options::four_influences.
 * No allocation. */
DEFORM_C_API deform_status deform_character_skin_bind(const deform_character* character, deform_skin_bind* out);

/* Marks the padding lanes of a lattice binding. */
#define DEFORM_NO_POINT ((uint32_t)0xFFFFFFFFu)
/* What a GPU binds once for lattice `lattice`: views into the character (shared by its instances), valid until
 * destroy. The bound points come in lanes, blocks of 16 as the CPU evaluates them: lane n is point points[n] at
 * (u[n], v[n], w[n]) in the lattice's box with selection weight weights[n]; a padding lane has point DEFORM_NO_POINT
 * and weight 0 and is skipped. Each point is in at most one lane of a lattice, and in a lattice's bound or carried
 * points, not both. */
typedef struct deform_lattice_binding {
  int32_t degree[3];          /* Bezier degree along u (the bone), v and w, 1 to 16: degree + 1 control points each */
  size_t control_point_count; /* (degree[0] + 1) * (degree[1] + 1) * (degree[2] + 1) */
  size_t bound_count;         /* points the field moves (lanes that are not padding) */
  size_t lane_count;          /* entries of points, u, v, w and weights: bound_count plus padding, a multiple of 16 */
  const uint32_t* points;
  const float* u;
  const float* v;
  const float* w;
  const float* weights; /* in (0, 1] */
  size_t carried_count; /* points beyond the far face, moved by its displacement */
  const uint32_t* carried_points;
  const float* carried_weights; /* in (0, 1] */
} deform_lattice_binding;
/* What lattice `lattice` adds this frame, as of the last update. */
typedef struct deform_lattice_frame {
  int active; /* nonzero: the lattice moves points; 0: at rest, or not run by the update (a level without deformers
               * or with a point subset): it adds nothing, and the rest of this is an earlier update's */
  const float* displacements; /* control_point_count * 3, world space, i-fastest: a view, valid until destroy */
  float far_displacement[3];  /* what each carried point gets, times its weight */
} deform_lattice_frame;
/* Fill `out` for lattice `lattice` (below deform_character_lattice_count). DEFORM_ERROR_ARGUMENT for a NULL argument
 * or a lattice out of range. No allocation: call _lattice_binding at set-up, _lattice_frame after each update. */
DEFORM_C_API deform_status deform_character_lattice_binding(const deform_character* character, size_t lattice,
                                                            deform_lattice_binding* out);
DEFORM_C_API deform_status deform_character_lattice_frame(const deform_character* character, size_t lattice,
                                                          deform_lattice_frame* out);

/* ---- Skinning over caller arrays (deform/runtime/skinning.hpp, SkinningJob) ---- */

/* Linear blend skinning: out[v] = sum_k weights[4v+k] * palette[bones[4v+k]] * positions[v]. `palette`: bone_count
 * matrices (16 floats each, T_world * T_bind^-1); `bones`, `weights`: 4 per vertex (unused slots weight 0);
 * `positions` and `out`: vertex_count * 3 floats. Refuses (DEFORM_ERROR_REFUSED, nothing written) a non-finite
 * palette, an index out of range, or weights that are negative or do not sum to about 1. */
DEFORM_C_API deform_status deform_skin_lbs(const float* palette, size_t bone_count, const uint16_t* bones,
                                           const float* weights, const float* positions, size_t vertex_count,
                                           float* out);

/* ---- Direct Delta Mush over caller arrays (deform/runtime/direct_delta_mush.hpp; docs/skinning.md) ---- */

typedef struct deform_ddm deform_ddm;

/* Binds Direct Delta Mush (bind_direct_delta_mush): `positions`, point_count rest points (3 floats each);
 * `triangles`, triangle_count triangles of point indices (3 each); `bones` and `weights`, 4 per point as for
 * deform_skin_lbs. `iterations` and `step` are the smoothing's (0 for either keeps its default, 4 and 2); the other
 * settings keep their defaults. It allocates and takes time (a sparse factorisation): call it at set-up. Fails with
 * DEFORM_ERROR_ARGUMENT and a message naming the problem: a setting out of range, a point index out of range, a
 * point not finite, a weight not finite or negative. */
DEFORM_C_API deform_status deform_ddm_create(const float* positions, size_t point_count, const uint32_t* triangles,
                                             size_t triangle_count, const uint16_t* bones, const float* weights,
                                             int iterations, float step, deform_ddm** out);
DEFORM_C_API void deform_ddm_destroy(deform_ddm* ddm);
/* The number of points bound. */
DEFORM_C_API size_t deform_ddm_point_count(const deform_ddm* ddm);
/* Skins the bound rest points by `palette` (bone_count matrices, as for deform_skin_lbs) into `out` (point_count * 3
 * floats). `normals` and `out_normals`: both NULL, or point_count * 3 floats each (one normal per point, turned by its
 * point's rotation). Refuses (DEFORM_ERROR_REFUSED, nothing written) a palette too small for the weights' bones or
 * not finite. Allocates nothing. */
DEFORM_C_API deform_status deform_ddm_skin(const deform_ddm* ddm, const float* palette, size_t bone_count, float* out,
                                           const float* normals, float* out_normals);

/* ---- Bezier lattices (deform/runtime/lattice.hpp; free-form deformation of any point cloud) ---- */

typedef struct deform_lattice deform_lattice;

/* A Bezier lattice over the box [origin, origin + size] of the given degree per axis (1..16), its control points
 * at rest. */
DEFORM_C_API deform_status deform_lattice_create(const float origin[3], const float size[3], int degree_u, int degree_v,
                                                 int degree_w, deform_lattice** out);
DEFORM_C_API void deform_lattice_destroy(deform_lattice* lattice);
/* The control points, i-fastest ((degree_u+1) * (degree_v+1) * (degree_w+1) points, 3 floats each): a view into the
 * lattice to read and write freely, valid until destroy. `count` (may be NULL) receives the number of points. */
DEFORM_C_API float* deform_lattice_control_points(deform_lattice* lattice, size_t* count);
/* Binds `count` points (3 floats each): those inside the box are deformed by later evaluations, the others are left
 * as they are. Replaces an earlier binding. */
DEFORM_C_API deform_status deform_lattice_bind(deform_lattice* lattice, const float* points, size_t count);
/* Writes the deformed bound points into `out` (the count given to bind, 3 floats each); points outside the box are
 * not written (copy the rest positions there first). */
DEFORM_C_API deform_status deform_lattice_evaluate(const deform_lattice* lattice, float* out, size_t count);

#ifdef __cplusplus
}
#endif

#endif
