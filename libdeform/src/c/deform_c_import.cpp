// deform_character_import (deform/c/deform.h): in a source of its own, so that a static program that does not call it
// pulls no importer from libdeform_c.a and needs no deform::import to link.
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>

#include "c_character.hpp"
#include "deform/c/deform.h"
#ifdef DEFORM_C_HAVE_IMPORT
#include "deform/import/import.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/skeleton.hpp"
#endif

using deform_c::fail;
using deform_c::fail_argument;

extern "C" {

deform_status deform_character_import(const char* path, const deform_import_options* options, deform_character** out) {
  if (path == nullptr || out == nullptr) return fail_argument("deform_character_import: path or out is NULL");
  deform_import_options defaults;
  deform_import_options_init(&defaults);
  if (options == nullptr) options = &defaults;
  // The first version's fields end with worker_path; a later version reads its own fields only when struct_size
  // covers them.
  if (options->struct_size < offsetof(deform_import_options, worker_path) + sizeof(options->worker_path))
    return fail_argument("deform_import_options: struct_size is too small (use deform_import_options_init)");
  if (options->rig != DEFORM_IMPORT_RIG_NONE && options->rig != DEFORM_IMPORT_RIG_DEFAULT &&
      options->rig != DEFORM_IMPORT_RIG_FILE)
    return fail_argument("deform_import_options: rig is not a deform_import_rig");
  if (options->rig == DEFORM_IMPORT_RIG_FILE && options->rig_path == nullptr)
    return fail_argument("deform_import_options: DEFORM_IMPORT_RIG_FILE with rig_path NULL");
  if (options->allow_count > 0 && options->allow_outside == nullptr)
    return fail_argument("deform_import_options: allow_outside is NULL with a count above 0");
  for (size_t i = 0; i < options->allow_count; ++i)
    if (options->allow_outside[i] == nullptr) return fail_argument("deform_import_options: a folder is NULL");
  if (!(options->max_seconds >= 0.0 && std::isfinite(options->max_seconds)))
    return fail_argument("deform_import_options: max_seconds is negative or not finite");
#ifdef DEFORM_C_HAVE_IMPORT
  return deform_c::guarded([&] {
    deform::ImportOptions import_options;
    for (size_t i = 0; i < options->allow_count; ++i)
      import_options.references.allow_outside.emplace_back(options->allow_outside[i]);
    deform::IsolationLimits limits;
    if (options->max_memory_bytes != 0) limits.max_memory_bytes = options->max_memory_bytes;
    if (options->max_seconds != 0.0) limits.max_seconds = options->max_seconds;
    if (options->worker_path != nullptr) limits.worker = options->worker_path;
    deform::ImportedModel imported;
    try {
      imported = deform::import_model_isolated(path, import_options, limits);
    } catch (const deform::Error& e) {
      // Its argument errors are the environment's (no worker found, no pipe), not the call's: "anything else".
      if (e.kind() == deform::Error::Kind::argument)
        return fail(DEFORM_ERROR_INTERNAL, options->worker_path != nullptr
                                               ? "worker_path '" + limits.worker + "': " + e.what()
                                               : std::string(e.what()));
      throw;
    }
    auto source = std::make_shared<deform_c::CharacterSource>();
    source->clips = std::move(imported.clips);
    // As the CLI reports them (model_loading::load_model): each line names the file.
    for (const std::string& message : imported.warnings) source->warnings.push_back(std::string(path) + ": " + message);
    deform::Model& model = imported.model;
    // A field past the first version's end is read only when the caller's struct has it.
    const bool four = options->struct_size >= offsetof(deform_import_options, four_influences) + sizeof(int) &&
                      options->four_influences != 0;
    if (four && model.weights.has_extra()) {
      float largest = 0.0f;
      const std::size_t dropped = deform::drop_extra_influences(model.weights, &largest);
      source->warnings.push_back(std::string(path) + ": " + std::to_string(dropped) +
                                 " points kept their four strongest influences (four_influences; the largest weight "
                                 "dropped " +
                                 std::to_string(largest) + " of its point's)");
    }
    // The rig as the CLI picks it for an imported model: the file's (read against the model's skeleton and points),
    // or default_rig's (model_loading::starting_rig), bound by the Character, whose refusal fails the call.
    switch (options->rig) {
      case DEFORM_IMPORT_RIG_FILE: {
        const deform::Rig rig = deform::read_rig_json(options->rig_path, model.skeleton, model.mesh.point_count());
        return deform_c::adopt(deform::Character(std::move(model), rig), std::move(source), out);
      }
      case DEFORM_IMPORT_RIG_DEFAULT: {
        const deform::Rig rig = deform::default_rig(model);
        return deform_c::adopt(deform::Character(std::move(model), rig), std::move(source), out);
      }
      default: return deform_c::adopt(deform::Character(std::move(model)), std::move(source), out);
    }
  });
#else
  return fail(DEFORM_ERROR_INTERNAL, std::string("deform_character_import: this build lacks the import component ") +
                                         "(deform::import, built when Assimp and tinygltf are found): cannot read '" +
                                         path + "'");
#endif
}

}  // extern "C"
