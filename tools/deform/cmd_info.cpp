// deform info PATH: what a .sk skeleton or a mesh holds, as JSON (docs/cli.md).
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <span>

#include "cli.hpp"
#include "model_loader.hpp"
#include "deform/import/import.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/pose_json.hpp"
#include "deform/io/sk.hpp"
#include "deform/io/text.hpp"
#include "deform/offline/rig.hpp"
#include "deform/offline/topology.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/runtime/skeleton.hpp"
#ifdef DEFORM_HAVE_IMPORT
#endif

namespace cli {
namespace {

using Json = nlohmann::ordered_json;  // keeps the spec's key order: "kind" first

Json vec3(glm::vec3 v) {
  return Json::array({deform::shortest_double(v.x), deform::shortest_double(v.y), deform::shortest_double(v.z)});
}

// Every bone as a `.sk`'s info lists it: id, name, parent, bind-pose head, limits.
Json bone_list(const deform::Skeleton& skeleton) {
  Json bones = Json::array();
  for (std::size_t i = 0; i < skeleton.bone_count(); ++i) {
    const deform::Bone& b = skeleton.bones()[i];
    bones.push_back({{"id", i},
                     {"name", b.name},
                     {"parent", b.parent},
                     {"head", vec3(glm::vec3(skeleton.bind_world()[i][3]))},
                     {"limits", {{"min", vec3(b.limits.min)}, {"max", vec3(b.limits.max)}}}});
  }
  return bones;
}

Json skeleton_info(const deform::Skeleton& skeleton) { return {{"kind", "skeleton"}, {"bones", bone_list(skeleton)}}; }

// `names`: per submesh, its `o`/`g` names (an OBJ's, or an import's node and mesh: ImportedModel::submesh_names).
Json mesh_info(const deform::Mesh& mesh, std::span<const deform::ObjSubmeshNames> names) {
  Json materials = Json::array();
  for (const deform::Material& m : mesh.materials) materials.push_back(m.name);
  Json submeshes = Json::array();
  for (std::size_t i = 0; i < mesh.submeshes.size(); ++i) {
    const deform::Submesh& s = mesh.submeshes[i];
    const deform::ObjSubmeshNames named = i < names.size() ? names[i] : deform::ObjSubmeshNames{};
    const bool has_material = s.material >= 0 && static_cast<std::size_t>(s.material) < mesh.materials.size();
    submeshes.push_back(
        {{"material", has_material ? Json(mesh.materials[static_cast<std::size_t>(s.material)].name) : Json(nullptr)},
         {"object", named.object},
         {"group", named.group},
         {"first_triangle", s.first_triangle},
         {"triangles", s.triangle_count}});
  }
  const deform::Bounds bounds = deform::compute_bounds(mesh.positions);
  return {{"kind", "mesh"},
          {"vertices", mesh.point_count()},
          {"triangles", mesh.triangle_count()},
          {"materials", std::move(materials)},
          {"render_vertices", mesh.vertex_count()},
          {"faces", mesh.face_sizes.size()},
          {"has_uvs", !mesh.vertex_uvs.empty()},
          {"submeshes", std::move(submeshes)},
          {"bounds", {{"min", vec3(bounds.min)}, {"max", vec3(bounds.max)}}}};
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// --rig: the default rig default_rig() makes for a rigged model, and why (rig.hpp's survey_rig; docs/ik.md).
[[maybe_unused]] Json rig_info(const deform::Model& model) {
  const deform::Skeleton& skeleton = model.skeleton;
  const deform::RigSurvey survey = deform::survey_rig(model);
  const deform::Rig rig = deform::default_rig(model);
  const auto name = [&](std::int32_t bone) { return bone < 0 ? Json(nullptr) : Json(skeleton.key(bone)); };
  const auto names = [&](const std::vector<std::int32_t>& bones) {
    Json list = Json::array();
    for (const std::int32_t b : bones) list.push_back(skeleton.key(b));
    return list;
  };
  Json limbs = Json::array();
  for (const deform::Limb& limb : survey.limbs)
    limbs.push_back({{"kind", deform::limb_kind_name(limb.kind)},
                     {"side", limb.side > 0   ? "left"
                              : limb.side < 0 ? "right"
                                              : "middle"},
                     {"root", name(limb.chain.front())},
                     {"effector", name(limb.chain.back())},
                     {"chain", names(limb.chain)},
                     {"lattices", names(limb.lattices)},
                     {"why", limb.why}});
  Json reach = Json::array();
  if (rig.reach_effector >= 0)
    reach.push_back({{"effector", name(rig.reach_effector)}, {"root", name(rig.reach_root)}});
  for (const deform::Rig::ReachChain& chain : rig.reach_chains)
    reach.push_back({{"effector", name(chain.effector)}, {"root", name(chain.root)}});
  Json lattices = Json::array();
  for (const deform::LatticeSpec& spec : rig.lattices) lattices.push_back(skeleton.key(spec.bone));
  Json springs = Json::array();
  for (const deform::SpringChainSpec& chain : rig.spring_chains)
    springs.push_back({{"name", chain.name}, {"bones", names(chain.bones)}});
  Json skipped = Json::array();
  for (const auto& [bone, why] : survey.skipped) skipped.push_back({{"bone", skeleton.key(bone)}, {"why", why}});
  return {{"naming", survey.naming},       {"four_legged", survey.four_legged}, {"up", vec3(survey.up)},
          {"pelvis", name(survey.pelvis)}, {"chest", name(survey.chest)},       {"limbs", std::move(limbs)},
          {"reach", std::move(reach)},     {"lattices", std::move(lattices)},   {"spring_chains", std::move(springs)},
          {"skipped", std::move(skipped)}};
}

int run(const std::vector<std::string>& argv) {
  const Args args(argv, {"--allow-outside"}, {"--rig"});
  const deform::ReferencePolicy policy = reference_policy(args);
  if (args.positionals().size() != 1) throw UsageError("expected exactly one file (a .sk skeleton or an .obj mesh)");
  const std::string& path = args.positionals()[0];
  const std::string ext = lower_extension(path);
  Json info;
  if (args.has("--rig") && (ext == ".sk" || ext == ".obj"))
    throw UsageError("--rig needs a rigged model the importer reads (glTF, FBX, .x, IQM, ...), not a " + ext + " file");
  if (ext == ".sk") {
    info = skeleton_info(deform::read_sk(path));
  } else if (ext == ".obj") {
    deform::Warnings warnings;
    deform::ObjNames names;
    const deform::Mesh mesh = deform::read_obj(path, &warnings, policy, &names);
    info = mesh_info(mesh, names.submeshes);
    for (const std::string& w : warnings.messages) note(w);
#ifdef DEFORM_HAVE_IMPORT  // imported models: bones and clips
  } else if (deform::is_importable(path)) {
    deform::ImportOptions options;
    options.references = policy;
    const deform::ImportedModel imported = deform::import_model_isolated(path, options);
    for (const std::string& w : imported.warnings) note(path + ": " + w);
    info = mesh_info(imported.model.mesh, imported.submesh_names);  // "vertices": the distinct points (docs/import.md)
    if (imported.rigged) {
      info["bones"] = imported.model.skeleton.bone_count();
      Json clips = Json::array();
      for (const deform::Animation& clip : imported.clips) {
        // The samplers the clip's tracks of two keys or more use (one key holds a value), in the order step,
        // linear, cubic_spline.
        bool used[3] = {false, false, false};
        for (const deform::Channel& channel : clip.channels) {
          if (channel.translation.times.size() > 1) used[static_cast<int>(channel.translation.interpolation)] = true;
          if (channel.rotation.times.size() > 1) used[static_cast<int>(channel.rotation.interpolation)] = true;
        }
        for (const deform::MorphChannel& channel : clip.morph_channels)
          if (channel.weight.times.size() > 1) used[static_cast<int>(channel.weight.interpolation)] = true;
        Json interpolation = Json::array();
        const char* names[3] = {"step", "linear", "cubic_spline"};
        for (int i = 0; i < 3; ++i)
          if (used[i]) interpolation.push_back(names[i]);
        clips.push_back({{"name", clip.name},
                         {"duration", deform::shortest_double(clip.duration)},
                         {"channels", clip.channels.size()},
                         {"interpolation", std::move(interpolation)},
                         {"morph_channels", clip.morph_channels.size()}});
      }
      info["clips"] = std::move(clips);
    }
    if (imported.rigged || !imported.model.morph_targets.empty()) {
      // New keys only (the ones above are fixed): morph targets by name and mesh, and the most influences a point has.
      Json morphs = Json::array();
      for (const deform::MorphTarget& t : imported.model.morph_targets)
        morphs.push_back({{"name", t.name},
                          {"mesh", t.mesh},
                          {"default_weight", deform::shortest_double(t.default_weight)},
                          {"points", t.points.size()}});
      info["morph_targets"] = std::move(morphs);
      std::size_t most = 0;
      for (std::size_t p = 0; p < imported.model.weights.size(); ++p)
        most = std::max(most, deform::influence_count(imported.model.weights, p));
      info["max_influences"] = most;
    }
    if (imported.rigged) {
      // New key: the file's skins (glTF: every skin; other formats: one), each with the meshes it deforms.
      Json skins = Json::array();
      for (const deform::ImportedSkin& skin : imported.skins)
        skins.push_back({{"name", skin.name}, {"joints", skin.joints}, {"meshes", skin.meshes}});
      info["skins"] = std::move(skins);
      // New key: the imported bones themselves, as a .sk's info lists them (the names a pose or a weights study
      // addresses; "bones" above stays the count the contract fixes).
      info["skeleton"] = bone_list(imported.model.skeleton);
    }
    if (args.has("--rig")) {
      if (!imported.rigged) throw deform::Error::in_file(path, "", "--rig needs a rigged model: this one has no skin");
      info["rig"] = rig_info(imported.model);  // new key, last
    }
#endif
  } else {
    throw deform::Error::in_file(path, "", "unsupported file type '" + ext + "' (info reads .sk and .obj)");
  }
  print_json_in_order(info);
  return exit_ok;
}

}  // namespace

const Command info_command = {
    "info", "inspect a .sk skeleton, an .obj mesh or an importable model",
    "usage: deform info PATH [--rig] [--allow-outside DIR]...\n"
    "\n"
    "Files a model names (MTL, textures, buffers) are read only from its own folder, or from a folder given with\n"
    "--allow-outside DIR (repeatable); any other is refused with exit 2 (docs/security.md).\n"
    "Prints what PATH holds as one JSON document on stdout.\n"
    "  S.sk      {\"kind\": \"skeleton\", \"bones\": [{\"id\", \"name\", \"parent\", \"head\": [x, y, z],\n"
    "             \"limits\": {\"min\": [x, y, z], \"max\": [x, y, z]}}, ...]}\n"
    "            head: the bone's bind-pose world position; limits: local Euler X·Y·Z, degrees.\n"
    "  MESH.obj  {\"kind\": \"mesh\", \"vertices\" (OBJ `v` lines), \"triangles\", \"materials\" (names),\n"
    "             \"render_vertices\", \"faces\", \"has_uvs\", \"submeshes\", \"bounds\": {\"min\", \"max\"}}\n"
    "            Reader warnings (a missing MTL or texture) go to stderr.\n"
    "  MODEL     any format the importer reads (glTF, FBX, .x, ...; builds with deform::import): the mesh keys\n"
    "            (\"vertices\": distinct points) and, when rigged, \"bones\": B and \"clips\": [{\"name\",\n"
    "            \"duration\" (seconds), \"channels\", \"interpolation\": the samplers its tracks use, of step,\n"
    "            linear, cubic_spline, \"morph_channels\": the morph targets it animates}], then \"morph_targets\": "
    "[{\"name\", \"mesh\", \"default_weight\",\n"
    "            \"points\" (the points it moves)}] (for `deform skin --morph NAME:W`) and \"max_influences\" (the\n"
    "            most bones one point is skinned by), and when rigged \"skins\": [{\"name\", \"joints\", \"meshes\": "
    "the\n"
    "            names of the meshes it deforms}] (glTF: every skin of the file; other formats: one). Importer\n"
    "            warnings go to stderr.\n"
    "  --rig     (a rigged MODEL) adds \"rig\": the default rig's choices and why: \"naming\" (the name map\n"
    "            that matched, or none), \"four_legged\", \"up\", \"pelvis\", \"chest\", \"limbs\": [{\"kind\" (arm,\n"
    "            leg, front_leg, hind_leg, neck, tail), \"side\", \"root\", \"effector\", \"chain\", \"lattices\",\n"
    "            \"why\"}], \"reach\": [{\"effector\", \"root\"}] (the rig's chains, its default first),\n"
    "            \"lattices\", \"spring_chains\" and \"skipped\": [{\"bone\", \"why\"}] (helper bones left out).\n"
    "\n"
    "Exit status: 0 success; 2 bad usage or a malformed file (the message names the file, the byte offset or\n"
    "line, and the bone or element); 1 any other failure.\n",
    run};

}  // namespace cli
