/* The C API (deform/c/deform.h) from C: a Character reaches, stretches and springs back; skinning and lattices agree
 * with plain references computed here; errors come back as status codes with messages naming what failed. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <unistd.h>

#include "deform/c/deform.h"

static int failures = 0;
#define CHECK(cond)                                                                                                 \
  do {                                                                                                              \
    if (!(cond)) {                                                                                                  \
      fprintf(stderr, "%s:%d: CHECK(%s) failed; last error: %s\n", __FILE__, __LINE__, #cond, deform_last_error()); \
      ++failures;                                                                                                   \
    }                                                                                                               \
  } while (0)

/* A small deterministic generator, so that the cases are the same on every run. */
static uint64_t state = 0x9E3779B97F4A7C15ull;
static double uniform(double lo, double hi) {
  state ^= state << 13, state ^= state >> 7, state ^= state << 17;
  return lo + (hi - lo) * (double)(state >> 11) / 9007199254740992.0;
}

static double distance3(const float* a, const float* b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static void character_reaches_stretches_and_springs_back(void) {
  deform_character* hero = NULL;
  CHECK(deform_character_create_builtin(&hero) == DEFORM_OK);
  if (hero == NULL) return;
  const size_t points = deform_character_point_count(hero);
  CHECK(points > 1000);
  CHECK(deform_character_bone_count(hero) > 10);
  const int32_t hand = deform_character_find_bone(hero, "hand_l");
  CHECK(hand > 0);
  CHECK(deform_character_find_bone(hero, "no such bone") == -1);

  CHECK(deform_character_update(hero, 1.0f / 60.0f) == DEFORM_OK);
  float* rest = malloc(3 * points * sizeof(float));
  CHECK(deform_character_copy_positions(hero, rest, 3 * points) == DEFORM_OK);
  CHECK(deform_character_copy_positions(hero, rest, 3 * points - 1) == DEFORM_ERROR_ARGUMENT);

  /* Beyond the arm's reach: IK leaves a residual, the lattices stretch to cover it. */
  const float target[3] = {1.6f, 1.5f, 0.3f};
  deform_reach_result reached;
  CHECK(deform_character_reach(hero, hand, target, &reached) == DEFORM_OK);
  CHECK(reached.residual > 0.05f);
  CHECK(reached.stretch > 0.05f);
  for (int frame = 0; frame < 600; ++frame) CHECK(deform_character_update(hero, 1.0f / 60.0f) == DEFORM_OK);
  float hand_at[3];
  CHECK(deform_character_bone_position(hero, hand, hand_at) == DEFORM_OK);
  CHECK(distance3(hand_at, target) < 0.01 * reached.residual + 1e-3);
  CHECK(deform_character_stretch(hero) > 0.9f * reached.stretch);

  /* The mesh moved, and the view is the copy. */
  const float* now = deform_character_positions(hero);
  double moved = 0.0;
  for (size_t i = 0; i < points; ++i) moved = fmax(moved, distance3(now + 3 * i, rest + 3 * i));
  CHECK(moved > 0.1);

  /* Released, the stretch swings back and settles at zero. */
  deform_character_release(hero);
  float lowest = 0.0f;
  for (int frame = 0; frame < 600; ++frame) {
    CHECK(deform_character_update(hero, 1.0f / 60.0f) == DEFORM_OK);
    lowest = fminf(lowest, deform_character_stretch(hero));
  }
  CHECK(lowest < 0.0f);
  CHECK(fabsf(deform_character_stretch(hero)) < 1e-3f);

  /* Refusals change nothing and say why. */
  CHECK(deform_character_update(hero, -1.0f) == DEFORM_ERROR_REFUSED);
  CHECK(strlen(deform_last_error()) > 0);
  const float nowhere[3] = {NAN, 0.0f, 0.0f};
  CHECK(deform_character_reach(hero, hand, nowhere, NULL) == DEFORM_ERROR_REFUSED);
  CHECK(deform_character_reach(hero, 0, target, NULL) == DEFORM_ERROR_REFUSED);
  /* A finite target so far away that distances to it overflow: refused, never an infinite distance with DEFORM_OK. */
  const float far_away[3] = {3e38f, 3e38f, 3e38f};
  CHECK(deform_character_reach(hero, hand, far_away, NULL) == DEFORM_ERROR_REFUSED);
  CHECK(strstr(deform_last_error(), "too far") != NULL);
  CHECK(deform_character_bone_position(hero, -1, hand_at) == DEFORM_ERROR_ARGUMENT);

  /* A pose: the bind pose given back as quaternions and translations of the right count. */
  const size_t bones = deform_character_bone_count(hero);
  float* rotations = calloc(4 * bones, sizeof(float));
  float* translations = calloc(3 * bones, sizeof(float));
  for (size_t b = 0; b < bones; ++b) rotations[4 * b + 3] = 1.0f;
  CHECK(deform_character_set_pose(hero, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_set_pose(hero, rotations, translations, bones - 1) == DEFORM_ERROR_ARGUMENT);
  rotations[3] = 0.0f;
  CHECK(deform_character_set_pose(hero, rotations, translations, bones) == DEFORM_ERROR_REFUSED);
  rotations[3] = 1.0f;

  /* Secondary motion: the body sways (the hips slide along Z, across the outstretched arm, and back) with the pose's
   * lead; with inertia the arm's lattices lag behind, so the fingers leave the rigid sway's path (the wrist stays on
   * the forearm, whose lattice keeps its far face on the bone, and a sway along the arm would move it only within
   * its along-bone bound: flesh, not a limb that changes length). */
  const int32_t fingers = deform_character_find_bone(hero, "fingers1_l");
  CHECK(fingers > 0);
  CHECK(deform_character_lattice_count(hero) == 3);
  CHECK(deform_character_spring_chain_count(hero) == 1); /* the ponytail */
  CHECK(deform_character_bind_pose(hero, rotations, translations, bones) == DEFORM_OK);
  float* later_rotations = malloc(4 * bones * sizeof(float));
  float* later_translations = malloc(3 * bones * sizeof(float));
  memcpy(later_rotations, rotations, 4 * bones * sizeof(float));
  memcpy(later_translations, translations, 3 * bones * sizeof(float));
  const float hips_z = translations[2];
  /* Run 0 rigid; run 1 every lattice at the scale 1 of its part's tuned inertia; run 2 each lattice given that tuned
   * inertia by hand (upper arm and forearm 0.3, hand 0.2: docs/elasticity.md), which is the same motion. */
  float paths[3][60][3];
  for (int run = 0; run < 3; ++run) {
    deform_character* mover = NULL;
    CHECK(deform_character_create_builtin(&mover) == DEFORM_OK);
    if (mover == NULL) break;
    if (run < 2) {
      CHECK(deform_character_set_lattice_motion(mover, DEFORM_ALL_LATTICES, (float)run, NULL, 1.0f) == DEFORM_OK);
    } else {
      const float tuned[3] = {0.3f, 0.3f, 0.2f};
      for (size_t l = 0; l < 3; ++l)
        CHECK(deform_character_set_lattice_motion(mover, l, tuned[l], NULL, 1.0f) == DEFORM_OK);
    }
    for (int n = 0; n < 60; ++n) {
      const float t = (float)n / 60.0f, lead = 1e-3f;
      translations[2] = hips_z + 0.1f * sinf(6.28318531f * t);
      later_translations[2] = hips_z + 0.1f * sinf(6.28318531f * (t + lead));
      CHECK(deform_character_set_pose_moving(mover, rotations, translations, later_rotations, later_translations, lead,
                                             bones) == DEFORM_OK);
      CHECK(deform_character_update(mover, n == 0 ? 0.0f : 1.0f / 60.0f) == DEFORM_OK);
      CHECK(deform_character_bone_position(mover, fingers, paths[run][n]) == DEFORM_OK);
    }
    deform_character_destroy(mover);
  }
  CHECK(memcmp(paths[1], paths[2], sizeof paths[1]) == 0);
  float largest_lag = 0.0f;
  for (int n = 0; n < 60; ++n) {
    const float dx = paths[1][n][0] - paths[0][n][0], dy = paths[1][n][1] - paths[0][n][1];
    const float dz = paths[1][n][2] - paths[0][n][2];
    largest_lag = fmaxf(largest_lag, sqrtf(dx * dx + dy * dy + dz * dz));
  }
  CHECK(largest_lag > 0.003f && largest_lag < 0.3f); /* 7 mm at the tuned inertia of the arm's parts */
  CHECK(deform_character_set_pose_moving(hero, rotations, translations, later_rotations, later_translations, 0.0f,
                                         bones) == DEFORM_ERROR_REFUSED);
  CHECK(deform_character_set_pose_moving(hero, rotations, translations, NULL, later_translations, 1e-3f, bones) ==
        DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_lattice_motion(hero, 99, 0.5f, NULL, 1.0f) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_lattice_motion(hero, 0, 2.0f, NULL, 1.0f) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "inertia") != NULL);
  CHECK(deform_character_set_lattice_motion(hero, DEFORM_ALL_LATTICES, 1.5f, NULL, 1.0f) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "inertia scale") != NULL);
  CHECK(deform_character_bind_pose(hero, rotations, translations, bones - 1) == DEFORM_ERROR_ARGUMENT);
  free(later_rotations);
  free(later_translations);
  free(rotations);
  free(translations);
  free(rest);
  deform_character_destroy(hero);
  deform_character_destroy(NULL);
}

static void loading_errors_name_the_file(void) {
  deform_character* nobody = NULL;
  CHECK(deform_character_load("/nonexistent/body.obj", "/nonexistent/body.sk", "/nonexistent/body.skw", NULL,
                              &nobody) == DEFORM_ERROR_INPUT);
  CHECK(strstr(deform_last_error(), "/nonexistent/body") != NULL);
  CHECK(nobody == NULL);
  CHECK(deform_character_load(NULL, "a", "b", NULL, &nobody) == DEFORM_ERROR_ARGUMENT);
}

static void write_text(const char* path, const char* text) {
  FILE* f = fopen(path, "wb");
  CHECK(f != NULL);
  if (f == NULL) return;
  fputs(text, f);
  fclose(f);
}

/* An OBJ naming an MTL file outside its folder is refused, unread, unless the caller allows that folder. */
static void files_outside_the_model_folder_are_refused(void) {
  char root[256], model[300], obj[320], secret[320];
  snprintf(root, sizeof root, "/tmp/deform_c_confine_%ld", (long)getpid());
  snprintf(model, sizeof model, "%s/model", root);
  snprintf(obj, sizeof obj, "%s/body.obj", model);
  snprintf(secret, sizeof secret, "%s/secret.mtl", root);
  mkdir(root, 0700);
  mkdir(model, 0700);
  write_text(secret, "SECRET-c0ffee\nnewmtl s\n");
  write_text(obj, "mtllib ../secret.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  deform_character* nobody = NULL;
  CHECK(deform_character_load(obj, "/nonexistent/body.sk", "/nonexistent/body.skw", NULL, &nobody) ==
        DEFORM_ERROR_INPUT);
  CHECK(strstr(deform_last_error(), "mtllib") != NULL);
  CHECK(strstr(deform_last_error(), "SECRET") == NULL);
  /* Allowed, the OBJ and its MTL file are read: the load goes on to the (missing) skeleton. */
  const char* const allowed[] = {root};
  CHECK(deform_character_load_allowing(obj, "/nonexistent/body.sk", "/nonexistent/body.skw", NULL, allowed, 1,
                                       &nobody) == DEFORM_ERROR_INPUT);
  CHECK(strstr(deform_last_error(), "body.sk") != NULL);
  CHECK(deform_character_load_allowing(obj, "a", "b", NULL, NULL, 1, &nobody) == DEFORM_ERROR_ARGUMENT);
  CHECK(nobody == NULL);
  remove(obj);
  remove(secret);
  rmdir(model);
  rmdir(root);
}

/* The built-in character's clips: sampled into whole poses that set_pose takes, shared by its instances. */
static void builtin_clips_play(void) {
  deform_character* hero = NULL;
  CHECK(deform_character_create_builtin(&hero) == DEFORM_OK);
  if (hero == NULL) return;
  const char* const names[] = {"idle", "walk", "run", "wave"};
  CHECK(deform_character_clip_count(hero) == 4);
  for (size_t c = 0; c < 4 && c < deform_character_clip_count(hero); ++c) {
    CHECK(strcmp(deform_character_clip_name(hero, c), names[c]) == 0);
    CHECK(deform_character_clip_duration(hero, c) > 0.0f);
  }
  CHECK(deform_character_clip_name(hero, 4) == NULL);
  CHECK(deform_character_clip_duration(hero, 4) == 0.0f);
  const int32_t walk = deform_character_find_clip(hero, "walk");
  CHECK(walk == 1);
  CHECK(deform_character_find_clip(hero, "moonwalk") == -1);
  if (walk < 0) {
    deform_character_destroy(hero);
    return;
  }

  const size_t bones = deform_character_bone_count(hero);
  float* r0 = malloc(4 * bones * sizeof(float));
  float* t0 = malloc(3 * bones * sizeof(float));
  float* r1 = malloc(4 * bones * sizeof(float));
  float* t1 = malloc(3 * bones * sizeof(float));
  float* bind_r = malloc(4 * bones * sizeof(float));
  float* bind_t = malloc(3 * bones * sizeof(float));
  CHECK(deform_character_bind_pose(hero, bind_r, bind_t, bones) == DEFORM_OK);
  const float duration = deform_character_clip_duration(hero, (size_t)walk);
  CHECK(deform_character_sample_clip(hero, (size_t)walk, 0.1f * duration, r0, t0, bones) == DEFORM_OK);
  CHECK(deform_character_sample_clip(hero, (size_t)walk, 0.4f * duration, r1, t1, bones) == DEFORM_OK);
  double rotation_gap = 0.0, unit_error = 0.0;
  size_t unchanged = 0;
  for (size_t b = 0; b < bones; ++b) {
    const float* q = r0 + 4 * b;
    unit_error = fmax(unit_error, fabs(sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) - 1.0));
    for (int k = 0; k < 4; ++k) rotation_gap = fmax(rotation_gap, fabs(r0[4 * b + k] - r1[4 * b + k]));
    /* Bones the walk leaves alone keep the bind pose, rotations in (x, y, z, w) order as bind_pose gives them. */
    if (memcmp(r0 + 4 * b, r1 + 4 * b, 4 * sizeof(float)) == 0 &&
        memcmp(t0 + 3 * b, t1 + 3 * b, 3 * sizeof(float)) == 0) {
      ++unchanged;
      CHECK(memcmp(r0 + 4 * b, bind_r + 4 * b, 4 * sizeof(float)) == 0);
      CHECK(memcmp(t0 + 3 * b, bind_t + 3 * b, 3 * sizeof(float)) == 0);
    }
  }
  CHECK(unit_error < 1e-5);
  CHECK(rotation_gap > 0.05);
  CHECK(unchanged < bones);
  /* A looping clip wraps its time: one duration later is the same pose. */
  CHECK(deform_character_clip_loops(hero, (size_t)walk) != 0);
  CHECK(deform_character_sample_clip(hero, (size_t)walk, 1.1f * duration, r1, t1, bones) == DEFORM_OK);
  double wrap_gap = 0.0;
  for (size_t k = 0; k < 4 * bones; ++k) wrap_gap = fmax(wrap_gap, fabs(r0[k] - r1[k]));
  CHECK(wrap_gap < 1e-4);

  /* The sampled pose, set and updated, moves the points from the bind pose's. */
  const size_t points = deform_character_point_count(hero);
  float* rest = malloc(3 * points * sizeof(float));
  CHECK(deform_character_update(hero, 0.0f) == DEFORM_OK);
  CHECK(deform_character_copy_positions(hero, rest, 3 * points) == DEFORM_OK);
  CHECK(deform_character_set_pose(hero, r0, t0, bones) == DEFORM_OK);
  CHECK(deform_character_update(hero, 1.0f / 60.0f) == DEFORM_OK);
  const float* walked = deform_character_positions(hero);
  double moved = 0.0;
  for (size_t i = 0; i < points; ++i) moved = fmax(moved, distance3(walked + 3 * i, rest + 3 * i));
  CHECK(moved > 0.05);

  /* An instance shares the clips (the same name views) and samples as the original does. */
  deform_character* twin = NULL;
  CHECK(deform_character_instance(hero, &twin) == DEFORM_OK);
  CHECK(deform_character_clip_count(twin) == 4);
  CHECK(deform_character_clip_name(twin, 1) == deform_character_clip_name(hero, 1));
  CHECK(deform_character_sample_clip(twin, (size_t)walk, 0.1f * duration, r1, t1, bones) == DEFORM_OK);
  CHECK(memcmp(r0, r1, 4 * bones * sizeof(float)) == 0 && memcmp(t0, t1, 3 * bones * sizeof(float)) == 0);
  deform_character_destroy(hero); /* in either order: the twin keeps the clips */
  CHECK(strcmp(deform_character_clip_name(twin, 3), "wave") == 0);

  /* Refusals write nothing. */
  memcpy(r1, r0, 4 * bones * sizeof(float));
  CHECK(deform_character_sample_clip(twin, 4, 0.0f, r1, t1, bones) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "clip out of range") != NULL);
  CHECK(deform_character_sample_clip(twin, 0, 0.0f, r1, t1, bones - 1) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "bone_count") != NULL);
  CHECK(deform_character_sample_clip(twin, 0, NAN, r1, t1, bones) == DEFORM_ERROR_REFUSED);
  CHECK(deform_character_sample_clip(twin, 0, 0.0f, NULL, t1, bones) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_sample_clip(NULL, 0, 0.0f, r1, t1, bones) == DEFORM_ERROR_ARGUMENT);
  CHECK(memcmp(r0, r1, 4 * bones * sizeof(float)) == 0);
  CHECK(deform_character_clip_count(NULL) == 0);
  deform_character_destroy(twin);

  /* Native files carry no clips. */
  deform_character* native = NULL;
  CHECK(deform_character_load(DEFORM_DATA_DIR "/builtin.obj", DEFORM_DATA_DIR "/builtin.sk",
                              DEFORM_DATA_DIR "/builtin.skw", NULL, &native) == DEFORM_OK);
  CHECK(deform_character_clip_count(native) == 0);
  CHECK(deform_character_warning_count(native) == 0);
  deform_character_destroy(native);
  free(r0), free(t0), free(r1), free(t1), free(bind_r), free(bind_t), free(rest);
}

#define MRFIXIT "/usr/share/assimp/models/IQM/mrfixit.iqm"

#ifdef DEFORM_TEST_HAVE_IMPORT
/* A glTF triangle whose buffer lies outside its folder: refused unless that folder is allowed. */
static void imports_are_confined(const char* work) {
  char model[300], gltf[320], bin[320];
  snprintf(model, sizeof model, "%s/confined", work);
  snprintf(gltf, sizeof gltf, "%s/triangle.gltf", model);
  snprintf(bin, sizeof bin, "%s/outside.bin", work);
  mkdir(model, 0700);
  const float triangle[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  FILE* f = fopen(bin, "wb");
  CHECK(f != NULL);
  if (f == NULL) return;
  fwrite(triangle, sizeof triangle, 1, f);
  fclose(f);
  write_text(gltf,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"uri\":\"../outside.bin\",\"byteLength\":36}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"accessors\":[{\"bufferView\":0,"
             "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"nodes\":[{\"mesh\":0}],"
             "\"scenes\":[{\"nodes\":[0]}],\"scene\":0}");
  deform_character* c = NULL;
  CHECK(deform_character_import(gltf, NULL, &c) == DEFORM_ERROR_INPUT);
  CHECK(strstr(deform_last_error(), gltf) != NULL);
  CHECK(strstr(deform_last_error(), "buffers[0]") != NULL);
  CHECK(c == NULL);
  deform_import_options options;
  deform_import_options_init(&options);
  const char* const allowed[] = {work};
  options.allow_outside = allowed;
  options.allow_count = 1;
  CHECK(deform_character_import(gltf, &options, &c) == DEFORM_OK);
  CHECK(deform_character_point_count(c) == 3);
  CHECK(deform_character_bone_count(c) == 1); /* a static scene: one bone "root" */
  CHECK(deform_character_clip_count(c) == 0);
  deform_character_destroy(c);
  options.allow_outside = NULL;
  CHECK(deform_character_import(gltf, &options, &c) == DEFORM_ERROR_ARGUMENT);
}

/* What `deform skin` writes: the OBJ's `v` lines, up to `capacity` points; the count read. */
static size_t read_obj_points(const char* path, float* out, size_t capacity) {
  FILE* f = fopen(path, "r");
  CHECK(f != NULL);
  if (f == NULL) return 0;
  char line[512];
  size_t n = 0;
  while (fgets(line, sizeof line, f) != NULL) {
    float x, y, z;
    if (line[0] == 'v' && line[1] == ' ' && sscanf(line + 2, "%f %f %f", &x, &y, &z) == 3) {
      if (n < capacity) out[3 * n] = x, out[3 * n + 1] = y, out[3 * n + 2] = z;
      ++n;
    }
  }
  fclose(f);
  return n;
}

#endif

/* deform_character_import on a real model: its clip played through the C API deforms as `deform skin` does. */
static void imported_model_plays_its_clips(void) {
  deform_character* c = NULL;
#ifndef DEFORM_TEST_HAVE_IMPORT
  CHECK(deform_character_import(MRFIXIT, NULL, &c) == DEFORM_ERROR_INTERNAL);
  CHECK(strstr(deform_last_error(), "lacks the import component") != NULL);
  CHECK(c == NULL);
#else
  const char* work = DEFORM_TEST_WORK_DIR;
  mkdir(work, 0700);
  imports_are_confined(work);

  CHECK(deform_character_import("/nonexistent/model.iqm", NULL, &c) == DEFORM_ERROR_INPUT);
  CHECK(strstr(deform_last_error(), "/nonexistent/model.iqm") != NULL);
  CHECK(deform_character_import(NULL, NULL, &c) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_import(MRFIXIT, NULL, NULL) == DEFORM_ERROR_ARGUMENT);
  deform_import_options options;
  deform_import_options_init(&options);
  options.rig = DEFORM_IMPORT_RIG_FILE;
  CHECK(deform_character_import(MRFIXIT, &options, &c) == DEFORM_ERROR_ARGUMENT); /* no rig_path */
  options.struct_size = 0;
  CHECK(deform_character_import(MRFIXIT, &options, &c) == DEFORM_ERROR_ARGUMENT);
  deform_import_options_init(&options);
  options.max_seconds = INFINITY;
  CHECK(deform_character_import(MRFIXIT, &options, &c) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "max_seconds") != NULL);
  deform_import_options_init(&options);
  options.worker_path = "/nonexistent/deform-import-worker";
  CHECK(deform_character_import(MRFIXIT, &options, &c) == DEFORM_ERROR_INTERNAL);
  CHECK(strstr(deform_last_error(), "/nonexistent/deform-import-worker") != NULL);
  CHECK(c == NULL);
  if (access(MRFIXIT, R_OK) != 0) {
    printf("C API: %s is missing (Debian's assimp-testmodels): its import is not checked\n", MRFIXIT);
    return;
  }
  deform_import_options_init(&options);
  options.rig = DEFORM_IMPORT_RIG_FILE;
  options.rig_path = "/nonexistent/mrfixit.rig.json";
  CHECK(deform_character_import(MRFIXIT, &options, &c) == DEFORM_ERROR_INPUT);
  CHECK(strstr(deform_last_error(), "/nonexistent/mrfixit.rig.json") != NULL);

  /* No rig: skinning and IK only; the counts `deform info` gives. */
  CHECK(deform_character_import(MRFIXIT, NULL, &c) == DEFORM_OK);
  if (c == NULL) return;
  CHECK(deform_character_bone_count(c) == 76);
  const size_t points = deform_character_point_count(c);
  CHECK(points == 1504); /* `deform info`: 1504 vertices (points), 76 bones, one clip "idle" */
  CHECK(deform_character_clip_count(c) == 1);
  CHECK(deform_character_lattice_count(c) == 0);
  const int32_t idle = deform_character_find_clip(c, "idle");
  CHECK(idle >= 0);
  const size_t bones = deform_character_bone_count(c);
  float* rotations = malloc(4 * bones * sizeof(float));
  float* translations = malloc(3 * bones * sizeof(float));
  float* expected = malloc(3 * (points + 1) * sizeof(float));
  if (idle >= 0) {
    CHECK(deform_character_sample_clip(c, (size_t)idle, 0.5f, rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_set_pose(c, rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_update(c, 0.0f) == DEFORM_OK);
    const float* got = deform_character_positions(c);

    char command[1024], obj[512];
    snprintf(obj, sizeof obj, "%s/mrfixit_idle.obj", work);
    remove(obj);
    snprintf(command, sizeof command, "'%s' skin '%s' --clip idle --time 0.5 --out '%s' > /dev/null", DEFORM_TEST_CLI,
             MRFIXIT, obj);
    CHECK(system(command) == 0);
    CHECK(read_obj_points(obj, expected, points + 1) == points);
    float low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < points; ++i)
      for (int k = 0; k < 3; ++k)
        low[k] = fminf(low[k], expected[3 * i + k]), high[k] = fmaxf(high[k], expected[3 * i + k]);
    const double size = distance3(low, high);
    CHECK(size > 0.0);
    double gap = 0.0;
    for (size_t i = 0; i < points; ++i) gap = fmax(gap, distance3(got + 3 * i, expected + 3 * i));
    CHECK(gap <= 1e-5 * size);
    printf("mrfixit idle at 0.5 s: largest gap %.3g of the size (bound 1e-5) from deform skin's %zu points\n",
           gap / size, points);
  }
  deform_character_destroy(c);

  /* The default rig, as the CLI gives it: lattices on the limbs it finds. */
  deform_import_options_init(&options);
  options.rig = DEFORM_IMPORT_RIG_DEFAULT;
  c = NULL;
  CHECK(deform_character_import(MRFIXIT, &options, &c) == DEFORM_OK);
  CHECK(deform_character_lattice_count(c) > 0);
  CHECK(deform_character_clip_count(c) > 0);
  deform_character_destroy(c);
  free(rotations), free(translations), free(expected);

  /* A model with six influences on some points (`deform info`: max_influences 6): its skin does not fit the GPU
   * route's four slots, unless imported with four_influences, which keeps each point's four strongest and says so. */
  const char* six = "/usr/share/assimp/models/FBX/animation_with_skeleton.fbx";
  if (access(six, R_OK) != 0) return;
  deform_skin_bind bind;
  c = NULL;
  CHECK(deform_character_import(six, NULL, &c) == DEFORM_OK);
  CHECK(deform_character_skin_bind(c, &bind) == DEFORM_ERROR_REFUSED);
  CHECK(strstr(deform_last_error(), "more than four influences") != NULL);
  deform_character_destroy(c);
  deform_import_options_init(&options);
  options.four_influences = 1;
  c = NULL;
  CHECK(deform_character_import(six, &options, &c) == DEFORM_OK);
  const deform_status bound = deform_character_skin_bind(c, &bind);
  CHECK(bound == DEFORM_OK);
  int normalised = 1;
  for (size_t i = 0; bound == DEFORM_OK && i < bind.point_count; ++i) {
    const float* w = bind.weights + 4 * i;
    normalised = normalised && fabsf(w[0] + w[1] + w[2] + w[3] - 1.0f) < 1e-5f;
  }
  CHECK(normalised);
  int said = 0;
  for (size_t i = 0; i < deform_character_warning_count(c); ++i)
    said = said || strstr(deform_character_warning(c, i), "four strongest influences") != NULL;
  CHECK(said);
  deform_character_destroy(c);
#endif
}

/* Rigid transforms: a rotation about a random axis, a translation, column-major. */
static void random_rigid(float* m) {
  double axis[3] = {uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
  const double length = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]) + 1e-9;
  const double angle = uniform(-3.14159, 3.14159), c = cos(angle), s = sin(angle), t = 1 - c;
  const double x = axis[0] / length, y = axis[1] / length, z = axis[2] / length;
  const double r[3][3] = {{t * x * x + c, t * x * y - s * z, t * x * z + s * y},
                          {t * x * y + s * z, t * y * y + c, t * y * z - s * x},
                          {t * x * z - s * y, t * y * z + s * x, t * z * z + c}};
  for (int col = 0; col < 3; ++col) {
    for (int row = 0; row < 3; ++row) m[4 * col + row] = (float)r[row][col];
    m[4 * col + 3] = 0.0f;
  }
  m[12] = (float)uniform(-2, 2), m[13] = (float)uniform(-2, 2), m[14] = (float)uniform(-2, 2), m[15] = 1.0f;
}

static void skinning_matches_a_plain_reference(void) {
  enum { bones = 12, vertices = 1000 };
  static float palette[16 * bones], positions[3 * vertices], weights[4 * vertices], out[3 * vertices];
  static uint16_t ids[4 * vertices];
  for (int trial = 0; trial < 20; ++trial) {
    for (int b = 0; b < bones; ++b) random_rigid(palette + 16 * b);
    for (int v = 0; v < vertices; ++v) {
      double sum = 0.0, w[4];
      for (int k = 0; k < 4; ++k) sum += (w[k] = k < 1 + v % 4 ? uniform(0.01, 1.0) : 0.0);
      for (int k = 0; k < 4; ++k)
        weights[4 * v + k] = (float)(w[k] / sum), ids[4 * v + k] = (uint16_t)(uniform(0, bones - 1e-9));
      for (int a = 0; a < 3; ++a) positions[3 * v + a] = (float)uniform(-1, 1);
    }
    CHECK(deform_skin_lbs(palette, bones, ids, weights, positions, vertices, out) == DEFORM_OK);
    double worst = 0.0;
    for (int v = 0; v < vertices; ++v) {
      double expected[3] = {0, 0, 0};
      for (int k = 0; k < 4; ++k) {
        const float* m = palette + 16 * ids[4 * v + k];
        const float* p = positions + 3 * v;
        for (int row = 0; row < 3; ++row)
          expected[row] += weights[4 * v + k] * (m[row] * p[0] + m[4 + row] * p[1] + m[8 + row] * p[2] + m[12 + row]);
      }
      for (int a = 0; a < 3; ++a) worst = fmax(worst, fabs(expected[a] - out[3 * v + a]));
    }
    CHECK(worst < 1e-5);
  }
  out[0] = 12345.0f;
  palette[5] = NAN;
  CHECK(deform_skin_lbs(palette, bones, ids, weights, positions, vertices, out) == DEFORM_ERROR_REFUSED);
  CHECK(out[0] == 12345.0f);
  CHECK(strstr(deform_last_error(), "not finite") != NULL);
  palette[5] = 0.0f;
  ids[7] = bones;
  CHECK(deform_skin_lbs(palette, bones, ids, weights, positions, vertices, out) == DEFORM_ERROR_REFUSED);
}

/* Degree 1 is trilinear interpolation of the 8 corners (the definition, computed here). */
static void lattice_matches_trilinear_interpolation(void) {
  const float origin[3] = {-1.0f, 0.0f, 2.0f}, size[3] = {2.0f, 4.0f, 1.0f};
  deform_lattice* box = NULL;
  CHECK(deform_lattice_create(origin, size, 1, 1, 1, &box) == DEFORM_OK);
  if (box == NULL) return;
  size_t count = 0;
  float* corners = deform_lattice_control_points(box, &count);
  CHECK(count == 8);
  enum { n = 500 };
  static float points[3 * n], out[3 * n];
  for (int i = 0; i < 3 * n; ++i) points[i] = origin[i % 3] + (float)uniform(-0.2, 1.2) * size[i % 3];
  CHECK(deform_lattice_bind(box, points, n) == DEFORM_OK);
  for (int i = 0; i < 24; ++i) corners[i] += (float)uniform(-0.5, 0.5);
  memcpy(out, points, sizeof points);
  CHECK(deform_lattice_evaluate(box, out, n) == DEFORM_OK);
  double worst = 0.0;
  int inside = 0;
  for (int p = 0; p < n; ++p) {
    double uvw[3];
    int in = 1;
    for (int a = 0; a < 3; ++a) {
      uvw[a] = (points[3 * p + a] - origin[a]) / size[a];
      in &= uvw[a] >= 0.0 && uvw[a] <= 1.0;
    }
    if (!in) {
      CHECK(memcmp(out + 3 * p, points + 3 * p, 3 * sizeof(float)) == 0);
      continue;
    }
    ++inside;
    double expected[3] = {0, 0, 0};
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const double w = (i ? uvw[0] : 1 - uvw[0]) * (j ? uvw[1] : 1 - uvw[1]) * (k ? uvw[2] : 1 - uvw[2]);
          for (int a = 0; a < 3; ++a) expected[a] += w * corners[3 * (i + 2 * (j + 2 * k)) + a];
        }
    for (int a = 0; a < 3; ++a) worst = fmax(worst, fabs(expected[a] - out[3 * p + a]));
  }
  CHECK(inside > n / 4);
  CHECK(worst < 1e-5);
  CHECK(deform_lattice_evaluate(box, out, n - 1) == DEFORM_ERROR_ARGUMENT);
  deform_lattice_destroy(box);
  CHECK(deform_lattice_create(origin, size, 0, 1, 1, &box) == DEFORM_ERROR_ARGUMENT);
  const float flat[3] = {1.0f, 0.0f, 1.0f};
  CHECK(deform_lattice_create(origin, flat, 1, 1, 1, &box) == DEFORM_ERROR_ARGUMENT);
}

/* Delta Mush through the C API: at the bind pose the rest comes back; a bent elbow is smoothed; a mask of zeros keeps
 * the skinned points; bad values are refused, changing nothing. */
static void delta_mush_smooths_a_bent_elbow(void) {
  deform_character* plain = NULL;
  deform_character* mushed = NULL;
  CHECK(deform_character_create_builtin(&plain) == DEFORM_OK);
  CHECK(deform_character_create_builtin(&mushed) == DEFORM_OK);
  if (plain == NULL || mushed == NULL) return;
  const size_t points = deform_character_point_count(plain), bones = deform_character_bone_count(plain);
  float* rest = malloc(points * 3 * sizeof(float));
  float* zeros = calloc(points, sizeof(float));
  float* rotations = malloc(bones * 4 * sizeof(float));
  float* translations = malloc(bones * 3 * sizeof(float));
  CHECK(deform_character_copy_positions(plain, rest, points * 3) == DEFORM_OK);
  CHECK(deform_character_set_delta_mush(mushed, -1, 0.5f, NULL, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "iterations") != NULL);
  CHECK(deform_character_set_delta_mush(mushed, 10, NAN, NULL, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "step") != NULL);
  CHECK(deform_character_set_delta_mush(mushed, 10, 0.5f, zeros, points - 1) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_delta_mush(mushed, 10, 0.5f, NULL, 3) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_delta_mush(mushed, 10, 0.5f, NULL, 0) == DEFORM_OK);
  CHECK(deform_character_update(mushed, 0.0f) == DEFORM_OK);
  double worst = 0.0;
  for (size_t p = 0; p < points; ++p)
    worst = fmax(worst, distance3(deform_character_positions(mushed) + 3 * p, rest + 3 * p));
  CHECK(worst < 1e-5); /* the rest pose back (the character is about 2 units tall) */
  /* The left elbow bent 100 degrees about x. */
  CHECK(deform_character_bind_pose(plain, rotations, translations, bones) == DEFORM_OK);
  const int32_t forearm = deform_character_find_bone(plain, "forearm_l");
  CHECK(forearm >= 0);
  if (forearm >= 0) {
    const float half = 0.5f * 100.0f * 3.14159265f / 180.0f;
    float* q = rotations + 4 * forearm;
    q[0] = sinf(half), q[1] = 0.0f, q[2] = 0.0f, q[3] = cosf(half);
  }
  double moved = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    CHECK(deform_character_set_pose(plain, rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_set_pose(mushed, rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_update(plain, 0.0f) == DEFORM_OK);
    CHECK(deform_character_update(mushed, 0.0f) == DEFORM_OK);
    moved = 0.0;
    for (size_t p = 0; p < points; ++p)
      moved =
          fmax(moved, distance3(deform_character_positions(mushed) + 3 * p, deform_character_positions(plain) + 3 * p));
    if (pass == 0) CHECK(moved > 1e-3); /* smoothed */
    else CHECK(moved == 0.0);           /* a mask of zeros: every point as skinned */
    if (pass == 0) CHECK(deform_character_set_delta_mush(mushed, 10, 0.5f, zeros, points) == DEFORM_OK);
  }
  CHECK(deform_character_set_delta_mush(mushed, 0, 0.5f, NULL, 0) == DEFORM_OK); /* off */
  free(rest);
  free(zeros);
  free(rotations);
  free(translations);
  deform_character_destroy(plain);
  deform_character_destroy(mushed);
}

/* Direct Delta Mush as the character's skinning: the rest pose comes back; a bent elbow differs from LBS; bad values
 * are refused; iterations 0 turns it off, giving LBS's points to the bit. */
static void character_direct_delta_mush(void) {
  deform_character* plain = NULL;
  deform_character* ddm = NULL;
  CHECK(deform_character_create_builtin(&plain) == DEFORM_OK);
  CHECK(deform_character_create_builtin(&ddm) == DEFORM_OK);
  if (plain == NULL || ddm == NULL) return;
  const size_t points = deform_character_point_count(plain), bones = deform_character_bone_count(plain);
  float* rest = malloc(points * 3 * sizeof(float));
  float* rotations = malloc(bones * 4 * sizeof(float));
  float* translations = malloc(bones * 3 * sizeof(float));
  CHECK(deform_character_copy_positions(plain, rest, points * 3) == DEFORM_OK);
  CHECK(deform_character_set_direct_delta_mush(NULL, 4, 2.0f) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_direct_delta_mush(ddm, -1, 2.0f) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "iterations") != NULL);
  CHECK(deform_character_set_direct_delta_mush(ddm, 4, NAN) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "step") != NULL);
  CHECK(deform_character_set_direct_delta_mush(ddm, 4, 2.0f) == DEFORM_OK);
  CHECK(deform_character_update(ddm, 0.0f) == DEFORM_OK);
  double worst = 0.0;
  for (size_t p = 0; p < points; ++p)
    worst = fmax(worst, distance3(deform_character_positions(ddm) + 3 * p, rest + 3 * p));
  CHECK(worst < 1e-4); /* the rest pose back (the character is about 2 units tall) */
  CHECK(deform_character_bind_pose(plain, rotations, translations, bones) == DEFORM_OK);
  const int32_t forearm = deform_character_find_bone(plain, "forearm_l");
  CHECK(forearm >= 0);
  if (forearm >= 0) {
    const float half = 0.5f * 100.0f * 3.14159265f / 180.0f;
    float* q = rotations + 4 * forearm;
    q[0] = sinf(half), q[1] = 0.0f, q[2] = 0.0f, q[3] = cosf(half);
  }
  for (int pass = 0; pass < 2; ++pass) {
    CHECK(deform_character_set_pose(plain, rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_set_pose(ddm, rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_update(plain, 0.0f) == DEFORM_OK);
    CHECK(deform_character_update(ddm, 0.0f) == DEFORM_OK);
    double moved = 0.0;
    for (size_t p = 0; p < points; ++p)
      moved =
          fmax(moved, distance3(deform_character_positions(ddm) + 3 * p, deform_character_positions(plain) + 3 * p));
    if (pass == 0) CHECK(moved > 1e-3); /* not LBS */
    else CHECK(moved == 0.0);           /* off: LBS to the bit */
    if (pass == 0) {
      /* The reduced form: near the full one at the bent elbow, not the same. */
      float* full = malloc(points * 3 * sizeof(float));
      CHECK(deform_character_copy_positions(ddm, full, points * 3) == DEFORM_OK);
      CHECK(deform_character_set_direct_delta_mush_reduced(NULL, 4, 2.0f) == DEFORM_ERROR_ARGUMENT);
      CHECK(deform_character_set_direct_delta_mush_reduced(ddm, 4, 2.0f) == DEFORM_OK);
      CHECK(deform_character_update(ddm, 0.0f) == DEFORM_OK);
      double gap = 0.0;
      for (size_t p = 0; p < points; ++p)
        gap = fmax(gap, distance3(deform_character_positions(ddm) + 3 * p, full + 3 * p));
      CHECK(gap > 1e-5);
      CHECK(gap < 0.1);
      free(full);
      CHECK(deform_character_set_direct_delta_mush(ddm, 0, 0.0f) == DEFORM_OK);
    }
  }
  free(rest);
  free(rotations);
  free(translations);
  deform_character_destroy(plain);
  deform_character_destroy(ddm);
}

/* Direct Delta Mush on a tube of 12 rings of 8 points along y, two bones (the joint at y = 5.5): the rest pose comes
 * back, one rigid transform on both bones moves every point and normal rigidly, and bad calls are refused. */
static void direct_delta_mush_keeps_rest_and_rigid_motion(void) {
  enum { rings = 12, around = 8, points = rings * around, triangles = 2 * (rings - 1) * around };
  static float positions[3 * points], weights[4 * points], normals[3 * points], out[3 * points], out_n[3 * points];
  static uint16_t ids[4 * points];
  static uint32_t tris[3 * triangles];
  for (int r = 0; r < rings; ++r)
    for (int a = 0; a < around; ++a) {
      const int p = r * around + a;
      const double angle = 6.2831853 * a / around;
      positions[3 * p] = (float)cos(angle), positions[3 * p + 1] = (float)r, positions[3 * p + 2] = (float)sin(angle);
      normals[3 * p] = (float)cos(angle), normals[3 * p + 1] = 0.0f, normals[3 * p + 2] = (float)sin(angle);
      const double w = fmin(1.0, fmax(0.0, (r - 3.5) / 4.0));
      ids[4 * p] = 0, ids[4 * p + 1] = 1, ids[4 * p + 2] = 0, ids[4 * p + 3] = 0;
      weights[4 * p] = (float)(1 - w), weights[4 * p + 1] = (float)w, weights[4 * p + 2] = 0, weights[4 * p + 3] = 0;
    }
  int t = 0;
  for (int r = 0; r + 1 < rings; ++r)
    for (int a = 0; a < around; ++a) {
      const uint32_t p0 = (uint32_t)(r * around + a), p1 = (uint32_t)(r * around + (a + 1) % around);
      const uint32_t q0 = p0 + around, q1 = p1 + around;
      tris[t++] = p0, tris[t++] = q0, tris[t++] = p1, tris[t++] = p1, tris[t++] = q0, tris[t++] = q1;
    }
  deform_ddm* ddm = NULL;
  CHECK(deform_ddm_create(positions, points, tris, triangles, ids, weights, 0, 0.0f, &ddm) == DEFORM_OK);
  if (ddm == NULL) return;
  CHECK(deform_ddm_point_count(ddm) == points);
  float palette[32];
  for (int i = 0; i < 32; ++i) palette[i] = (i % 16) % 5 == 0 ? 1.0f : 0.0f; /* two identities */
  CHECK(deform_ddm_skin(ddm, palette, 2, out, normals, out_n) == DEFORM_OK);
  double worst = 0.0;
  for (int i = 0; i < 3 * points; ++i) worst = fmax(worst, fabs(out[i] - positions[i]));
  CHECK(worst < 1e-5); /* 1e-6 of the tube's size (about 11.2) */
  random_rigid(palette);
  memcpy(palette + 16, palette, 16 * sizeof(float));
  CHECK(deform_ddm_skin(ddm, palette, 2, out, normals, out_n) == DEFORM_OK);
  worst = 0.0;
  double worst_n = 0.0;
  for (int p = 0; p < points; ++p) {
    const float* x = positions + 3 * p;
    const float* n = normals + 3 * p;
    for (int row = 0; row < 3; ++row) {
      const double e = palette[row] * x[0] + palette[4 + row] * x[1] + palette[8 + row] * x[2] + palette[12 + row];
      const double en = palette[row] * n[0] + palette[4 + row] * n[1] + palette[8 + row] * n[2];
      worst = fmax(worst, fabs(e - out[3 * p + row]));
      worst_n = fmax(worst_n, fabs(en - out_n[3 * p + row]));
    }
  }
  CHECK(worst < 1e-4);
  CHECK(worst_n < 1e-4);
  out[0] = 12345.0f;
  palette[3] = NAN;
  CHECK(deform_ddm_skin(ddm, palette, 2, out, NULL, NULL) == DEFORM_ERROR_REFUSED);
  CHECK(strstr(deform_last_error(), "palette matrix is not finite") != NULL);
  CHECK(deform_ddm_skin(ddm, palette, 1, out, NULL, NULL) == DEFORM_ERROR_REFUSED);
  CHECK(strstr(deform_last_error(), "palette is too small") != NULL);
  CHECK(out[0] == 12345.0f);
  CHECK(deform_ddm_skin(ddm, palette, 2, out, normals, NULL) == DEFORM_ERROR_ARGUMENT);
  deform_ddm_destroy(ddm);
  deform_ddm* bad = NULL;
  CHECK(deform_ddm_create(positions, points, tris, triangles, ids, weights, 1000, 0.0f, &bad) == DEFORM_ERROR_ARGUMENT);
  CHECK(bad == NULL && strstr(deform_last_error(), "iterations") != NULL);
  tris[4] = points;
  CHECK(deform_ddm_create(positions, points, tris, triangles, ids, weights, 0, 0.0f, &bad) == DEFORM_ERROR_ARGUMENT);
  CHECK(bad == NULL);
  deform_ddm_destroy(NULL);
}

/* A rig's pose-space corrective on the built-in character's left elbow: its weight is 0 at the bind pose and 1 at the
 * pose it was sculpted at (the driver is exact at its samples), where exactly its three points move, by their bind
 * deltas turned with the forearm; the morph weight calls name and refuse as documented. */
static void corrective_driven_by_the_elbow(void) {
  char rig[256];
  snprintf(rig, sizeof rig, "/tmp/deform_c_corrective_%ld.rig.json", (long)getpid());
  write_text(rig,
             "{\"rig\": 1, \"lattices\": [], \"correctives\": [{\"name\": \"elbow\", \"bones\": [\"forearm_l\"], "
             "\"shapes\": [\n"
             "  {\"name\": \"elbow_pad\", \"pose\": [[100, 0, 0]], \"points\": [1, 5, 9],\n"
             "   \"deltas\": [[0, 0, 0.01], [0, 0.01, 0], [0.01, 0, 0]]}]}]}\n");
  deform_character* plain = NULL;
  deform_character* padded = NULL;
  CHECK(deform_character_load(DEFORM_DATA_DIR "/builtin.obj", DEFORM_DATA_DIR "/builtin.sk",
                              DEFORM_DATA_DIR "/builtin.skw", NULL, &plain) == DEFORM_OK);
  CHECK(deform_character_load(DEFORM_DATA_DIR "/builtin.obj", DEFORM_DATA_DIR "/builtin.sk",
                              DEFORM_DATA_DIR "/builtin.skw", rig, &padded) == DEFORM_OK);
  remove(rig);
  if (plain == NULL || padded == NULL) {
    fprintf(stderr, "%s\n", deform_last_error());
    deform_character_destroy(plain);
    return;
  }
  CHECK(deform_character_pose_driver_count(plain) == 0 && deform_character_morph_target_count(plain) == 0);
  CHECK(deform_character_pose_driver_count(padded) == 1 && deform_character_morph_target_count(padded) == 1);
  CHECK(deform_character_morph_target_name(padded, 0) != NULL &&
        strcmp(deform_character_morph_target_name(padded, 0), "elbow_pad") == 0);
  CHECK(deform_character_morph_target_name(padded, 1) == NULL);
  const size_t points = deform_character_point_count(plain), bones = deform_character_bone_count(plain);
  float* rotations = malloc(bones * 4 * sizeof(float));
  float* translations = malloc(bones * 3 * sizeof(float));
  float weight = -1.0f;
  CHECK(deform_character_bind_pose(plain, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_update(padded, 0.0f) == DEFORM_OK);
  CHECK(deform_character_morph_weights(padded, &weight, 1) == DEFORM_OK && fabsf(weight) < 1e-6f);
  CHECK(deform_character_morph_weights(padded, &weight, 0) == DEFORM_ERROR_ARGUMENT);
  const int32_t forearm = deform_character_find_bone(plain, "forearm_l");
  CHECK(forearm >= 0);
  if (forearm >= 0) {
    const float half = 0.5f * 100.0f * 3.14159265f / 180.0f;
    float* q = rotations + 4 * forearm;
    q[0] = sinf(half), q[1] = 0.0f, q[2] = 0.0f, q[3] = cosf(half);
  }
  CHECK(deform_character_set_pose(plain, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_set_pose(padded, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_update(plain, 0.0f) == DEFORM_OK);
  CHECK(deform_character_update(padded, 0.0f) == DEFORM_OK);
  CHECK(deform_character_morph_weights(padded, &weight, 1) == DEFORM_OK && fabsf(weight - 1.0f) < 1e-4f);
  size_t moved = 0;
  for (size_t p = 0; p < points; ++p) {
    const double d = distance3(deform_character_positions(padded) + 3 * p, deform_character_positions(plain) + 3 * p);
    if (p == 1 || p == 5 || p == 9) CHECK(fabs(d - 0.01) < 1e-4); /* a rigid forearm keeps the 1 cm */
    else if (d != 0.0) ++moved;
  }
  CHECK(moved == 0);
  /* A weight set by hand holds on a target no driver owns; the driver overrides its own at the next update. */
  CHECK(deform_character_set_morph_weight(padded, 0, 0.25f) == DEFORM_OK);
  CHECK(deform_character_morph_weights(padded, &weight, 1) == DEFORM_OK && weight == 0.25f);
  CHECK(deform_character_update(padded, 0.0f) == DEFORM_OK);
  CHECK(deform_character_morph_weights(padded, &weight, 1) == DEFORM_OK && fabsf(weight - 1.0f) < 1e-4f);
  CHECK(deform_character_set_morph_weight(padded, 1, 0.5f) == DEFORM_ERROR_REFUSED);
  CHECK(strstr(deform_last_error(), "morph target out of range") != NULL);
  CHECK(deform_character_set_morph_weight(padded, 0, NAN) == DEFORM_ERROR_REFUSED);
  CHECK(deform_character_set_morph_weight_named(padded, "elbow_pad", 0.5f) == DEFORM_OK);
  CHECK(deform_character_set_morph_weight_named(padded, "knee_pad", 0.5f) == DEFORM_ERROR_REFUSED);
  CHECK(strstr(deform_last_error(), "no morph target of that name") != NULL);
  CHECK(deform_character_set_morph_weight_named(padded, NULL, 0.5f) == DEFORM_ERROR_ARGUMENT);
  free(rotations);
  free(translations);
  deform_character_destroy(plain);
  deform_character_destroy(padded);
}

/* Per point, the unit sum of its triangles' area-weighted normals: what a point's normal is, computed here. */
static void face_normals_per_point(const deform_character* c, double* out) {
  const size_t points = deform_character_point_count(c), triangles = deform_character_triangle_count(c);
  const uint32_t* corner = deform_character_triangles(c);
  const uint32_t* point_of = deform_character_vertex_points(c);
  const float* xyz = deform_character_positions(c);
  memset(out, 0, 3 * points * sizeof(double));
  for (size_t t = 0; t < triangles; ++t) {
    const float* a = xyz + 3 * point_of[corner[3 * t]];
    const float* b = xyz + 3 * point_of[corner[3 * t + 1]];
    const float* d = xyz + 3 * point_of[corner[3 * t + 2]];
    const double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, f[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    const double n[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]};
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < 3; ++r) out[3 * point_of[corner[3 * t + k]] + r] += n[r];
  }
  for (size_t p = 0; p < points; ++p) {
    double* n = out + 3 * p;
    const double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length > 0)
      for (int r = 0; r < 3; ++r) n[r] /= length;
  }
}

/* The mean over render vertices of the cosine between the character's normal and its point's face normals. */
static double normals_agreement(deform_character* c, double* scratch) {
  face_normals_per_point(c, scratch);
  const float* normals = deform_character_normals(c);
  const uint32_t* point_of = deform_character_vertex_points(c);
  const size_t vertices = deform_character_vertex_count(c);
  double sum = 0.0, worst_length = 0.0;
  for (size_t v = 0; v < vertices; ++v) {
    const float* n = normals + 3 * v;
    const double* f = scratch + 3 * point_of[v];
    sum += n[0] * f[0] + n[1] * f[1] + n[2] * f[2];
    worst_length = fmax(worst_length, fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0));
  }
  CHECK(worst_length < 1e-5);
  return sum / (double)vertices;
}

/* The render mesh and normals a host draws with, and instances sharing a character's data. */
static void render_mesh_normals_and_instances(void) {
  deform_character* hero = NULL;
  CHECK(deform_character_create_builtin(&hero) == DEFORM_OK);
  if (hero == NULL) return;
  const size_t points = deform_character_point_count(hero), vertices = deform_character_vertex_count(hero);
  const size_t triangles = deform_character_triangle_count(hero);
  CHECK(vertices >= points);
  CHECK(triangles > 1000);
  CHECK(deform_character_uvs(hero) != NULL);
  const uint32_t* point_of = deform_character_vertex_points(hero);
  const uint32_t* corner = deform_character_triangles(hero);
  int in_range = 1;
  for (size_t v = 0; v < vertices; ++v) in_range &= point_of[v] < points;
  for (size_t k = 0; k < 3 * triangles; ++k) in_range &= corner[k] < vertices;
  CHECK(in_range);

  /* Bent and stretched: the normals carried through skinning and the lattices still face as the triangles do. */
  double* scratch = malloc(3 * points * sizeof(double));
  CHECK(deform_character_update(hero, 0.0f) == DEFORM_OK);
  CHECK(normals_agreement(hero, scratch) > 0.97);
  const float target[3] = {1.6f, 1.5f, 0.3f};
  CHECK(deform_character_reach(hero, deform_character_find_bone(hero, "hand_l"), target, NULL) == DEFORM_OK);
  for (int frame = 0; frame < 30; ++frame) CHECK(deform_character_update(hero, 1.0f / 60.0f) == DEFORM_OK);
  CHECK(normals_agreement(hero, scratch) > 0.97);

  /* An instance starts at rest, deforms as its source did from rest, and outlives it. */
  deform_character* twin = NULL;
  CHECK(deform_character_instance(hero, &twin) == DEFORM_OK);
  CHECK(deform_character_instance(hero, NULL) == DEFORM_ERROR_ARGUMENT);
  if (twin != NULL) {
    CHECK(deform_character_vertex_points(twin) == point_of); /* shared, not copied */
    deform_character_destroy(hero);
    hero = NULL;
    deform_character* fresh = NULL;
    CHECK(deform_character_create_builtin(&fresh) == DEFORM_OK);
    CHECK(deform_character_reach(twin, deform_character_find_bone(twin, "hand_l"), target, NULL) == DEFORM_OK);
    CHECK(deform_character_reach(fresh, deform_character_find_bone(fresh, "hand_l"), target, NULL) == DEFORM_OK);
    for (int frame = 0; frame < 30; ++frame) {
      CHECK(deform_character_update(twin, 1.0f / 60.0f) == DEFORM_OK);
      CHECK(deform_character_update(fresh, 1.0f / 60.0f) == DEFORM_OK);
    }
    CHECK(memcmp(deform_character_positions(twin), deform_character_positions(fresh), 3 * points * sizeof(float)) == 0);
    deform_character_destroy(fresh);
  }
  deform_character_destroy(twin);
  deform_character_destroy(hero);
  free(scratch);
}

/* Turns each named bone of a pose (rotations x, y, z, w per bone) further, about a random axis by a random angle whose
 * half is in [half_lo, half_hi] radians. */
static void bend_randomly(const deform_character* c, float* rotations, const char* const* names, size_t count,
                          double half_lo, double half_hi) {
  for (size_t k = 0; k < count; ++k) {
    const int32_t b = deform_character_find_bone(c, names[k]);
    CHECK(b >= 0);
    if (b < 0) continue;
    const double half = uniform(half_lo, half_hi), ax = uniform(-1, 1), ay = uniform(-1, 1), az = uniform(-1, 1);
    const double s = sin(half) / sqrt(ax * ax + ay * ay + az * az + 1e-12), cosine = cos(half);
    const double t[4] = {ax * s, ay * s, az * s, cosine};
    float* q = rotations + 4 * b;
    const double r[4] = {
        q[3] * t[0] + q[0] * t[3] + q[1] * t[2] - q[2] * t[1], q[3] * t[1] - q[0] * t[2] + q[1] * t[3] + q[2] * t[0],
        q[3] * t[2] + q[0] * t[1] - q[1] * t[0] + q[2] * t[3], q[3] * t[3] - q[0] * t[0] - q[1] * t[1] - q[2] * t[2]};
    for (int i = 0; i < 4; ++i) q[i] = (float)r[i];
  }
}

/* The largest distance between two characters' positions over `count` points (all when ids is NULL). */
static double largest_gap(const deform_character* a, const deform_character* b, const uint32_t* ids, size_t count) {
  const float* pa = deform_character_positions(a);
  const float* pb = deform_character_positions(b);
  double worst = 0.0;
  for (size_t k = 0; k < count; ++k) {
    const size_t p = ids ? ids[k] : k;
    worst = fmax(worst, distance3(pa + 3 * p, pb + 3 * p));
  }
  return worst;
}

/* Levels of detail: level 0 is the whole character; fewer bones, a point subset and an update interval change the
 * cost as stated and keep the shape near; the camera helpers pick levels; malformed levels are refused whole. */
static void levels_of_detail(void) {
  deform_character *lod = NULL, *whole = NULL;
  CHECK(deform_character_create_builtin(&lod) == DEFORM_OK);
  CHECK(deform_character_create_builtin(&whole) == DEFORM_OK);
  if (lod == NULL || whole == NULL) return;
  const size_t points = deform_character_point_count(lod), bones = deform_character_bone_count(lod);
  CHECK(deform_character_level_count(lod) == 1);

  /* A bent pose: the bones a walk turns, each about a random axis. */
  float* rotations = malloc(4 * bones * sizeof(float));
  float* translations = malloc(3 * bones * sizeof(float));
  CHECK(deform_character_bind_pose(lod, rotations, translations, bones) == DEFORM_OK);
  const char* bent[] = {"spine",  "neck",       "thigh_l",    "thigh_r",  "shin_l",
                        "shin_r", "upperarm_l", "upperarm_r", "forearm_l"};
  bend_randomly(lod, rotations, bent, sizeof bent / sizeof *bent, 0.1, 0.3);

  uint32_t* half_points = malloc(points / 2 * sizeof(uint32_t));
  for (size_t k = 0; k < points / 2; ++k) half_points[k] = (uint32_t)(2 * k + 1);
  deform_level levels[3] = {{0, 1, 1, NULL, 0}, {bones / 2, 1, 1, NULL, 0}, {bones / 3, 0, 2, half_points, points / 2}};
  CHECK(deform_character_set_levels(lod, levels, 3, rotations, translations, 1, 0) == DEFORM_OK);
  CHECK(deform_character_level_count(lod) == 3);
  CHECK(deform_character_level(lod) == 0);

  deform_level_cost cost[3];
  for (size_t l = 0; l < 3; ++l) CHECK(deform_character_level_cost(lod, l, &cost[l]) == DEFORM_OK);
  CHECK(deform_character_level_cost(lod, 3, &cost[0]) == DEFORM_ERROR_ARGUMENT);
  CHECK(cost[0].points == points && cost[1].points == points && cost[2].points == points / 2);
  CHECK(cost[0].bones > cost[1].bones && cost[1].bones > cost[2].bones && cost[1].bones <= bones / 2);
  CHECK(cost[0].influences > cost[2].influences);
  CHECK(cost[0].deformers == 1 && cost[2].deformers == 0);
  CHECK(cost[0].update_interval == 1 && cost[2].update_interval == 2);

  /* Level 0 draws what the character without levels draws. The updates take no time (dt 0), so that the comparisons
   * see the skin alone, not the springs' response to a pose set at once. */
  CHECK(deform_character_set_pose(lod, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_set_pose(whole, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_update(lod, 0.0f) == DEFORM_OK);
  CHECK(deform_character_update(whole, 0.0f) == DEFORM_OK);
  CHECK(largest_gap(lod, whole, NULL, points) == 0.0);

  /* Level 1 merges the bones the pose given to set_levels leaves unturned: the same shape. */
  CHECK(deform_character_set_level(lod, 3) == DEFORM_ERROR_REFUSED);
  CHECK(deform_character_level(lod) == 0);
  CHECK(deform_character_set_level(lod, 1) == DEFORM_OK);
  CHECK(deform_character_level(lod) == 1);
  CHECK(deform_character_update(lod, 0.0f) == DEFORM_OK);
  CHECK(largest_gap(lod, whole, NULL, points) < 1e-5);

  /* Level 2 deforms every 2nd update, its own points only, and merges turned bones: near, not the same. */
  CHECK(deform_character_set_level(lod, 2) == DEFORM_OK);
  int deformed = 0;
  for (int frame = 0; frame < 8; ++frame) {
    deformed += deform_character_next_update_deforms(lod);
    CHECK(deform_character_update(lod, 0.0f) == DEFORM_OK);
  }
  CHECK(deformed == 4);
  const double level2_gap = largest_gap(lod, whole, half_points, points / 2);
  CHECK(level2_gap > 1e-3 && level2_gap < 0.3);

  /* One level alone is the whole character again (levels cleared), on an instance. */
  deform_character* cleared = NULL;
  CHECK(deform_character_instance(lod, &cleared) == DEFORM_OK);
  CHECK(deform_character_set_levels(cleared, levels, 1, NULL, NULL, 0, 0) == DEFORM_OK);
  CHECK(deform_character_level_count(cleared) == 1 && deform_character_level(cleared) == 0);
  CHECK(deform_character_set_pose(cleared, rotations, translations, bones) == DEFORM_OK);
  CHECK(deform_character_update(cleared, 0.0f) == DEFORM_OK);
  CHECK(largest_gap(cleared, whole, NULL, points) == 0.0);
  deform_character_destroy(cleared);

  /* Instances share the levels. */
  deform_character* member = NULL;
  CHECK(deform_character_instance(lod, &member) == DEFORM_OK);
  CHECK(deform_character_level_count(member) == 3);
  deform_character_destroy(member);

  /* Malformed levels change nothing. */
  deform_level bad[2] = {{0, 1, 1, NULL, 0}, {bones + 5, 1, 0, NULL, 0}};
  CHECK(deform_character_set_levels(lod, bad, 2, NULL, NULL, 0, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "level 1") != NULL);
  bad[1].update_interval = 1;
  const uint32_t twice[2] = {7, 7};
  bad[1].points = twice, bad[1].point_count = 2;
  CHECK(deform_character_set_levels(lod, bad, 2, NULL, NULL, 0, 0) == DEFORM_ERROR_ARGUMENT);
  bad[1].points = NULL;
  CHECK(deform_character_set_levels(lod, bad, 2, NULL, NULL, 0, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_levels(lod, bad, 0, NULL, NULL, 0, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_levels(lod, bad, 2, NULL, NULL, 1, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_set_levels(lod, levels, 3, NULL, NULL, 0, 1001) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_level_count(lod) == 3 && deform_character_level(lod) == 2);

  /* The camera helpers: a 2-unit character 2 units away fills 2 atan(1/2) / (pi/2) of a 90-degree view. */
  CHECK(fabs(deform_screen_height(2.0f, 2.0f, 1.5707963f) - 2.0 * atan(0.5) / 1.5707963) < 1e-5);
  CHECK(deform_screen_height(2.0f, -1.0f, 1.0f) == 0.0f);
  const float thresholds[3] = {0.5f, 0.25f, 0.125f};
  CHECK(deform_pick_level(thresholds, 3, 0.6f) == 0 && deform_pick_level(thresholds, 3, 0.3f) == 1);
  CHECK(deform_pick_level(thresholds, 3, 0.2f) == 2 && deform_pick_level(thresholds, 3, 0.1f) == 3);

  free(half_points);
  free(rotations);
  free(translations);
  deform_character_destroy(lod);
  deform_character_destroy(whole);
}

/* B_i,n(t) = C(n, i) t^i (1 - t)^(n - i), the Bernstein polynomial, in double. */
static double bernstein(int n, int i, double t) {
  double value = 1.0;
  for (int k = 1; k <= i; ++k) value = value * (double)(n - i + k) / (double)k; /* C(n, i) */
  for (int k = 0; k < i; ++k) value *= t;
  for (int k = 0; k < n - i; ++k) value *= 1.0 - t;
  return value;
}

enum { most_lattices = 8 };

/* What a host's shaders do with the GPU route's data (deform.h, "The whole deformation on the GPU"), in plain loops
 * over every point, into `out` (point_count * 3 doubles): linear blend skinning by the palette, then every active
 * lattice's carried points, then every active lattice's Bezier field. Returns the largest distance the lattices moved
 * a point, so that a caller can see they did. */
static double deform_like_a_shader(const deform_character* c, const deform_skin_bind* skin,
                                   const deform_lattice_binding* lattices, size_t lattice_count, double* out) {
  const float* palette = deform_character_palette(c);
  for (size_t p = 0; p < skin->point_count; ++p) {
    double m[16] = {0.0}, sum = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double w = skin->weights[4 * p + k];
      const float* bone = palette + 16 * (size_t)skin->bones[4 * p + k];
      for (int e = 0; e < 16; ++e) m[e] += w * bone[e];
      sum += w;
    }
    const float* x = skin->positions + 3 * p;
    for (int r = 0; r < 3; ++r) /* column-major: element (row r, column c) at m[4c + r] */
      out[3 * p + r] = (m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r]) / sum;
  }
  double* skinned = malloc(3 * skin->point_count * sizeof(double));
  memcpy(skinned, out, 3 * skin->point_count * sizeof(double));
  deform_lattice_frame frames[most_lattices];
  for (size_t l = 0; l < lattice_count; ++l) CHECK(deform_character_lattice_frame(c, l, &frames[l]) == DEFORM_OK);
  for (size_t l = 0; l < lattice_count; ++l) {
    if (!frames[l].active) continue;
    for (size_t n = 0; n < lattices[l].carried_count; ++n)
      for (int r = 0; r < 3; ++r)
        out[3 * lattices[l].carried_points[n] + r] +=
            (double)lattices[l].carried_weights[n] * frames[l].far_displacement[r];
  }
  for (size_t l = 0; l < lattice_count; ++l) {
    if (!frames[l].active) continue;
    const deform_lattice_binding* b = &lattices[l];
    const int du = b->degree[0], dv = b->degree[1], dw = b->degree[2];
    for (size_t n = 0; n < b->lane_count; ++n) {
      if (b->points[n] == DEFORM_NO_POINT) continue;
      double field[3] = {0.0, 0.0, 0.0};
      for (int k = 0; k <= dw; ++k)
        for (int j = 0; j <= dv; ++j)
          for (int i = 0; i <= du; ++i) {
            const double basis = bernstein(du, i, b->u[n]) * bernstein(dv, j, b->v[n]) * bernstein(dw, k, b->w[n]);
            const float* d = frames[l].displacements + 3 * (size_t)(i + (du + 1) * (j + (dv + 1) * k));
            for (int r = 0; r < 3; ++r) field[r] += basis * d[r];
          }
      for (int r = 0; r < 3; ++r) out[3 * b->points[n] + r] += (double)b->weights[n] * field[r];
    }
  }
  double moved = 0.0;
  for (size_t p = 0; p < skin->point_count; ++p) {
    const double dx = out[3 * p] - skinned[3 * p], dy = out[3 * p + 1] - skinned[3 * p + 1],
                 dz = out[3 * p + 2] - skinned[3 * p + 2];
    moved = fmax(moved, sqrt(dx * dx + dy * dy + dz * dz));
  }
  free(skinned);
  return moved;
}

/* The largest distance between a character's positions and points in double. */
static double gap_to(const deform_character* c, const double* points, size_t count) {
  const float* p = deform_character_positions(c);
  double worst = 0.0;
  for (size_t i = 0; i < 3 * count; i += 3) {
    const double dx = p[i] - points[i], dy = p[i + 1] - points[i + 1], dz = p[i + 2] - points[i + 2];
    worst = fmax(worst, sqrt(dx * dx + dy * dy + dz * dz));
  }
  return worst;
}

/* The whole deformation on the host's GPU: a character deforming on the CPU and a twin that only poses (deform_on_cpu
 * off) take the same bent pose, reach beyond the arm (the lattices stretch), jiggle under gravity and spring back after
 * a release. From the twin's palette, bind arrays and lattice data, plain loops here (skinning, carried points,
 * Bernstein polynomials of their own) give the first one's points. */
static void gpu_route_reproduces_the_cpu(void) {
  deform_character *cpu = NULL, *gpu = NULL;
  CHECK(deform_character_create_builtin(&cpu) == DEFORM_OK);
  CHECK(deform_character_create_builtin(&gpu) == DEFORM_OK);
  if (cpu == NULL || gpu == NULL) return;
  const size_t points = deform_character_point_count(gpu), bones = deform_character_bone_count(gpu);
  const size_t lattice_count = deform_character_lattice_count(gpu);
  CHECK(lattice_count == 3 && lattice_count <= most_lattices);

  /* Refusals, each with a message. */
  deform_skin_bind skin;
  deform_lattice_binding lattices[most_lattices];
  deform_lattice_frame frame;
  CHECK(deform_character_set_deform_on_cpu(NULL, 0) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "NULL") != NULL);
  CHECK(deform_character_palette(NULL) == NULL);
  CHECK(strstr(deform_last_error(), "deform_character_palette") != NULL);
  CHECK(deform_character_skin_bind(gpu, NULL) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_skin_bind(NULL, &skin) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_lattice_binding(gpu, lattice_count, &lattices[0]) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "lattice out of range") != NULL);
  CHECK(deform_character_lattice_binding(gpu, 0, NULL) == DEFORM_ERROR_ARGUMENT);
  CHECK(deform_character_lattice_frame(gpu, lattice_count, &frame) == DEFORM_ERROR_ARGUMENT);
  CHECK(strstr(deform_last_error(), "lattice out of range") != NULL);
  CHECK(deform_character_lattice_frame(NULL, 0, &frame) == DEFORM_ERROR_ARGUMENT);

  /* The bind data, once: four influences per point summing to 1, lanes of 16 with padding marked, parameters in the
   * box, the carried points apart from the bound ones. */
  CHECK(deform_character_skin_bind(gpu, &skin) == DEFORM_OK);
  CHECK(skin.point_count == points);
  int sane = 1;
  for (size_t p = 0; p < points; ++p) {
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) sane &= skin.bones[4 * p + k] < bones, sum += skin.weights[4 * p + k];
    const float* n = skin.normals + 3 * p;
    sane &= fabs(sum - 1.0) < 1e-5 && fabs(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0) < 1e-5;
  }
  CHECK(sane);
  for (size_t l = 0; l < lattice_count; ++l) {
    CHECK(deform_character_lattice_binding(gpu, l, &lattices[l]) == DEFORM_OK);
    const deform_lattice_binding* b = &lattices[l];
    CHECK(b->degree[0] >= 1 && b->degree[0] <= 16 && b->degree[1] >= 1 && b->degree[1] <= 16 && b->degree[2] >= 1 &&
          b->degree[2] <= 16);
    CHECK(b->control_point_count ==
          (size_t)(b->degree[0] + 1) * (size_t)(b->degree[1] + 1) * (size_t)(b->degree[2] + 1));
    CHECK(b->lane_count % 16 == 0 && b->lane_count >= b->bound_count && b->bound_count > 0);
    size_t real = 0;
    sane = 1;
    for (size_t n = 0; n < b->lane_count; ++n) {
      if (b->points[n] == DEFORM_NO_POINT) {
        sane &= b->weights[n] == 0.0f;
        continue;
      }
      ++real;
      sane &= b->points[n] < points && b->weights[n] > 0.0f && b->weights[n] <= 1.0f;
      sane &= b->u[n] >= -1e-4f && b->u[n] <= 1.0001f && b->v[n] >= -1e-4f && b->v[n] <= 1.0001f && b->w[n] >= -1e-4f &&
              b->w[n] <= 1.0001f;
      for (size_t m = 0; m < b->carried_count; ++m) sane &= b->carried_points[m] != b->points[n];
    }
    for (size_t m = 0; m < b->carried_count; ++m)
      sane &= b->carried_points[m] < points && b->carried_weights[m] > 0.0f && b->carried_weights[m] <= 1.0f;
    CHECK(sane && real == b->bound_count);
    /* Shared by instances, not copied. */
    deform_character* member = NULL;
    deform_lattice_binding shared;
    CHECK(deform_character_instance(gpu, &member) == DEFORM_OK);
    CHECK(deform_character_lattice_binding(member, l, &shared) == DEFORM_OK);
    CHECK(shared.points == b->points && shared.u == b->u && shared.carried_points == b->carried_points);
    deform_character_destroy(member);
  }
  CHECK(lattices[0].carried_count > 0); /* the upper arm carries the forearm and the hand */

  /* The model's size: the diagonal of its bind positions' box. */
  double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
  for (size_t p = 0; p < points; ++p)
    for (int r = 0; r < 3; ++r)
      lo[r] = fmin(lo[r], skin.positions[3 * p + r]), hi[r] = fmax(hi[r], skin.positions[3 * p + r]);
  const double size =
      sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
  CHECK(size > 1.0 && size < 5.0);

  /* A bent pose (spine, neck, legs and the right arm, each about a random axis), the same for both. */
  float* rotations = malloc(4 * bones * sizeof(float));
  float* translations = malloc(3 * bones * sizeof(float));
  CHECK(deform_character_bind_pose(gpu, rotations, translations, bones) == DEFORM_OK);
  const char* bent[] = {"spine", "neck", "thigh_l", "shin_r", "upperarm_r", "forearm_r"};
  bend_randomly(gpu, rotations, bent, sizeof bent / sizeof *bent, 0.2, 0.5);
  /* Gravity on every lattice's control points makes the fields bend, not only stretch along the bone. */
  const float gravity[3] = {0.0f, -9.81f, 0.0f};
  const float target[3] = {1.6f, 1.5f, 0.3f};
  deform_character* both[2] = {cpu, gpu};
  for (int i = 0; i < 2; ++i) {
    CHECK(deform_character_set_lattice_motion(both[i], DEFORM_ALL_LATTICES, 1.0f, gravity, 1.0f) == DEFORM_OK);
    CHECK(deform_character_set_pose(both[i], rotations, translations, bones) == DEFORM_OK);
    CHECK(deform_character_update(both[i], 1.0f / 60.0f) == DEFORM_OK); /* both deform once */
  }
  CHECK(deform_character_set_deform_on_cpu(gpu, 0) == DEFORM_OK);
  float* held = malloc(3 * points * sizeof(float));
  CHECK(deform_character_copy_positions(gpu, held, 3 * points) == DEFORM_OK);
  const size_t vertices = deform_character_vertex_count(gpu);
  float* held_normals = malloc(3 * vertices * sizeof(float));
  memcpy(held_normals, deform_character_normals(gpu), 3 * vertices * sizeof(float));
  for (int i = 0; i < 2; ++i)
    CHECK(deform_character_reach(both[i], deform_character_find_bone(both[i], "hand_l"), target, NULL) == DEFORM_OK);

  /* The bound: the CPU sums in float, these loops in double; the terms (points and displacements about the model's
   * size, 64 Bernstein terms a tricubic lattice, four matrices a point) round at a few 1e-7 of the size, so 1e-5 of it
   * leaves room for another CPU's fused multiply-adds and stays far below what a mistake moves (a lattice's field or
   * carried translation here: several percent of the size). */
  const double bound = 1e-5 * size;
  double* shaded = malloc(3 * points * sizeof(double));
  double worst = 0.0, lattices_moved = 0.0;
  int positions_held = 1, actives = 0;
  for (int step = 1; step <= 50; ++step) {
    if (step == 30)
      for (int i = 0; i < 2; ++i) deform_character_release(both[i]); /* spring back */
    for (int i = 0; i < 2; ++i) CHECK(deform_character_update(both[i], 1.0f / 60.0f) == DEFORM_OK);
    positions_held &= memcmp(deform_character_positions(gpu), held, 3 * points * sizeof(float)) == 0;
    positions_held &= memcmp(deform_character_normals(gpu), held_normals, 3 * vertices * sizeof(float)) == 0;
    const double moved = deform_like_a_shader(gpu, &skin, lattices, lattice_count, shaded);
    lattices_moved = fmax(lattices_moved, moved);
    const double gap = gap_to(cpu, shaded, points);
    worst = fmax(worst, gap);
    if (step == 3 || step == 12 || step == 30 || step == 50) {
      for (size_t l = 0; l < lattice_count; ++l) {
        CHECK(deform_character_lattice_frame(gpu, l, &frame) == DEFORM_OK);
        actives += frame.active != 0;
      }
      printf("GPU route, update %d: largest gap %.3g of the size (bound 1e-5), lattices move points by %.3g\n", step,
             gap / size, moved / size);
    }
  }
  CHECK(worst < bound);
  CHECK(lattices_moved > 0.02 * size); /* the stretch is in the comparison */
  CHECK(actives == 4 * (int)lattice_count);
  CHECK(positions_held); /* posing only: the last deforming update's points and normals stay */

  /* Deforming on the CPU again, the twin's next update is the first one's to the bit: posing kept the same state. */
  CHECK(deform_character_set_deform_on_cpu(gpu, 1) == DEFORM_OK);
  for (int i = 0; i < 2; ++i) CHECK(deform_character_update(both[i], 1.0f / 60.0f) == DEFORM_OK);
  CHECK(memcmp(deform_character_positions(gpu), deform_character_positions(cpu), 3 * points * sizeof(float)) == 0);

  /* A level without deformers runs no lattice: none is active, though the springs still swing, and the skin alone is
   * the first one's at that level. */
  const deform_level levels[2] = {{0, 1, 1, NULL, 0}, {bones, 0, 1, NULL, 0}};
  for (int i = 0; i < 2; ++i) {
    CHECK(deform_character_set_levels(both[i], levels, 2, NULL, NULL, 0, 0) == DEFORM_OK);
    CHECK(deform_character_set_level(both[i], 1) == DEFORM_OK);
  }
  CHECK(deform_character_set_deform_on_cpu(gpu, 0) == DEFORM_OK);
  for (int step = 0; step < 3; ++step)
    for (int i = 0; i < 2; ++i) CHECK(deform_character_update(both[i], 1.0f / 60.0f) == DEFORM_OK);
  int none_active = 1;
  for (size_t l = 0; l < lattice_count; ++l) {
    CHECK(deform_character_lattice_frame(gpu, l, &frame) == DEFORM_OK);
    none_active &= frame.active == 0;
  }
  CHECK(none_active);
  CHECK(deform_like_a_shader(gpu, &skin, lattices, lattice_count, shaded) == 0.0);
  CHECK(gap_to(cpu, shaded, points) < bound);

  free(shaded);
  free(held);
  free(held_normals);
  free(rotations);
  free(translations);
  deform_character_destroy(cpu);
  deform_character_destroy(gpu);
}

int main(void) {
  CHECK(strlen(deform_version()) >= 5);
  CHECK(strcmp(deform_last_error(), "") == 0);
  character_reaches_stretches_and_springs_back();
  loading_errors_name_the_file();
  files_outside_the_model_folder_are_refused();
  builtin_clips_play();
  imported_model_plays_its_clips();
  skinning_matches_a_plain_reference();
  lattice_matches_trilinear_interpolation();
  delta_mush_smooths_a_bent_elbow();
  character_direct_delta_mush();
  direct_delta_mush_keeps_rest_and_rigid_motion();
  corrective_driven_by_the_elbow();
  render_mesh_normals_and_instances();
  levels_of_detail();
  gpu_route_reproduces_the_cpu();
  if (failures) {
    fprintf(stderr, "%d checks failed\n", failures);
    return 1;
  }
  printf("C API: every check passed\n");
  return 0;
}
