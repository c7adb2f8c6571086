// libFuzzer harness: the .skw reader (parse_skw) for a 6-point mesh and 6 bones; what parses is normalised.
#include <cmath>

#include "deform/io/sk.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::refuse_or_check([&] {
    const deform::SkinWeights weights = deform::parse_skw(fuzz::text(data, size), 6, 6, "fuzz.skw");
    for (std::size_t p = 0; p < weights.size(); ++p) {
      const float sum = weights.weights[p].x + weights.weights[p].y + weights.weights[p].z + weights.weights[p].w;
      if (!(std::fabs(sum - 1.0f) < 1e-5f)) fuzz::broken("weights sum to 1");
      for (int k = 0; k < 4; ++k)
        if (weights.bones[p][k] >= 6) fuzz::broken("bone ids in range");
    }
  });
  return 0;
}
