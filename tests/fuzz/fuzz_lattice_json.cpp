// libFuzzer harness: the lattice JSON and vertex list readers for a 100-point mesh.
#include "deform/io/lattice_json.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    const deform::LatticeDocument document = deform::parse_lattice_json(fuzz::text(data, size), 100, "fuzz.json");
    for (std::uint32_t v : document.vertices)
      if (v >= 100) fuzz::broken("listed vertices in range");
  });
  fuzz::refuse_or_check([&] {
    for (std::uint32_t v : deform::parse_vertex_list(fuzz::text(data, size), 100, "fuzz.txt"))
      if (v >= 100) fuzz::broken("vertex list in range");
  });
  return 0;
}
