#include "shared_steps.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>

#include "cli.hpp"
#include "model_loader.hpp"
#include "deform/extras/builtin.hpp"
#include "deform/io/atomic_file.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#ifdef DEFORM_HAVE_STB
#include <stb_image_write.h>
#endif
namespace cli {
namespace {

std::string lower_extension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

}  // namespace

model_loading::LoadedModel load_rig_model(const deform::RigModel& named, const std::string& rig_path,
                                          const deform::ReferencePolicy& policy) {
  model_loading::ModelRequest request;
  request.references = policy;
  if (!named.builtin) {
    if (named.obj.empty() && named.file.empty())
      throw deform::Error::in_file(rig_path, "key 'model'",
                                   "the rig names no model: give the model too (MODEL --rig " + rig_path + ")");
    // Each is confined before it is opened; the paths keep the rig's spelling (they name the files in messages).
    if (!named.file.empty()) {
      deform::resolve_referenced_file(rig_path, named.file, "key 'model.file'", policy);
    } else {
      deform::resolve_referenced_file(rig_path, named.obj, "key 'model.obj'", policy);
      deform::resolve_referenced_file(rig_path, named.skeleton, "key 'model.skeleton'", policy);
      deform::resolve_referenced_file(rig_path, named.weights, "key 'model.weights'", policy);
    }
    const std::filesystem::path folder = std::filesystem::path(rig_path).parent_path();
    if (!named.file.empty()) {
      request.path = (folder / named.file).string();
      if (!model_loading::importable(request.path))
        throw deform::Error::in_file(rig_path, "key 'model.file'",
                                     "'" + named.file + "' is not a format this build imports");
    } else {
      request.path = (folder / named.obj).string();
      request.skeleton = (folder / named.skeleton).string();
      request.weights = (folder / named.weights).string();
    }
  }
  model_loading::LoadedModel loaded = model_loading::load_model(request);
  for (const std::string& message : loaded.warnings) note(message);
  return loaded;
}

std::string describe_file(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return "a folder";
  std::ifstream in(path, std::ios::binary);
  if (!in) return "a file that cannot be read";
  std::string head(64 * 1024, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(in.gcount()));
  if (head.empty()) return "an empty file";
  const auto starts = [&](std::string_view magic) { return head.compare(0, magic.size(), magic) == 0; };
  if (starts("glTF")) return "a glTF binary";
  if (starts("SKEL")) return "a skeleton (.sk)";
  if (starts("skw ")) return "skin weights (.skw)";
  if (starts("\x89PNG")) return "a PNG image";
  if (starts("\xFF\xD8\xFF")) return "a JPEG image";
  if (starts("Kaydara FBX Binary")) return "an FBX binary";
  if (starts("INTERQUAKEMODEL")) return "an IQM model";
  if (starts("xof ")) return "a DirectX .x model";
  const std::size_t first = head.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && head[first] == '{') {
    if (head.find("\"asset\"") != std::string::npos) return "a glTF JSON file";
    if (head.find("\"rig\"") != std::string::npos) return "a rig JSON file";
    if (head.find("\"control_points\"") != std::string::npos || head.find("\"displacements\"") != std::string::npos)
      return "a lattice JSON file";
    if (head.find("\"bones\"") != std::string::npos) return "a pose JSON file";
    return "a JSON file";
  }
  if (first != std::string::npos && head[first] == '[') return "a JSON file";  // not a rig: the parser says why
  if (head.find("<COLLADA") != std::string::npos) return "a Collada model";
  const std::string extension = lower_extension(path);
  if (extension == ".obj") return "an OBJ mesh";
  if (model_loading::importable(path)) return "a model (" + extension + ")";
  return "a file that is not JSON";
}

std::string read_rig_text(const std::string& path) {
  const std::string kind = describe_file(path);
  if (kind != "a rig JSON file" && kind != "a JSON file" && kind != "a file that cannot be read")
    throw deform::Error::in_file(path, "", "expected a rig JSON file (--rig), got " + kind);
  return deform::read_file_text(path);
}

void apply_inertia_option(const Args& args, deform::Rig& rig) {
  const auto text = args.value("--inertia");
  if (!text) return;
  const double inertia = parse_number(*text, "--inertia");
  if (!(inertia >= 0.0 && inertia <= 1.0)) throw UsageError("--inertia must be in [0, 1]");
  // A scale, so that each part keeps its tuned character: limbs keep their length at any value (docs/cli.md).
  for (deform::LatticeSpec& spec : rig.lattices)
    spec.motion.inertia = deform::scaled_inertia(spec.motion.part, float(inertia));
}

RiggedModel load_rigged_model(const Args& args, bool need_rig) {
  const std::vector<std::string>& files = args.positionals();
  std::optional<std::string> rig_path = args.value("--rig");
  // A rig positional: RIG.json, or a rig file by its content whatever its name (arm.rig).
  const bool rig_positional = files.size() == 1 && !args.has("--builtin") &&
                              (lower_extension(files[0]) == ".json" || describe_file(files[0]) == "a rig JSON file");
  if (rig_positional && rig_path)
    throw UsageError("'" + files[0] + "' is a rig and --rig names another: give MODEL --rig FILE, or the rig alone");
  if (rig_positional) rig_path = files[0];

  if (files.empty() && !rig_path && !args.has("--builtin"))
    throw UsageError("expected a model (MODEL, MESH.obj --skeleton S.sk --weights W.skw, or --builtin) or a RIG.json");
  RiggedModel out;
  std::string text;
  if (rig_path) text = read_rig_text(*rig_path);
  if (rig_path && (rig_positional || (files.empty() && !args.has("--builtin")))) {
    for (const char* flag : {"--skeleton", "--weights", "--max-influences"})
      if (args.has(flag)) throw UsageError(std::string(flag) + " belongs to a model given on the command line");
    out.named = deform::parse_rig_model(text, *rig_path);
    out.loaded = load_rig_model(out.named, *rig_path, reference_policy(args));
    const std::filesystem::path folder = std::filesystem::path(*rig_path).parent_path();
    for (std::string* file : {&out.named.obj, &out.named.skeleton, &out.named.weights, &out.named.file})
      if (!file->empty()) *file = (folder / *file).string();
  } else {
    out.loaded = load_model(args);  // --builtin, MODEL or the native triple; the rig's "model", if any, is not used
    out.named.builtin = out.loaded.builtin;
    if (out.loaded.imported) {
      out.named.file = out.loaded.source;
    } else if (!out.loaded.builtin) {
      out.named.obj = out.loaded.source;
      out.named.skeleton = args.value("--skeleton").value_or("");
      out.named.weights = args.value("--weights").value_or("");
    }
  }
  deform::Model& model = out.loaded.model;
  if (rig_path) out.rig = deform::parse_rig_json(text, model.skeleton, model.mesh.point_count(), *rig_path);
  else if (need_rig) out.rig = model_loading::starting_rig(out.loaded);
  if (out.loaded.builtin) out.loaded.clips = deform::builtin_clips(model);
  const std::string folder =
      out.loaded.builtin ? "" : std::filesystem::path(out.loaded.source).parent_path().lexically_normal().string();
  out.texture_root = folder.empty() ? "." : folder;
  return out;
}

void save_rig(const std::string& path, deform::Rig rig, const deform::RigModel& named,
              const deform::Skeleton& skeleton) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::absolute(path).parent_path();
  rig.model = named;
  for (std::string* file : {&rig.model.obj, &rig.model.skeleton, &rig.model.weights, &rig.model.file}) {
    if (file->empty()) continue;
    const fs::path relative = fs::absolute(*file).lexically_normal().lexically_relative(folder);
    if (!relative.empty()) *file = relative.generic_string();
  }
  deform::write_rig_json(path, rig, skeleton);
}

const deform::Animation& find_clip_or_fail(const std::vector<deform::Animation>& clips, const std::string& name) {
  const std::int32_t found = deform::find_clip(clips, name);
  if (found < 0) {
    std::string names;
    for (const deform::Animation& c : clips) names += (names.empty() ? "" : ", ") + ("'" + c.name + "'");
    throw UsageError("--clip: no clip named '" + name + "' (the model has " +
                     (names.empty() ? std::string("none") : names) + ")");
  }
  return clips[std::size_t(found)];
}

ClipPlayer::ClipPlayer(deform::Character& character, const deform::Animation& clip)
    : character_(character), clip_(clip), bind_(character.skeleton().bind_pose()), pose_(bind_), later_(bind_) {}

void ClipPlayer::sample(double t, deform::Pose& into) const {
  std::copy(bind_.rotations.begin(), bind_.rotations.end(), into.rotations.begin());
  std::copy(bind_.translations.begin(), bind_.translations.end(), into.translations.begin());
  deform::SamplingJob job;
  job.animation = &clip_;
  job.time = float(t);
  job.rotations = into.rotations;
  job.translations = into.translations;
  if (!job.run()) throw UsageError("--clip: clip '" + clip_.name + "' does not fit the skeleton");
}

void ClipPlayer::set(double t) {
  constexpr float lead = 1e-3f;  // docs/elasticity.md: a lead of 1 ms or less keeps every frame rate alike
  sample(t, pose_);
  sample(t + lead, later_);
  character_.set_pose(pose_, later_, lead);
}

void embed_builtin_texture(model_loading::LoadedModel& loaded) {
  if (!loaded.builtin) return;
#ifdef DEFORM_HAVE_STB
  constexpr int size = 512;  // as tools/make_builtin writes samples/data/builtin.png
  const std::vector<std::uint8_t> pixels = deform::builtin_texture(size);
  std::vector<std::uint8_t> png;
  const auto append = [](void* context, void* data, int bytes) {
    auto* out = static_cast<std::vector<std::uint8_t>*>(context);
    out->insert(out->end(), static_cast<const std::uint8_t*>(data), static_cast<const std::uint8_t*>(data) + bytes);
  };
  if (!stbi_write_png_to_func(append, &png, size, size, 3, pixels.data(), size * 3)) return;
  const auto image = std::make_shared<const std::vector<std::uint8_t>>(std::move(png));
  for (deform::Material& m : loaded.model.mesh.materials)
    if (!m.diffuse_map.empty()) m.diffuse_map.clear(), m.diffuse_image = image;
#else
  note("this build has no stb: the built-in character's texture is left out");
#endif
}

// Render-vertex normals of the deformed points: n' ∝ cof(J)·n with J = ∂Q/∂(u,v,w) · diag(size)⁻¹ (as `deform ffd`).
std::vector<glm::vec3> ffd_normals(const deform::Mesh& mesh, const deform::BezierLattice& lattice,
                                   const std::vector<bool>& deformed) {
  const deform::LatticeFrame& frame = lattice.frame();
  const glm::vec3 size(frame.u_axis.x, frame.v_axis.y, frame.w_axis.z);
  std::vector<glm::vec3> normals = mesh.vertex_normals;
  for (std::size_t r = 0; r < normals.size() && r < mesh.vertex_point.size(); ++r) {
    const std::uint32_t p = mesh.vertex_point[r];
    if (!deformed[p]) continue;
    glm::mat3 j = lattice.jacobian(frame.to_lattice(mesh.positions[p]));
    for (int a = 0; a < 3; ++a) j[a] /= size[a];
    const glm::mat3 cofactor(glm::cross(j[1], j[2]), glm::cross(j[2], j[0]), glm::cross(j[0], j[1]));
    const glm::vec3 n = cofactor * normals[r];
    const float length = glm::length(n);
    if (length > 0.0f && std::isfinite(length)) normals[r] = n / length;
  }
  return normals;
}

}  // namespace cli
