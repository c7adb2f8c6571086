// deform simulate (--builtin | RIG): reach for a target, hold, release, settle — or play a clip, the lattices and
// spring chains jiggling with it, or both; the effector and stretch over time.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "cli.hpp"
#include "model_loader.hpp"
#include "shared_steps.hpp"
#include "model_loading.hpp"
#include "deform/character/character.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/io/text.hpp"
#include "deform/offline/rig.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/model.hpp"
namespace cli {
namespace {

using Json = nlohmann::ordered_json;  // keeps "t" first in each sample, as documented

constexpr const char* usage =
    "usage: deform simulate (--builtin | MODEL | RIG) [--rig FILE] (--target X,Y,Z | --clip NAME | both)\n"
    "                       [--release-at T] [--seconds S] [--dt DT] [--effector BONE] [--integrator exact|verlet]\n"
    "                       [--min-length F] [--volume F] [--inertia F] [--save-rig FILE] [--allow-outside DIR]...\n"
    "\n"
    "The model a RIG names is read only from the rig's folder, or a folder --allow-outside names (docs/security.md).\n"
    "Reaches for the target with the rig's reach chain (IK within the DOF limits, then the chain's elastic lattices\n"
    "stretch to cover what remains), holds, releases at T and lets the stretch spring back; with --clip, plays the\n"
    "clip meanwhile (the reach follows the moving body), the lattices with inertia and the rig's spring chains\n"
    "jiggling with it. Prints\n"
    "{\"dt\": DT, \"samples\": [{\"t\": .., \"effector\": [x, y, z], \"stretch\": ..}, ...]}, one sample per step from "
    "t = 0.\n"
    "\n"
    "  --builtin            the built-in character with its default rig (three lattices on the left arm)\n"
    "  MODEL                any model `deform skin` takes (an import, or MESH.obj --skeleton S.sk --weights W.skw),\n"
    "                       with the default rig for it (deform::default_rig)\n"
    "  RIG                  a rig file (RIG.json, docs/formats.md) whose \"model\" names the model\n"
    "  --rig FILE           the rig for the model given (its \"model\" key is then not used), or alone: as RIG\n"
    "  --target X,Y,Z       world-space target of the effector (metres for the built-in character)\n"
    "  --clip NAME          play this clip of the model from t = 0, looping as the clip says: the built-in\n"
    "                       character (--builtin, or a rig on it) has \"idle\", \"walk\", \"run\" and \"wave\";\n"
    "                       an imported model, its file's clips\n"
    "  --release-at T       seconds after the reach when the stretch is released (default 1.5); a step that\n"
    "                       crosses T is split there\n"
    "  --seconds S          length of the simulation (default 3)\n"
    "  --dt DT              step in seconds (default 1/60)\n"
    "  --effector BONE      effector bone (default: the rig's reach effector)\n"
    "  --integrator NAME    override every lattice's integrator: exact (default) or verlet (the thesis' Verlet)\n"
    "  --min-length F       every lattice shows at least F of its length, in [0, 1) (default: the rig's,\n"
    "                       0.7 unless it says; 0: no floor)\n"
    "  --volume F           volume compensation in [0, 1]: a lattice stretched by s scales across its bone by\n"
    "                       s^(-F/2) (default: the rig's, 1 unless it says: keeps its volume; 0: the plain\n"
    "                       stretch)\n"
    "  --inertia F          how much the lattices lag behind their bones' motion, in [0, 1]: a scale of each\n"
    "                       lattice's tuned inertia, its part's (\"motion.part\" in the rig: an upper arm 0.3,\n"
    "                       a hand 0.2, a foot 0.1, ...), so 1 is the tuned jiggle and 0 none; a lattice with\n"
    "                       no part takes F itself (default: the rig's inertia, 0 unless it says: the lattices\n"
    "                       move only when stretched)\n"
    "  --save-rig FILE      also write the rig as run (these options applied) to FILE, its \"model\" naming the\n"
    "                       model relative to FILE's folder, so that `deform simulate FILE` runs it again\n";

// A value as the float it is reported as, in its shortest form; a non-finite one (a diverged simulation) as 0.
double shortest(double value) { return std::isfinite(value) ? deform::shortest_double(float(value)) : 0.0; }

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = {"--target", "--clip",     "--release-at", "--seconds",
                                          "--dt",     "--effector", "--integrator", "--min-length",
                                          "--volume", "--inertia",  "--save-rig"};
  value_flags.insert(value_flags.end(), rig_value_flags.begin(), rig_value_flags.end());
  const Args args(argv, value_flags, {"--builtin"});
  if (args.help()) {
    std::cout << usage;
    return exit_ok;
  }
  const auto target_text = args.value("--target");
  const auto clip_name = args.value("--clip");
  if (!target_text && !clip_name) throw UsageError("give --target, --clip or both");
  const glm::vec3 target = target_text ? parse_vec3(*target_text, "--target") : glm::vec3(0.0f);
  const double seconds = args.value("--seconds") ? parse_number(*args.value("--seconds"), "--seconds") : 3.0;
  const double release_at =
      args.value("--release-at") ? parse_number(*args.value("--release-at"), "--release-at") : 1.5;
  const double dt = args.value("--dt") ? parse_number(*args.value("--dt"), "--dt") : 1.0 / 60.0;
  if (!(dt > 0.0) || dt > 10.0) throw UsageError("--dt must be in (0, 10] seconds");
  if (!(seconds >= 0.0)) throw UsageError("--seconds must be >= 0");
  if (seconds / dt > 1e6) throw UsageError("--seconds / --dt gives more than 1000000 steps");

  RiggedModel rigged = load_rigged_model(args);
  deform::Model model = std::move(rigged.loaded.model);
  deform::Rig rig = std::move(rigged.rig);
  const std::vector<deform::Animation> clips = std::move(rigged.loaded.clips);
  const deform::Animation* clip = clip_name ? &find_clip_or_fail(clips, *clip_name) : nullptr;
  if (const auto name = args.value("--integrator")) {
    if (*name != "exact" && *name != "verlet") throw UsageError("--integrator must be exact or verlet");
    for (deform::LatticeSpec& spec : rig.lattices) {
      spec.elastic.integrator = *name == "exact" ? deform::Integrator::exact : deform::Integrator::verlet;
    }
  }
  if (const auto text = args.value("--min-length")) {
    const double fraction = parse_number(*text, "--min-length");
    if (!(fraction >= 0.0 && fraction < 1.0)) throw UsageError("--min-length must be in [0, 1)");
    for (deform::LatticeSpec& spec : rig.lattices) spec.shape.min_length_fraction = float(fraction);
  }
  if (const auto text = args.value("--volume")) {
    const double volume = parse_number(*text, "--volume");
    if (!(volume >= 0.0 && volume <= 1.0)) throw UsageError("--volume must be in [0, 1]");
    for (deform::LatticeSpec& spec : rig.lattices) spec.shape.volume = float(volume);
  }
  apply_inertia_option(args, rig);
  std::int32_t effector = rig.reach_effector;
  if (const auto name = args.value("--effector")) {
    effector = model.skeleton.find(*name);
    if (effector < 0) throw UsageError("--effector: no bone named '" + *name + "'");
  }
  if (effector <= 0) throw UsageError("the rig has no reach effector: give --effector BONE");
  // The rig as run, the options above applied, naming its model: `deform simulate FILE` runs it again.
  if (const auto path = args.value("--save-rig")) save_rig(*path, rig, rigged.named, model.skeleton);

  deform::Character character(std::move(model), rig);
  // The pose at time t: the clip's, moving as it does (ClipPlayer), then the reach on top.
  std::optional<ClipPlayer> player;
  if (clip != nullptr) player.emplace(character, *clip);
  bool reaching = target_text.has_value();
  const auto pose_at = [&](double t) {
    if (player) player->set(t);
    if (reaching) {
      const deform::ReachResult reach = character.reach(effector, target);
      if (!reach.status)
        throw UsageError("cannot reach for that target with bone '" + character.skeleton().key(effector) + "'");
    }
  };
  pose_at(0.0);
  if (const deform::Status status = character.update(0.0f); !status)
    throw UsageError(std::string("the first pose was refused: ") + status.reason());
  Json samples = Json::array();
  const auto sample = [&](double t) {
    const glm::vec3 e = character.bone_position(effector);
    samples.push_back({{"t", shortest(t)},
                       {"effector", {shortest(e.x), shortest(e.y), shortest(e.z)}},
                       {"stretch", shortest(character.stretch())}});
  };
  sample(0.0);
  const auto steps = static_cast<long long>(std::llround(seconds / dt));
  const auto advance = [&](double step, double t) {
    if (clip != nullptr) pose_at(t);
    if (const deform::Status status = character.update(float(step)); !status) {
      std::string detail = status.reason();
      for (const deform::LatticeSpec& spec : rig.lattices)
        if (spec.elastic.integrator == deform::Integrator::verlet)
          detail += "; lattice '" + spec.name + "' is stable for --dt below " +
                    std::to_string(deform::verlet_max_step(spec.elastic.oscillator, spec.elastic.verlet_kd));
      throw UsageError("step at t = " + std::to_string(t) + " refused: " + detail);
    }
  };
  // The release happens at T whatever the step: the step that crosses T is split there (the exact integrator's state
  // after h1 then h2 is its state after h1 + h2). A T within a billionth of a step of a step's end counts as that end
  // (n·dt lands a rounding error away from T). The seed's Verlet assumes equal steps, so with a Verlet lattice the
  // release waits for the first step that starts at or after T, as it always did.
  bool split = true;
  for (const deform::LatticeSpec& spec : rig.lattices)
    split = split && spec.elastic.integrator != deform::Integrator::verlet;
  const double snap = 1e-9 * dt;
  bool released = false;
  const auto let_go = [&] {
    character.release();
    reaching = false;
    released = true;
  };
  if (release_at <= snap) let_go();
  for (long long n = 1; n <= steps; ++n) {
    const double start = double(n - 1) * dt;
    const double t = double(n) * dt;
    if (!released && split && release_at < t - snap) {  // here release_at > start + snap: see the end of the loop
      advance(release_at - start, release_at);
      let_go();
      advance(t - release_at, t);
    } else {
      advance(dt, t);
    }
    if (!released && release_at <= t + (split ? snap : 1e-9)) let_go();
    sample(t);
  }
  // One sample per line: a long curve stays readable and greppable.
  require_finite_json(samples);
  std::cout << "{\n  \"dt\": " << Json(shortest(dt)).dump() << ",\n  \"samples\": [";
  for (std::size_t n = 0; n < samples.size(); ++n) std::cout << (n ? ",\n    " : "\n    ") << samples[n].dump();
  std::cout << "\n  ]\n}\n";
  return exit_ok;
}

}  // namespace

const Command simulate_command = {"simulate", "reach, stretch, release: the elastic curve over time", usage, run};

}  // namespace cli
