// libFuzzer harness: the pose JSON reader (parse_pose_json) on a small rig; what parses is finite and sized.
#include <cmath>

#include "deform/io/pose_json.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    const deform::Skeleton& skeleton = fuzz::skeleton();
    const deform::Pose pose = deform::parse_pose_json(fuzz::text(data, size), skeleton, true, "fuzz.json");
    if (pose.rotations.size() != skeleton.bone_count()) fuzz::broken("one rotation per bone");
    for (const glm::quat& q : pose.rotations)
      if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w))
        fuzz::broken("finite rotations");
  });
  return 0;
}
