// libFuzzer harness: the IQM reader (iqm_import.cpp) in this process, so that the sanitizers and coverage see it
// (fuzz_import runs the importer in a child process, where a crash is contained, not found). The bytes become a
// .iqm file. Expected: a model that keeps import_model's promises or a deform::Error naming the file; a crash, a
// sanitizer report or another exception is a finding. The seed (corpus/iqm_import/two_joints.iqm, 764 bytes) is a
// two-joint bar with a looping three-frame clip, small enough for the mutations to reach every record.
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
  static const std::string path = [] {
    const auto p = std::filesystem::temp_directory_path() / ("deform_fuzz_iqm_" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    return (p / "model.iqm").string();
  }();
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(size));
  try {
    const deform::ImportedModel imported = deform::import_model(path);
    const deform::Mesh& mesh = imported.model.mesh;
    if (mesh.triangles.empty()) fuzz::broken("an imported model has triangles");
    for (std::uint32_t v : mesh.triangles)
      if (v >= mesh.vertex_count()) fuzz::broken("triangles name render vertices in range");
    if (imported.model.weights.size() != mesh.point_count()) fuzz::broken("one weight entry per point");
    for (const glm::vec4& w : imported.model.weights.weights)
      if (!(std::abs(w.x + w.y + w.z + w.w - 1.0f) < 1e-3f)) fuzz::broken("imported weights are normalised");
    for (const deform::Animation& clip : imported.clips) clip.require_valid(imported.model.skeleton.bone_count(), path);
  } catch (const deform::Error& error) {
    if (std::string_view(error.what()).substr(0, path.size()) != path) {
      std::fprintf(stderr, "error without the file: %s\n", error.what());
      fuzz::broken("an import error names the file");
    }
  }
  std::remove(path.c_str());
  return 0;
}
