// libFuzzer harness: the .sk reader (parse_sk); a file that parses writes back byte for byte.
#include <vector>

#include "deform/io/sk.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    const std::vector<std::uint8_t> bytes(data, data + size);
    const deform::Skeleton skeleton = deform::parse_sk(bytes, "fuzz.sk");
    if (deform::format_sk(skeleton) != bytes) fuzz::broken(".sk round trip is byte-exact");
  });
  return 0;
}
