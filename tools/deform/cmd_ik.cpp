// deform ik: solve a bone chain toward a target point (docs/cli.md, docs/cli.md).
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "shared_steps.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/pose_json.hpp"
namespace cli {
namespace {

std::int32_t find_bone(const deform::Skeleton& skeleton, const std::string& name, std::string_view flag) {
  const std::int32_t id = skeleton.find(name);
  if (id < 0) throw UsageError(std::string(flag) + ": no bone named '" + name + "'");
  return id;
}

// What deform ik solves for: a skeleton alone (S.sk) names its bones; any model, or a rig, also brings a rig whose
// reach chain is the default.
struct IkSubject {
  deform::Skeleton skeleton;
  deform::Rig rig;
};

IkSubject load_ik_subject(const Args& args) {
  const bool skeleton_only =
      args.positionals().size() == 1 && std::filesystem::path(args.positionals()[0]).extension() == ".sk";
  IkSubject subject;
  if (skeleton_only) {
    const std::string& path = args.positionals()[0];
    if (args.has("--builtin")) throw UsageError("--builtin takes no skeleton file (got '" + path + "')");
    const std::string kind = describe_file(path);
    if (kind != "a skeleton (.sk)" && kind != "a file that cannot be read")
      throw deform::Error::in_file(path, "", "expected a skeleton (.sk), got " + kind);
    if (args.has("--rig")) throw UsageError("--rig needs the model it rigs, not a skeleton alone");
    if (!args.has("--effector")) throw UsageError("--effector is required with a skeleton alone (S.sk)");
    subject.skeleton = deform::read_sk(path);
  } else {
    RiggedModel rigged = load_rigged_model(args, !args.has("--effector"));
    subject.skeleton = std::move(rigged.loaded.model.skeleton);
    subject.rig = std::move(rigged.rig);
  }
  return subject;
}

// deform ik's options, checked in the order the usage errors are reported.
struct IkOptions {
  std::int32_t effector = -1, root = 0;
  glm::vec3 target{0.0f};
  std::string solver;  // ccd, fabrik or two-bone
  std::optional<glm::vec3> pole;
  float soften = 0.0f, max_stretch = 1.0f, swivel = 0.0f;  // the two-bone solver's
  deform::IkSettings settings;                             // its tolerance set with the chain (ik_chain)
  bool swing_twist = false;
  bool stretch_given = false;  // --stretch: the report says the stretch
};

IkOptions ik_options(const Args& args, const IkSubject& subject) {
  const deform::Skeleton& skeleton = subject.skeleton;
  IkOptions o;
  // Without --effector: the rig's reach chain (effector, and root unless --root says).
  if (const auto name = args.value("--effector")) {
    o.effector = find_bone(skeleton, *name, "--effector");
  } else {
    o.effector = subject.rig.reach_effector;
    if (o.effector < 0) throw UsageError("the rig has no reach effector: give --effector NAME");
    if (subject.rig.reach_root >= 0) o.root = subject.rig.reach_root;
  }
  if (const auto name = args.value("--root")) o.root = find_bone(skeleton, *name, "--root");
  o.target = parse_vec3(args.required("--target"), "--target");
  o.solver = args.value("--solver").value_or("ccd");
  if (o.solver != "ccd" && o.solver != "fabrik" && o.solver != "two-bone")
    throw UsageError("--solver: '" + o.solver + "' is not ccd, fabrik or two-bone");
  // The two-bone solver's rig settings (TwoBoneIkJob); of them the chain solvers take only the pole (IkJob::pole).
  for (const char* flag : {"--soften", "--stretch", "--swivel"})
    if (args.value(flag) && o.solver != "two-bone")
      throw UsageError(std::string(flag) + ": applies to --solver two-bone only");
  if (args.value("--pole")) o.pole = parse_vec3(*args.value("--pole"), "--pole");
  auto number_in = [&](const char* flag, double low, double high, const char* range, double fallback) {
    const auto text = args.value(flag);
    if (!text) return static_cast<float>(fallback);
    const double value = parse_number(*text, flag);
    if (!(value >= low && value <= high)) throw UsageError(std::string(flag) + ": '" + *text + "' is not " + range);
    return static_cast<float>(value);
  };
  o.soften = number_in("--soften", 0.0, 1.0, "within [0, 1]", 0.0);
  o.max_stretch = number_in("--stretch", 1.0, 1e6, "within [1, 1e6]", 1.0);
  o.swivel = number_in("--swivel", -360.0, 360.0, "within [-360, 360] degrees", 0.0);
  o.stretch_given = args.value("--stretch").has_value();
  o.settings.max_iterations = 100;
  if (auto n = args.value("--max-iterations"))
    o.settings.max_iterations = static_cast<int>(parse_integer(*n, "--max-iterations", 1, 1000000));
  const std::string limits = args.value("--limits").value_or("euler");
  if (limits != "euler" && limits != "swing-twist")
    throw UsageError("--limits: '" + limits + "' is not euler or swing-twist");
  o.swing_twist = limits == "swing-twist";
  if (o.swing_twist && o.solver == "two-bone")
    throw UsageError("--limits swing-twist: the two-bone solver has Euler limits only");
  return o;
}

// The chain from the root to the effector (deform::make_chain names the bones if it is not one), with swing-twist
// limits when asked: from the .sk Euler ones, about each joint's bone axis (its child's bind translation), the twist
// range of the nearest coordinate axis and a cone of the other two axes' larger bounds
// (deform::swing_twist_from_euler). Sets the tolerance: --tolerance, else 1e-4 of the chain's length.
deform::IkChain ik_chain(const Args& args, const deform::Skeleton& skeleton, const deform::Pose& pose, IkOptions& o) {
  deform::IkChain chain = deform::make_chain(skeleton, o.root, o.effector);
  if (o.swing_twist)
    for (std::size_t k = 0; k < chain.joint_count(); ++k)
      deform::set_swing_twist(chain, k,
                              deform::swing_twist_from_euler(skeleton.bone(chain.bones[k]).limits,
                                                             skeleton.bone(chain.bones[k + 1]).bind_translation));
  o.settings.tolerance = 1e-4f * deform::chain_length(chain, pose.translations);
  if (auto t = args.value("--tolerance")) {
    const double tolerance = parse_number(*t, "--tolerance");
    if (tolerance < 0.0) throw UsageError("--tolerance: must not be negative");
    o.settings.tolerance = static_cast<float>(tolerance);
  }
  if (o.solver == "two-bone" && chain.joint_count() != 2)
    throw deform::Error::invalid_argument("bone " + std::to_string(o.effector),
                                          "the two-bone solver needs a chain of exactly two joints, '" +
                                              skeleton.key(o.root) + "' has " + std::to_string(chain.joint_count()) +
                                              " above '" + skeleton.key(o.effector) + "'");
  return chain;
}

// The two-bone solve of `pose` (TwoBoneIkJob); without --pole the limb keeps its bind-pose bend plane. The pose's
// bones then carry the stretch, so that FK of them reaches the target.
deform::Status solve_two_bone(const deform::IkChain& chain, const deform::RigidTransform& base, const IkOptions& o,
                              deform::Pose& pose, deform::IkResult& result, float& stretch) {
  std::vector<glm::vec3> stretched = pose.translations;
  deform::TwoBoneIkJob job;
  job.chain = &chain;
  job.base = base;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.target = o.target;
  if (o.pole) {
    job.pole = *o.pole;
    job.pole_kind = deform::PoleKind::point;
  }
  job.swivel_degrees = o.swivel;
  job.soften = o.soften;
  job.max_stretch = o.max_stretch;
  job.tolerance = o.settings.tolerance;
  job.stretched_translations = stretched;
  job.result = &result;
  job.stretch = &stretch;
  if (const deform::Status valid = job.validate(); !valid)
    throw deform::Error::invalid_argument("bone " + std::to_string(o.effector),
                                          std::string("two-bone solve: ") + valid.reason());
  const deform::Status solved = job.run();
  pose.translations = stretched;
  return solved;
}

// The CCD or FABRIK solve of `pose` (IkJob).
deform::Status solve_chain(const deform::IkChain& chain, const deform::RigidTransform& base, const IkOptions& o,
                           deform::Pose& pose, deform::IkResult& result) {
  std::vector<std::byte> scratch(deform::IkJob::scratch_size(chain.joint_count()));
  deform::IkJob job;
  job.method = o.solver == "fabrik" ? deform::IkMethod::fabrik : deform::IkMethod::ccd;
  job.chain = &chain;
  job.base = base;
  job.rotations = pose.rotations;
  job.translations = pose.translations;
  job.target = o.target;
  job.settings = o.settings;
  job.scratch = scratch;
  job.result = &result;
  if (o.pole) job.pole = *o.pole, job.use_pole = true;
  return job.run();
}

// Reports what the printed angles give: read back as `deform skin --pose` will, and that pose measured. Swing-twist
// joints may leave the .sk's Euler box (a cone is another shape): printed exactly, read back unclamped
// (`deform skin --pose P --no-limits`).
void print_ik_report(const deform::Skeleton& skeleton, const deform::IkChain& chain, const deform::Pose& pose,
                     const IkOptions& o, const deform::IkResult& result, float stretch) {
  const std::string bones = deform::format_pose_bones_json(skeleton, pose, chain.bones, !o.swing_twist);
  const deform::Pose printed = deform::parse_pose_json("{\"bones\": " + bones + "}", skeleton, !o.swing_twist);
  glm::vec3 reached_point(0.0f);
  if (const deform::Status status =
          deform::effector_position(chain, printed.rotations, printed.translations, reached_point);
      !status)
    throw deform::Error::invalid_argument("the printed pose", status.reason());
  const float distance = glm::length(reached_point - o.target);

  nlohmann::ordered_json out;
  out["solver"] = o.solver;
  out["reached"] = distance <= o.settings.tolerance;
  out["distance"] = distance;
  out["iterations"] = result.iterations;
  if (o.stretch_given) out["stretch"] = stretch;
  out["effector"] = to_json(reached_point);
  out["bones"] = nlohmann::ordered_json::parse(bones);
  print_json_in_order(out);
}

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = {"--effector",       "--target",    "--root",   "--solver",
                                          "--max-iterations", "--tolerance", "--limits", "--pole",
                                          "--soften",         "--stretch",   "--swivel"};
  value_flags.insert(value_flags.end(), rig_value_flags.begin(), rig_value_flags.end());
  const Args args(argv, value_flags, {"--builtin"});
  const IkSubject subject = load_ik_subject(args);
  const deform::Skeleton& skeleton = subject.skeleton;
  IkOptions o = ik_options(args, subject);

  deform::Pose pose = skeleton.bind_pose();
  const deform::IkChain chain = ik_chain(args, skeleton, pose, o);
  deform::RigidTransform base;
  deform::IkResult result;
  deform::Status solved = deform::chain_base(chain, pose.rotations, pose.translations, base);
  float stretch = 1.0f;
  if (solved && o.solver == "two-bone") solved = solve_two_bone(chain, base, o, pose, result, stretch);
  else if (solved) solved = solve_chain(chain, base, o, pose, result);
  if (!solved) throw UsageError("the target or a setting is not valid");
  print_ik_report(skeleton, chain, pose, o, result, stretch);
  return exit_ok;
}

}  // namespace

const Command ik_command = {
    "ik", "solve inverse kinematics for a bone chain",
    "usage: deform ik (--builtin | MODEL | RIG | S.sk) [--rig FILE] --target X,Y,Z [--effector NAME] [--root NAME]\n"
    "                 [--solver ccd|fabrik|two-bone] [--max-iterations N] [--tolerance T]\n"
    "                 [--limits euler|swing-twist] [--pole X,Y,Z] [--soften F] [--stretch MAX] [--swivel DEGREES]\n\n"
    "Moves the chain from --root to --effector, starting from the bind pose and within the DOF limits, so that the\n"
    "effector's head reaches the target (world coordinates).\n"
    "  --builtin | MODEL   the built-in character, any model `deform skin` takes (an import, or MESH.obj\n"
    "                      --skeleton S.sk --weights W.skw), a rig file naming its model (RIG.json), or a skeleton\n"
    "                      alone (S.sk, with --effector)\n"
    "  --rig FILE          the model's rig (default: its default rig; the built-in character's: clavicle_l -> hand_l)\n"
    "  --effector NAME     the chain's last bone (default: the rig's reach effector, with its root)\n"
    "  --root NAME         the chain's first bone (default: the rig's reach root without --effector, else the\n"
    "                      skeleton root)\n"
    "  --solver            ccd (default), fabrik, or two-bone (a chain of exactly two joints, closed form)\n"
    "  --max-iterations N  sweeps or passes, default 100\n"
    "  --tolerance T       reached when |effector - target| <= T, default 1e-4 x the chain length\n"
    "  --limits KIND       euler (default): the .sk's per-axis Euler limits; swing-twist (ccd, fabrik): per joint a\n"
    "                      twist range about the bone axis and a swing cone, derived from the Euler limits; the\n"
    "                      angles are then printed unclamped, for `deform skin --pose P --no-limits`\n"
    "  --pole X,Y,Z        a world point the chain's middle bends toward (default: the bind pose's bend plane)\n"
    "two-bone only (exit 2 with another solver):\n"
    "  --soften F          0..1: approach full extension softly over that fraction of the reach, default 0\n"
    "  --stretch MAX       >= 1: the bones may lengthen up to MAX times to reach; prints \"stretch\", default 1\n"
    "  --swivel DEGREES    -360..360: turn of the bend plane about root -> target, default 0\n"
    "Prints {\"solver\", \"reached\", \"distance\", \"iterations\", (\"stretch\",) \"effector\": [x, y, z], \"bones\": "
    "{...}}; `bones`\n"
    "holds every chain bone's local rotation (Euler degrees) and translation, ready for `deform skin --pose`.\n"
    "An unreachable target is not an error: the closest pose found, \"reached\": false.\n",
    run};

}  // namespace cli
