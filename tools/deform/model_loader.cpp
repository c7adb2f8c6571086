#include "model_loader.hpp"

namespace cli {

LoadedModel load_model(const Args& args) {
  // Filled in by the skinning module (native triple, --builtin) and the importer (rigged imports).
  (void)args;
  throw UsageError("loading models is not available in this build yet");
}

}  // namespace cli
