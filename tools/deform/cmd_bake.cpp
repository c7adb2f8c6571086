// deform bake: a deformation over time as glTF 2.0 that any glTF viewer plays (docs/cli.md, docs/gltf-export.md):
// morph targets, one per frame, or (--as bones) a skinning decomposition into extra bones. Two sources: the
// reach-stretch-release `deform simulate` runs (or a clip with its jiggle), and a Bézier FFD growing from rest to its
// full displacement.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <vector>

#include "cli.hpp"
#include "model_loader.hpp"
#include "shared_steps.hpp"
#include "model_loading.hpp"
#include "deform/character/character.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/io/lattice_json.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/io/text.hpp"
#include "deform/offline/lattice_binding.hpp"
#include "deform/offline/rig.hpp"
#include "deform/offline/skinning_decomposition.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/model.hpp"
#include "deform/version.hpp"

namespace cli {
namespace {

using Json = nlohmann::json;

constexpr const char* usage =
    "usage: deform bake (--builtin | MODEL | RIG) [--rig FILE] (--target X,Y,Z | --clip NAME | both)\n"
    "                   [--release-at T] [--inertia F] [--seconds S] [--fps F] [--dt DT]\n"
    "                   [--as morphs | --as bones [--max-bones N] [--influences 4|8]] --out FILE.(gltf|glb)\n"
    "       deform bake MESH.obj --lattice L.json [--seconds S] [--fps F] --out FILE.(gltf|glb)\n"
    "\n"
    "The files a RIG or MESH names are read only from its folder, or a folder --allow-outside DIR (repeatable)\n"
    "names (docs/security.md).\n"
    "Writes a deformation over time as glTF 2.0 that any glTF viewer plays: the mesh at its bind pose plus one morph\n"
    "target per frame (sparse: only the vertices that move), and one animation whose weights show frame k at k/F\n"
    "seconds and blend neighbouring frames linearly in between (docs/gltf-export.md). With --as bones, the same "
    "motion\n"
    "as ordinary skeletal animation instead: the model's bones with their motion, plus at most N extra bones, each "
    "the\n"
    "child of a body bone, whose motion and weights (on the points the deformers move; the others keep theirs) a\n"
    "skinning decomposition fits to the frames, so that any engine plays, blends and retimes it.\n"
    "\n"
    "  --builtin | MODEL | RIG   what `deform simulate` runs, with the same rig, target, clip and release: the\n"
    "                       built-in character, any model (an import, or MESH.obj --skeleton S.sk --weights W.skw)\n"
    "                       with its default rig or --rig FILE, or a rig file naming its model; frame 0 is t = 0,\n"
    "                       the mesh's bind pose is the glTF's rest shape\n"
    "  --target X,Y,Z       world-space target of the rig's reach effector\n"
    "  --clip NAME          play this clip of the model (the built-in character's idle, walk, run, wave; an\n"
    "                       import's own), the rig's lattices and spring chains jiggling with it; the animation\n"
    "                       is named after the clip. With --as bones it repeats: each clip is played from the\n"
    "                       bind pose and the file holds one skin and an animation per clip\n"
    "  MESH.obj --lattice L.json   the FFD of `deform ffd`, its displacements scaled from 0 (frame 0) to 1 (the\n"
    "                       last frame, which is `deform ffd`'s output)\n"
    "  --seconds S          length (default: the clip's duration for --clip alone, 3 for a reach, 1 for an FFD);\n"
    "                       frames at 0, 1/F, ..., S\n"
    "  --fps F              frames per second, in (0, 240] (default 30); at most 1000 frames\n"
    "  --dt DT              largest simulation step, seconds (default 1/60); frames and the release split steps\n"
    "  --release-at T       seconds after the reach when the stretch is released (default 1.5)\n"
    "  --inertia F          how much the lattices lag behind their bones' motion, in [0, 1], as `deform simulate\n"
    "                       --inertia`: a scale of each lattice's tuned inertia (1 the tuned jiggle, 0 none);\n"
    "                       default: the rig's own (0 in the default and built-in rigs)\n"
    "  --as morphs|bones    what the file holds (default morphs); bones needs a reach or a clip, not an FFD\n"
    "  --max-bones N        --as bones: at most N extra bones, in [0, 1000] (default 24)\n"
    "  --influences 4|8     --as bones: at most this many weights per moved point (default 4; 8 writes JOINTS_1)\n"
    "\n"
    "Prints {\"gltf\": FILE, \"bin\": path or null, \"bytes\", \"frames\", \"fps\", \"render_vertices\",\n"
    "\"seconds\": the bake's wall-clock time}, and \"stored_displacements\" (sparse values over all frames, positions\n"
    "and normals) for morphs, or for bones \"extra_bones\", \"moved_points\", \"iterations\", and \"rms_error\" and\n"
    "\"max_error\": the distance of the bones' skinning from the frames, as fractions of the bounding-box diagonal.\n";

constexpr double max_frames = 1000;

float diagonal(const std::vector<glm::vec3>& points) {
  const deform::Bounds b = deform::compute_bounds(points);
  return glm::length(b.max - b.min);
}

struct Timing {
  double seconds = 0.0;
  double fps = 30.0;
  std::size_t frames = 1;
  double time(std::size_t k) const { return double(k) / fps; }
};

Timing parse_timing(const Args& args, double default_seconds) {
  Timing timing;
  timing.seconds = args.value("--seconds") ? parse_number(*args.value("--seconds"), "--seconds") : default_seconds;
  timing.fps = args.value("--fps") ? parse_number(*args.value("--fps"), "--fps") : 30.0;
  if (!(timing.seconds >= 0.0)) throw UsageError("--seconds must be >= 0");
  if (!(timing.fps > 0.0) || timing.fps > 240.0) throw UsageError("--fps must be in (0, 240]");
  const double frames = std::floor(timing.seconds * timing.fps + 1e-9) + 1.0;
  if (frames > max_frames) throw UsageError("--seconds * --fps gives more than 1000 frames");
  timing.frames = static_cast<std::size_t>(frames);
  return timing;
}

std::string checked_out(const Args& args) {
  const std::string out = args.required("--out");
  std::string ext = std::filesystem::path(out).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".gltf" && ext != ".glb") throw UsageError("--out must name a .gltf or .glb file");
  return out;
}

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// --as bones and its settings.
struct BonesRequest {
  bool bones = false;
  deform::DecompositionOptions options;
};

BonesRequest parse_bones_request(const Args& args) {
  BonesRequest request;
  if (const auto as = args.value("--as")) {
    if (*as != "morphs" && *as != "bones") throw UsageError("--as must be morphs or bones");
    request.bones = *as == "bones";
  }
  if (!request.bones && (args.has("--max-bones") || args.has("--influences")))
    throw UsageError("--max-bones and --influences belong to --as bones");
  if (const auto n = args.value("--max-bones")) {
    const double bones = parse_number(*n, "--max-bones");
    if (!(bones >= 0.0 && bones <= 1000.0) || bones != std::floor(bones))
      throw UsageError("--max-bones must be a whole number in [0, 1000]");
    request.options.max_bones = static_cast<std::size_t>(bones);
  }
  if (const auto n = args.value("--influences")) {
    if (*n != "4" && *n != "8") throw UsageError("--influences must be 4 or 8");
    request.options.influences = *n == "4" ? 4 : 8;
  }
  return request;
}

deform::GltfExportOptions export_options(const std::string& texture_root, const deform::ReferencePolicy& references) {
  deform::GltfExportOptions options;
  options.texture_root = texture_root;
  options.references = references;
  options.generator = "libdeform " DEFORM_VERSION_STRING;
  return options;
}

Json written_json(const deform::GltfWritten& written, const Timing& timing) {
  for (const std::string& w : written.warnings) note(w);
  return Json{{"gltf", written.gltf},   {"bin", written.bin.empty() ? Json(nullptr) : Json(written.bin)},
              {"bytes", written.bytes}, {"frames", timing.frames},
              {"fps", timing.fps},      {"render_vertices", written.vertices}};
}

// `texture_root`: the only folder textures are embedded from (the mesh's own); empty: none. Textures the model holds
// in memory (Material::diffuse_image) are embedded whatever it says.
int write_morphs(const std::string& out, const deform::Model& model, const deform::BakedFrames& baked,
                 const Timing& timing, const deform::GltfExportOptions& base, Clock::time_point start) {
  deform::GltfExportOptions options = base;
  options.baked = &baked;
  const deform::GltfWritten written = deform::write_gltf(out, model, options);
  Json json = written_json(written, timing);
  json["stored_displacements"] = written.sparse_values;
  json["seconds"] = seconds_since(start);
  print_json(json);
  return exit_ok;
}

// The frames as bones: the decomposition's skeleton, weights and clips on the rest mesh.
int write_bones(const std::string& out, deform::Model model, const std::vector<deform::DecompositionFrames>& clips,
                const BonesRequest& request, const Timing& timing, const deform::GltfExportOptions& base,
                Clock::time_point start) {
  deform::SkinningDecomposition fitted = deform::decompose_skinning(model, clips, request.options);
  model.skeleton = std::move(fitted.skeleton);
  model.weights = std::move(fitted.weights);
  deform::GltfExportOptions options = base;
  options.clips = fitted.clips;
  const deform::GltfWritten written = deform::write_gltf(out, model, options);
  Json json = written_json(written, timing);
  json["frames"] = fitted.frame_max_error.size();  // over every clip
  json["extra_bones"] = fitted.extra_bones;
  json["moved_points"] = fitted.moved_points.size();
  json["iterations"] = fitted.iterations;
  json["rms_error"] = fitted.rms_error;
  json["max_error"] = fitted.max_error;
  json["seconds"] = seconds_since(start);
  print_json(json);
  return exit_ok;
}

// One motion to bake: a clip or none, a reach or none, and how the simulation steps.
struct Motion {
  const deform::Animation* clip = nullptr;
  std::optional<glm::vec3> target;
  std::int32_t effector = -1;
  double release_at = 1.5;
  double dt = 1.0 / 60.0;
  Timing timing;
};

// Runs `character`, fresh at its bind pose, through the motion as `deform simulate` does, calling keep(k) with the
// character at frame k: t = 0 is just after the reach, and the release happens at its time whatever the steps (a
// step that crosses it is split there). The pose at time t is the clip's, moving as it does (ClipPlayer), then the
// reach on top.
void play_motion(deform::Character& character, const Motion& motion, const std::function<void(std::size_t)>& keep) {
  std::optional<ClipPlayer> player;
  if (motion.clip != nullptr) player.emplace(character, *motion.clip);
  bool reaching = motion.target.has_value();
  const auto pose_at = [&](double t) {
    if (player) player->set(t);
    if (reaching && !character.reach(motion.effector, *motion.target).status)
      throw UsageError("cannot reach for that target with bone '" + character.skeleton().key(motion.effector) + "'");
  };
  const auto advance = [&](double step, double t) {
    if (motion.clip != nullptr) pose_at(t);
    if (const deform::Status status = character.update(float(step)); !status)
      throw UsageError(std::string("a simulation step was refused: ") + status.reason());
  };
  bool released = !reaching;
  const auto let_go = [&] {
    character.release();
    reaching = false;
    released = true;
  };
  const double snap = 1e-9 * motion.dt;
  pose_at(0.0);
  if (!released && motion.release_at <= snap) let_go();
  if (const deform::Status status = character.update(0.0f); !status)
    throw UsageError(std::string("the first pose was refused: ") + status.reason());
  keep(0);
  double now = 0.0;
  for (std::size_t k = 1; k < motion.timing.frames; ++k) {
    const double t = motion.timing.time(k);
    while (now < t - snap) {
      double next = std::min(t, now + motion.dt);
      if (!released && motion.release_at > now + snap && motion.release_at < next - snap) next = motion.release_at;
      advance(next - now, next);
      now = next;
      if (!released && motion.release_at <= now + snap) let_go();
    }
    now = t;
    keep(k);
  }
}

int bake_animated(const Args& args) {
  const Clock::time_point start = Clock::now();
  const std::string out = checked_out(args);
  BonesRequest request = parse_bones_request(args);
  const auto target_text = args.value("--target");
  const std::vector<std::string> clip_names = args.values("--clip");
  if (!target_text && clip_names.empty())
    throw UsageError("give --target, --clip or both (or MESH.obj --lattice L.json)");
  if (clip_names.size() > 1 && !request.bones)
    throw UsageError("several --clip bake together only --as bones (one skin, an animation per clip)");
  for (std::size_t i = 0; i < clip_names.size(); ++i)
    if (std::count(clip_names.begin(), clip_names.end(), clip_names[i]) > 1)
      throw UsageError("--clip " + clip_names[i] + " is given twice");
  Motion motion;
  if (target_text) motion.target = parse_vec3(*target_text, "--target");
  if (args.value("--release-at")) motion.release_at = parse_number(*args.value("--release-at"), "--release-at");
  if (args.value("--dt")) motion.dt = parse_number(*args.value("--dt"), "--dt");
  if (!(motion.dt > 0.0) || motion.dt > 10.0) throw UsageError("--dt must be in (0, 10] seconds");

  RiggedModel rigged = load_rigged_model(args);
  embed_builtin_texture(rigged.loaded);
  const deform::Model model = std::move(rigged.loaded.model);
  deform::Rig rig = std::move(rigged.rig);
  apply_inertia_option(args, rig);
  const std::vector<deform::Animation> clips = std::move(rigged.loaded.clips);
  motion.effector = rig.reach_effector;
  if (target_text && motion.effector <= 0) throw UsageError("the rig has no reach effector");
  // Each motion: a clip alone lasts its own length (once round a loop); a reach, 3 s.
  std::vector<Motion> motions;
  for (const std::string& name : clip_names) {
    motions.push_back(motion);
    motions.back().clip = &find_clip_or_fail(clips, name);
  }
  if (motions.empty()) motions.push_back(motion);
  for (Motion& m : motions) {
    m.timing = parse_timing(args, m.clip != nullptr && !target_text ? double(m.clip->duration) : 3.0);
    if (m.timing.seconds / m.dt > 1e6) throw UsageError("--seconds / --dt gives more than 1000000 steps");
  }

  deform::Model rest = model;  // the glTF's rest shape: bind positions, the normals the character computes there
  deform::Character character(model, rig);
  if (!character.update(0.0f)) throw std::runtime_error("internal error: the bind pose did not deform");
  const std::span<const glm::vec3> bind_normals = character.normals();
  rest.mesh.vertex_normals.assign(bind_normals.begin(), bind_normals.end());
  deform::GltfExportOptions options = export_options(rigged.texture_root, reference_policy(args));
  options.up = rigged.loaded.up;
  const auto name_of = [](const Motion& m) { return m.clip != nullptr ? m.clip->name : std::string("reach"); };

  if (request.bones) {
    // The extra bones start from the lattices' slices, where the rubber moves the points. Each motion starts from
    // a fresh character, as the file's clips each start from the bind pose.
    request.options.seeds = deform::decomposition_seeds(character.deformers(), character.skeleton());
    std::vector<deform::DecompositionFrames> recorded(motions.size());
    for (std::size_t i = 0; i < motions.size(); ++i) {
      deform::Character actor = i == 0 ? std::move(character) : deform::Character(model, rig);
      deform::DecompositionFrames& frames = recorded[i];
      frames.name = name_of(motions[i]);
      play_motion(actor, motions[i], [&](std::size_t k) {
        const std::span<const glm::mat4> palette = actor.palette(), bind = actor.skeleton().bind_world();
        std::vector<glm::mat4>& world = frames.bone_world.emplace_back(palette.size());
        for (std::size_t b = 0; b < palette.size(); ++b) world[b] = palette[b] * bind[b];
        frames.times.push_back(float(motions[i].timing.time(k)));
        frames.positions.emplace_back(actor.positions().begin(), actor.positions().end());
      });
    }
    return write_bones(out, std::move(rest), recorded, request, motions[0].timing, options, start);
  }
  deform::BakedFrames baked;
  baked.name = name_of(motions[0]);
  baked.position_tolerance = 1e-6f * diagonal(rest.mesh.positions);
  baked.normal_tolerance = 1e-5f;
  play_motion(character, motions[0], [&](std::size_t k) {
    baked.times.push_back(float(motions[0].timing.time(k)));
    baked.positions.emplace_back(character.positions().begin(), character.positions().end());
    const std::span<const glm::vec3> normals = character.normals();
    baked.normals.emplace_back(normals.begin(), normals.end());
  });
  return write_morphs(out, rest, baked, motions[0].timing, options, start);
}

int bake_ffd(const Args& args) {
  const Clock::time_point start = Clock::now();
  const std::string out = checked_out(args);
  if (parse_bones_request(args).bones)
    throw UsageError("--as bones needs a rigged model (a reach or a clip); an FFD bakes as morphs");
  if (args.positionals().size() != 1) throw UsageError("an FFD bake takes exactly one MESH.obj");
  for (const char* flag : {"--builtin", "--target", "--clip", "--release-at", "--dt", "--rig", "--inertia"})
    if (args.has(flag)) throw UsageError(std::string(flag) + " belongs to a reach bake, not an FFD (--lattice)");
  const Timing timing = parse_timing(args, 1.0);
  const std::string mesh_path = args.positionals()[0];
  const std::string lattice_path = args.required("--lattice");

  deform::Warnings warnings;
  deform::Model model;
  model.mesh = deform::read_obj(mesh_path, &warnings, reference_policy(args));
  for (const std::string& w : warnings.messages) note(w);
  model.name = std::filesystem::path(mesh_path).stem().string();
  const deform::Mesh& mesh = model.mesh;
  const deform::LatticeDocument doc = deform::read_lattice_json(lattice_path, mesh.point_count());
  const deform::BezierLattice& displaced = doc.lattice;
  const deform::BezierLattice rest(displaced.frame(), displaced.degree(), lattice_path);
  const deform::LatticeBinding binding = doc.has_vertices ? deform::bind_lattice(rest, mesh.positions, doc.vertices)
                                                          : deform::bind_lattice(rest, mesh.positions);
  std::vector<bool> deformed(mesh.point_count(), false);
  for (const std::uint32_t p : binding.vertices)
    if (p != deform::LatticeBinding::no_vertex) deformed[p] = true;

  deform::BakedFrames baked;
  baked.name = "ffd";
  baked.position_tolerance = 0.0f;  // a point outside the lattice is copied, to the bit
  baked.normal_tolerance = 0.0f;
  deform::BezierLattice current = rest;
  const std::span<const glm::vec3> from = rest.control_points(), to = displaced.control_points();
  for (std::size_t k = 0; k < timing.frames; ++k) {
    // s = 1 on the last frame exactly: the displaced lattice itself, so that frame is `deform ffd`'s output.
    const float s = timing.frames == 1 ? 1.0f : float(double(k) / double(timing.frames - 1));
    const std::span<glm::vec3> points = current.control_points();
    for (std::size_t i = 0; i < points.size(); ++i)
      points[i] = k + 1 == timing.frames ? to[i] : from[i] + s * (to[i] - from[i]);
    std::vector<glm::vec3> positions = mesh.positions;
    deform::LatticeEvaluateJob job;
    job.binding = &binding;
    job.control_points = current.control_points();
    job.positions = positions;
    if (!job.run()) throw std::runtime_error("internal error: the lattice evaluation rejected its arguments");
    baked.times.push_back(float(timing.time(k)));
    baked.positions.push_back(std::move(positions));
    baked.normals.push_back(ffd_normals(mesh, current, deformed));
  }
  const std::string folder = std::filesystem::path(mesh_path).parent_path().lexically_normal().string();
  return write_morphs(out, model, baked, timing, export_options(folder.empty() ? "." : folder, reference_policy(args)),
                      start);
}

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = {"--target",  "--clip", "--release-at", "--seconds",
                                          "--fps",     "--dt",   "--lattice",    "--out",
                                          "--inertia", "--as",   "--max-bones",  "--influences"};
  value_flags.insert(value_flags.end(), rig_value_flags.begin(), rig_value_flags.end());
  const Args args(argv, value_flags, {"--builtin"});
  if (args.help()) {
    std::cout << usage;
    return exit_ok;
  }
  return args.has("--lattice") ? bake_ffd(args) : bake_animated(args);
}

}  // namespace

const Command bake_command = {"bake", "write a simulation or an FFD as a glTF morph-target animation", usage, run};

}  // namespace cli
