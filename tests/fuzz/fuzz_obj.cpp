// libFuzzer harness: the OBJ reader (parse_obj), then what it read written and read back.
#include "deform/io/obj.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    deform::Warnings warnings;
    const deform::Mesh mesh = deform::parse_obj(fuzz::text(data, size), "fuzz.obj", "/nonexistent", &warnings);
    if (mesh.vertex_point.size() != mesh.vertex_normals.size()) fuzz::broken("one normal per render vertex");
    for (std::uint32_t v : mesh.triangles)
      if (v >= mesh.vertex_count()) fuzz::broken("triangle indices in range");
    const deform::Mesh again = deform::parse_obj(deform::format_obj(mesh, mesh.positions), "again.obj", "/nonexistent");
    if (again.positions != mesh.positions) fuzz::broken("points read back as written");
  });
  return 0;
}
