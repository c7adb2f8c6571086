// deform corrective: a sculpted pose made a pose-space corrective of a rig (docs/skinning.md, "Pose-space
// correctives"): the bind-space shape that gives the sculpt back under linear blend skinning, added to a corrective
// group of the rig, which the rig file then keeps.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "model_loader.hpp"
#include "shared_steps.hpp"
#include "deform/character/character.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/pose_json.hpp"
#include "deform/io/text.hpp"
#include "deform/offline/pose_driver.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/error.hpp"

namespace cli {
namespace {

using Json = nlohmann::json;

constexpr const char* usage =
    "usage: deform corrective (--builtin | MODEL | RIG) [--rig FILE] --pose POSE.json --sculpt SCULPT.obj\n"
    "                         --bones A,B,... [--group NAME] [--name NAME] [--tolerance T] --out RIG.json\n"
    "\n"
    "The files a RIG or MESH names are read only from its folder, or a folder --allow-outside DIR (repeatable)\n"
    "names (docs/security.md).\n"
    "Makes a pose-space corrective: SCULPT.obj is the model at POSE.json as an artist fixed it (the same points in\n"
    "the same order, e.g. `deform skin --pose` output edited), and the shape is the bind-space morph target that\n"
    "gives it back under linear blend skinning at that pose. It joins the corrective group --group (made with the\n"
    "driver bones --bones when the rig has none of that name; default: the bones' names joined by '+'), whose pose\n"
    "driver turns it on near the pose, and the rig (the model's own, or --rig FILE, with its lattices and springs) is\n"
    "written to RIG.json atomically, naming its model.\n"
    "\n"
    "  --bones A,B,...   the driver bones: the pose is read from their rotations\n"
    "  --name NAME       the shape's (morph target's) name (default: the sculpt's file stem)\n"
    "  --tolerance T     points whose delta is within T model units of zero are left out (default 1e-6)\n"
    "\n"
    "Prints {\"rig\", \"group\", \"shape\", \"points\": the points the shape moves, \"shapes\": the group's count,\n"
    "\"max_error\": the largest distance, in model units, from the sculpt to what a character with the written rig\n"
    "gives at the pose}.\n";

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    out.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

int run(const std::vector<std::string>& argv) {
  std::vector<std::string> value_flags = {"--pose", "--sculpt", "--bones", "--group", "--name", "--tolerance", "--out"};
  value_flags.insert(value_flags.end(), rig_value_flags.begin(), rig_value_flags.end());
  const Args args(argv, value_flags, {"--builtin"});
  if (args.help()) {
    std::cout << usage;
    return exit_ok;
  }
  const std::string out = args.required("--out");
  const std::string sculpt_path = args.required("--sculpt");
  const float tolerance =
      args.value("--tolerance") ? float(parse_number(*args.value("--tolerance"), "--tolerance")) : 1e-6f;
  if (!(tolerance >= 0.0f)) throw UsageError("--tolerance must be >= 0");
  RiggedModel rigged = load_rigged_model(args);
  const deform::Model& model = rigged.loaded.model;
  const deform::Skeleton& skeleton = model.skeleton;
  std::vector<std::int32_t> bones;
  for (const std::string& name : split(args.required("--bones"))) {
    const std::int32_t bone = skeleton.find(name);
    if (bone < 0) throw UsageError("--bones: the skeleton has no bone '" + name + "'");
    if (std::find(bones.begin(), bones.end(), bone) != bones.end()) throw UsageError("--bones: '" + name + "' twice");
    bones.push_back(bone);
  }
  const deform::Pose wanted = deform::read_pose_json(args.required("--pose"), skeleton);
  deform::Warnings warnings;
  const deform::Mesh sculpt = deform::read_obj(sculpt_path, &warnings, reference_policy(args));
  for (const std::string& w : warnings.messages) note(w);
  if (sculpt.point_count() != model.mesh.point_count())
    throw UsageError("--sculpt has " + std::to_string(sculpt.point_count()) + " points, the model " +
                     std::to_string(model.mesh.point_count()) + ": it must be the model's mesh, posed and edited");

  // The pose as a character holds it (within the limits), and its skinning: what the shape corrects.
  deform::Rig plain = rigged.rig;
  plain.lattices.clear();  // the lattices do not move points at a still pose, and are not skinning
  plain.correctives.clear();
  deform::Character posed(model, plain);
  if (const deform::Status s = posed.set_pose(wanted); !s) throw UsageError(std::string("--pose: ") + s.reason());
  if (const deform::Status s = posed.update(0.0f); !s) throw UsageError(std::string("--pose: ") + s.reason());
  const std::vector<glm::mat4> palette(posed.palette().begin(), posed.palette().end());
  const std::string name =
      args.value("--name") ? *args.value("--name") : std::filesystem::path(sculpt_path).stem().string();
  const deform::MorphTarget shape = deform::corrective_from_sculpt(model, palette, sculpt.positions, tolerance, name);

  std::string group_name = args.value("--group") ? *args.value("--group") : "";
  if (group_name.empty())
    for (const std::int32_t bone : bones) group_name += (group_name.empty() ? "" : "+") + skeleton.key(bone);
  deform::Rig rig = rigged.rig;
  auto group = std::find_if(rig.correctives.begin(), rig.correctives.end(),
                            [&](const deform::CorrectiveSpec& g) { return g.name == group_name; });
  if (group == rig.correctives.end()) {
    rig.correctives.push_back({group_name, bones, deform::RbfKernel::gaussian, 0.0f, 1.0f, true, {}});
    group = rig.correctives.end() - 1;
  } else if (group->bones != bones) {
    throw UsageError("--group " + group_name + " has other driver bones than --bones");
  }
  for (const deform::CorrectiveSpec& g : rig.correctives)
    for (const deform::CorrectiveShape& s : g.shapes)
      if (s.name == name) throw UsageError("the rig has a corrective shape named '" + name + "' already (--name)");
  deform::CorrectiveShape added{name, {}, shape.points, shape.position_deltas};
  for (const std::int32_t bone : bones)
    added.pose.push_back(
        deform::euler_within_limits(posed.pose().rotations[std::size_t(bone)], skeleton.bone(bone).limits));
  for (const deform::CorrectiveShape& other : group->shapes) {
    bool same = true;
    for (std::size_t j = 0; j < bones.size(); ++j) same = same && glm::length(other.pose[j] - added.pose[j]) < 1e-3f;
    if (same)
      throw UsageError("shape '" + other.name + "' of group " + group_name +
                       " is at this pose already: a group holds one shape per pose (give another --group)");
  }
  group->shapes.push_back(std::move(added));

  // The written rig, checked: a character built with it gives the sculpt back at the pose.
  deform::Character check(model, rig);
  if (const deform::Status s = check.set_pose(posed.pose()); !s) throw UsageError(std::string("--pose: ") + s.reason());
  if (const deform::Status s = check.update(0.0f); !s) throw UsageError(std::string("--pose: ") + s.reason());
  float largest = 0.0f;
  for (std::size_t i = 0; i < sculpt.point_count(); ++i)
    largest = std::max(largest, glm::length(check.positions()[i] - sculpt.positions[i]));
  save_rig(out, rig, rigged.named, skeleton);
  print_json(Json{{"rig", out},
                  {"group", group_name},
                  {"shape", name},
                  {"points", shape.points.size()},
                  {"shapes", group->shapes.size()},
                  {"max_error", largest}});
  return exit_ok;
}

}  // namespace

const Command corrective_command = {"corrective", "make a sculpted pose a pose-space corrective of a rig", usage, run};

}  // namespace cli
