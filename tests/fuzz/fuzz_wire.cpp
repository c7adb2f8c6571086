// libFuzzer harness: the bytes the importer process sends back (wire::decode in import_model_isolated). The worker
// runs Assimp on hostile files, so the parent must treat its answer as hostile too. What decodes keeps decode's
// promises (indices in range, one weight entry per point, finite positions) and encodes back to itself.
#include <cmath>
#include <vector>

#include "deform/import/import.hpp"
#include "fuzz_common.hpp"
#include "wire.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    const deform::ImportedModel imported = deform::wire::decode({data, data + size}, "fuzz.wire");
    const deform::Mesh& mesh = imported.model.mesh;
    for (std::uint32_t p : mesh.vertex_point)
      if (p >= mesh.positions.size()) fuzz::broken("render vertices name points in range");
    for (std::uint32_t v : mesh.triangles)
      if (v >= mesh.vertex_count()) fuzz::broken("triangles name render vertices in range");
    if (imported.model.weights.bones.size() != mesh.positions.size()) fuzz::broken("one weight entry per point");
    for (const glm::u16vec4& ids : imported.model.weights.bones)
      for (int k = 0; k < 4; ++k)
        if (ids[k] >= imported.model.skeleton.bone_count()) fuzz::broken("weights name bones in range");
    for (const glm::vec3& p : mesh.positions)
      if (!std::isfinite(p.x + p.y + p.z)) fuzz::broken("positions are finite");
    const std::vector<std::uint8_t> once = deform::wire::encode(imported);
    if (deform::wire::encode(deform::wire::decode(once, "again.wire")) != once) fuzz::broken("a model encodes back");
  });
  return 0;
}
