// libFuzzer harness: the glTF reader (gltf_import.cpp) in this process, so that the sanitizers and coverage see it
// (fuzz_import runs the importer in a child process, where a crash is contained, not found). The bytes become a .glb
// when they start with "glTF", else a .gltf. Expected: a model that keeps import_model's promises or a deform::Error
// naming the file; a crash, a sanitizer report or another exception is a finding. A secret file lies beside the
// model's folder (4099 bytes of 0xAB, the size in gltf_import.dict; the corpus's uri_* files name it): a model whose
// points hold its bytes, (171, 171, 171) as unnormalised UNSIGNED_BYTE positions, read outside its folder.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "deform/import/import.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes = fuzz::text(data, size);
  static const std::string folder = [] {
    const auto base = std::filesystem::temp_directory_path() / ("deform_fuzz_gltf_" + std::to_string(::getpid()));
    std::filesystem::create_directories(base / "model");
    std::ofstream(base / "secret.bin", std::ios::binary | std::ios::trunc) << std::string(4099, '\xAB');
    return (base / "model").string();
  }();
  const std::string path = folder + (bytes.substr(0, 4) == "glTF" ? "/model.glb" : "/model.gltf");
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(size));
  try {
    const deform::ImportedModel imported = deform::import_model(path);
    const deform::Mesh& mesh = imported.model.mesh;
    if (mesh.triangles.empty()) fuzz::broken("an imported model has triangles");
    for (std::uint32_t v : mesh.triangles)
      if (v >= mesh.vertex_count()) fuzz::broken("triangles name render vertices in range");
    for (const glm::vec3& p : mesh.positions)
      if (p == glm::vec3(171.0f)) fuzz::broken("no byte from outside the model's folder is read");
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
