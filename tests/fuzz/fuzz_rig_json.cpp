// libFuzzer harness: the rig JSON reader on a small rig; what parses writes back and reads back equal, and its spring
// chains either refuse to bind or run a second of a swinging pose with every point finite.
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "deform/io/rig_json.hpp"
#include "deform/runtime/spring_chain.hpp"
#include "fuzz_common.hpp"

namespace {

void run_springs(const deform::Rig& rig, const deform::Skeleton& skeleton) {
  deform::SpringChains springs(skeleton, rig.spring_chains, rig.colliders, rig.spring_substep);
  std::vector<glm::mat4> world(skeleton.bone_count());
  for (int frame = 0; frame < 30; ++frame) {
    const glm::mat4 root = glm::rotate(glm::mat4(1.0f), 0.5f * std::sin(0.4f * float(frame)), glm::vec3(0, 0, 1));
    for (std::size_t b = 0; b < world.size(); ++b) world[b] = root * skeleton.bind_world()[b];
    if (!springs.run(frame == 0 ? 0.0f : 1.0f / 30.0f, world)) fuzz::broken("spring chains refused a valid frame");
    for (std::size_t c = 0; c < springs.chain_count(); ++c)
      for (const glm::vec3& p : springs.points(c))
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) fuzz::broken("spring chain not finite");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] { (void)deform::parse_rig_model(fuzz::text(data, size), "fuzz.json"); });
  fuzz::refuse_or_check([&] {
    const deform::Skeleton& skeleton = fuzz::skeleton();
    const deform::Rig rig = deform::parse_rig_json(fuzz::text(data, size), skeleton, 100, "fuzz.json");
    if (deform::parse_rig_json(deform::format_rig_json(rig, skeleton), skeleton, 100, "again.json") != rig)
      fuzz::broken("rig JSON round trip");
    run_springs(rig, skeleton);
  });
  return 0;
}
