// libFuzzer harness: the rig JSON reader on a small rig; what parses writes back and reads back equal.
#include "deform/io/rig_json.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] { (void)deform::parse_rig_model(fuzz::text(data, size), "fuzz.json"); });
  fuzz::refuse_or_check([&] {
    const deform::Skeleton& skeleton = fuzz::skeleton();
    const deform::Rig rig = deform::parse_rig_json(fuzz::text(data, size), skeleton, 100, "fuzz.json");
    if (deform::parse_rig_json(deform::format_rig_json(rig, skeleton), skeleton, 100, "again.json") != rig)
      fuzz::broken("rig JSON round trip");
  });
  return 0;
}
