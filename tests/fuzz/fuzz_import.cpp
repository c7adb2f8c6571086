// libFuzzer harness: the import entry point as the CLI and the viewer use it (import_model_isolated). The bytes become
// a file whose extension follows what they look like (glTF, GLB, DirectX .x, Collada, SMD, FBX, IQM, MD5, else OBJ),
// so one corpus reaches every Assimp reader. Whatever Assimp does in the importer process (crash, hang, blow-up), the
// caller gets a model that keeps import_model's promises or a deform::Error naming the file, never a crash. Coverage
// guides the mutations through this process's half (the answer's decoding and checks); the importer's own half is
// exercised, and contained, but not measured.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "deform/import/import.hpp"
#include "fuzz_common.hpp"

namespace {

const char* extension_for(std::string_view bytes) {
  const auto starts = [&](std::string_view prefix) { return bytes.substr(0, prefix.size()) == prefix; };
  if (starts("glTF")) return ".glb";
  if (starts("{")) return ".gltf";
  if (starts("xof ")) return ".x";
  if (starts("<?xml") || starts("<COLLADA")) return ".dae";
  if (starts("version 1")) return ".smd";
  if (starts("Kaydara FBX Binary") || starts("; FBX")) return ".fbx";
  if (starts("INTERQUAKEMODEL")) return ".iqm";
  if (starts("MD5Version")) return ".md5mesh";
  return ".obj";
}

// One scratch folder per fuzzing process, removed at exit.
const std::filesystem::path& scratch() {
  static const std::filesystem::path folder = [] {
    std::filesystem::path p =
        std::filesystem::temp_directory_path() / ("deform_fuzz_import_" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(scratch(), ignored);
    });
    return p;
  }();
  return folder;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes = fuzz::text(data, size);
  const std::string path = (scratch() / (std::string("model") + extension_for(bytes))).string();
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(size));
  deform::IsolationLimits limits;
  limits.max_seconds = 5.0;
  limits.max_memory_bytes = 1ull << 30;
  limits.max_output_bytes = 256ull << 20;
  try {
    const deform::ImportedModel imported = deform::import_model_isolated(path, {}, limits);
    const deform::Mesh& mesh = imported.model.mesh;
    if (mesh.triangles.empty()) fuzz::broken("an imported model has triangles");
    for (std::uint32_t v : mesh.triangles)
      if (v >= mesh.vertex_count()) fuzz::broken("triangles name render vertices in range");
    for (const glm::vec4& w : imported.model.weights.weights)
      if (!(std::abs(w.x + w.y + w.z + w.w - 1.0f) < 1e-3f)) fuzz::broken("imported weights are normalised");
  } catch (const deform::Error& error) {
    if (std::string_view(error.what()).substr(0, path.size()) != path) {
      std::fprintf(stderr, "error without the file: %s\n", error.what());
      fuzz::broken("an import error names the file");
    }
  }
  std::remove(path.c_str());
  return 0;
}
