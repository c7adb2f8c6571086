// libFuzzer harness: the MTL reader (parse_mtl), then what it read written and read back.
#include "deform/io/obj.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    deform::Warnings warnings;
    const std::vector<deform::Material> materials =
        deform::parse_mtl(fuzz::text(data, size), "fuzz.mtl", "/nonexistent", &warnings);
    const std::vector<deform::Material> again = deform::parse_mtl(deform::format_mtl(materials), "again.mtl", "/");
    if (again.size() != materials.size()) fuzz::broken("materials read back as written");
  });
  return 0;
}
