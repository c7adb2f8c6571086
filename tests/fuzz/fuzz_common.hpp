#pragma once
// Shared by the libFuzzer harnesses (one per reader, tests/fuzz/fuzz_*.cpp). A harness feeds the bytes to its reader:
// a deform::Error is the expected answer to bad input; any other exception, a crash, a sanitizer report, a hang or
// a memory blow-up (libFuzzer's -timeout and -rss_limit_mb) is a finding. What parses must keep the reader's promises,
// checked by the harness (a .sk writes back byte for byte, weights are normalised, ...).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "deform/runtime/error.hpp"
#include "deform/runtime/skeleton.hpp"

namespace fuzz {

inline std::string_view text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A broken promise: report it the way libFuzzer records a crash.
[[noreturn]] inline void broken(const char* promise) {
  std::fprintf(stderr, "reader promise broken: %s\n", promise);
  std::abort();
}

// Runs `parse`; deform::Error is the expected refusal, anything else escapes to libFuzzer as a finding. With
// DEFORM_FUZZ_SEEDS_PARSE=1 (the `fuzz_NAME_seeds` tests, run on the seed files alone) a refusal is a finding too:
// seeds the reader refuses, such as answers of an older wire version, would start the fuzzer from nothing.
template <class Parse>
void refuse_or_check(Parse&& parse) {
  try {
    parse();
  } catch (const deform::Error& e) {
    static const bool seeds_must_parse = [] {
      const char* v = std::getenv("DEFORM_FUZZ_SEEDS_PARSE");
      return v != nullptr && std::string_view(v) == "1";
    }();
    if (seeds_must_parse) {
      std::fprintf(stderr, "a seed is refused: %s\n", e.what());
      std::abort();
    }
  }
}

// A small rig for the readers that need one: root → shoulder → elbow → wrist, plus a bone named "#2" and an
// unnamed bone, so that '#ID' keys are exercised.
inline const deform::Skeleton& skeleton() {
  static const deform::Skeleton rig = [] {
    std::vector<deform::Bone> bones(6);
    const char* names[] = {"root", "shoulder", "elbow", "wrist", "#2", ""};
    for (int b = 0; b < 6; ++b) {
      bones[b].name = names[b];
      bones[b].parent = b == 0 ? -1 : (b <= 3 ? b - 1 : 0);
      bones[b].bind_translation = glm::vec3(0.0f, b == 0 ? 0.0f : 0.3f, 0.0f);
    }
    bones[0].children = {1, 4, 5};
    bones[1].children = {2};
    bones[2].children = {3};
    bones[1].limits.min = glm::vec3(-90.0f), bones[1].limits.max = glm::vec3(90.0f);
    return deform::Skeleton(bones, "fuzz");
  }();
  return rig;
}

}  // namespace fuzz
