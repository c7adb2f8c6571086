// The programs' model loading (model_loading.hpp).
#include "model_loading.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <limits>
#include <span>
#include <utility>

#include "deform/extras/builtin.hpp"
#include "deform/io/model_files.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/sk.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/skinning.hpp"
#ifdef DEFORM_HAVE_IMPORT
#include "deform/import/import.hpp"
#endif

namespace model_loading {
namespace {

bool is_obj(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".obj";
}

LoadedModel load_native(const ModelRequest& request) {
  if (request.skeleton.empty())
    throw deform::Error::invalid_argument(request.path, "the native files need a skeleton (.sk)");
  LoadedModel loaded;
  loaded.source = request.path;
  if (!request.weights.empty()) {
    deform::Warnings warnings;
    loaded.model = deform::load_model(request.path, request.skeleton, request.weights, &warnings, request.influences,
                                      request.references, &loaded.names);
    loaded.warnings = std::move(warnings.messages);
    return loaded;
  }
  if (!request.automatic_weights)
    throw deform::Error::invalid_argument(request.path, "the native files need weights (.skw)");
  deform::Warnings warnings;
  loaded.model.name = std::filesystem::path(request.path).stem().string();
  loaded.model.mesh = deform::read_obj(request.path, &warnings, request.references, &loaded.names);
  loaded.model.skeleton = deform::read_sk(request.skeleton);
  deform::WeightsResult automatic = deform::compute_heat_weights(loaded.model.mesh, loaded.model.skeleton);
  loaded.model.weights = std::move(automatic.weights);
  loaded.warnings = std::move(warnings.messages);
  for (std::string& w : automatic.warnings) loaded.warnings.push_back("automatic weights: " + std::move(w));
  return loaded;
}

}  // namespace

bool importable(const std::string& path) {
#ifdef DEFORM_HAVE_IMPORT
  return deform::is_importable(path) && !is_obj(path);
#else
  (void)path;
  return false;
#endif
}

LoadedModel load_model(const ModelRequest& request) {
  if (request.path.empty()) {
    LoadedModel loaded;
    loaded.model = deform::builtin_character();
    loaded.source = "builtin";
    loaded.builtin = true;
    for (const std::string_view part : deform::builtin_part_names())
      loaded.names.submeshes.push_back({"builtin", std::string(part)});
    return loaded;
  }
  if (!request.skeleton.empty() || !request.weights.empty()) return load_native(request);
#ifdef DEFORM_HAVE_IMPORT
  if (importable(request.path)) {
    deform::ImportOptions options;
    options.references = request.references;
    deform::ImportedModel imported = deform::import_model_isolated(request.path, options);
    LoadedModel loaded;
    loaded.model = std::move(imported.model);
    loaded.source = request.path;
    loaded.imported = true;
    loaded.rigged = imported.rigged;
    loaded.clips = std::move(imported.clips);
    loaded.up = imported.up;
    loaded.names.submeshes = std::move(imported.submesh_names);
    for (const std::string& message : imported.warnings) loaded.warnings.push_back(request.path + ": " + message);
    return loaded;
  }
  throw deform::Error::invalid_argument(request.path, is_obj(request.path)
                                                          ? "an OBJ needs its skeleton (.sk)"
                                                          : "not a format the importer reads, nor an OBJ");
#else
  throw deform::Error::invalid_argument(
      request.path, is_obj(request.path) ? "an OBJ needs its skeleton (.sk)"
                                         : "this build has no importer (deform::import): give an OBJ and its skeleton");
#endif
}

deform::Rig starting_rig(const LoadedModel& loaded) {
  return loaded.builtin ? deform::builtin_rig(loaded.model) : deform::default_rig(loaded.model);
}

namespace {

// Calls visit(points) with the model's skinned points (LBS) at `samples` (at least 2) evenly spaced times of `clip`,
// both ends included, the clip sampled over the bind pose. The last sample is the clip's end, not its start again.
template <class Visit>
void for_each_sampled_pose(const deform::Model& model, const deform::Animation& clip, int samples, Visit&& visit) {
  const std::size_t bones = model.skeleton.bone_count();
  std::vector<glm::mat4> world(bones), palette(bones);
  std::vector<glm::vec3> points(model.mesh.point_count());
  deform::Animation once = clip;
  once.loop = false;
  samples = std::max(samples, 2);
  for (int s = 0; s < samples; ++s) {
    deform::Pose pose = model.skeleton.bind_pose();
    deform::SamplingJob sampling;
    sampling.animation = &once;
    sampling.time = clip.duration * static_cast<float>(s) / static_cast<float>(samples - 1);
    sampling.rotations = pose.rotations;
    sampling.translations = pose.translations;
    deform::LocalToWorldJob fk;
    fk.skeleton = &model.skeleton;
    fk.rotations = pose.rotations;
    fk.translations = pose.translations;
    fk.world = world;
    fk.palette = palette;
    deform::SkinningJob skin;
    skin.matrices = palette;
    skin.bone_indices = model.weights.bones;
    skin.bone_weights = model.weights.weights;
    skin.in_positions = deform::as_floats(std::span<const glm::vec3>(model.mesh.positions));
    skin.out_positions = deform::as_floats(std::span<glm::vec3>(points));
    deform::Status status = sampling.run();
    if (status) status = fk.run();
    if (status) status = skin.run();
    if (!status) throw deform::Error::in_file(model.name, "clip '" + clip.name + "'", status.reason());
    visit(std::span<const glm::vec3>(points));
  }
}

}  // namespace

float lowest_height(const deform::Model& model, const deform::Animation& clip, glm::vec3 up, int samples) {
  float lowest = std::numeric_limits<float>::infinity();
  for_each_sampled_pose(model, clip, samples, [&](std::span<const glm::vec3> points) {
    for (const glm::vec3& p : points) lowest = std::min(lowest, glm::dot(p, up));
  });
  return lowest;
}

deform::Bounds posed_bounds(const deform::Model& model, const deform::Animation& clip, glm::quat frame, int samples) {
  glm::vec3 low(std::numeric_limits<float>::infinity()), high(-std::numeric_limits<float>::infinity());
  for_each_sampled_pose(model, clip, samples, [&](std::span<const glm::vec3> points) {
    for (const glm::vec3& p : points) {
      const glm::vec3 q = frame * p;
      low = glm::min(low, q);
      high = glm::max(high, q);
    }
  });
  if (model.mesh.positions.empty()) return {};
  return {low, high};
}

}  // namespace model_loading
