#pragma once
// What the C API's sources share (deform_c.cpp, deform_c_import.cpp): the character handle and the error plumbing.
// deform_character_import has a source of its own so that a static program that never calls it links no importer.
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "deform/c/deform.h"
#include "deform/character/character.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/error.hpp"

namespace deform_c {

// What a character and its instances share besides the Character's own data: its clips and the import's warnings.
struct CharacterSource {
  std::vector<deform::Animation> clips;
  std::vector<std::string> warnings;
};

}  // namespace deform_c

struct deform_character {
  deform::Character character;
  std::shared_ptr<const deform_c::CharacterSource> source;  // never null
  deform::Pose pose;                                // set_pose's staging, sized once so that the call allocates nothing
  deform::Pose later;                               // set_pose_moving's second pose, likewise
  deform::Pose bind;                                // the bind pose, where sample_clip starts
  deform::Pose sampled;                             // sample_clip's staging
  std::vector<std::vector<std::uint32_t>> cursors;  // one SamplingJob cursor per clip, this handle's own
};

namespace deform_c {

// Records `message` as this thread's deform_last_error and returns `status`. Never throws.
deform_status fail(deform_status status, std::string message);
deform_status fail_argument(const char* message);

// Runs `body` (returning deform_status), translating what C++ throws.
template <class Body>
deform_status guarded(Body&& body) noexcept {
  try {
    return body();
  } catch (const deform::Error& e) {
    // The environment (a full disk, permissions) is neither the input nor the call: "anything else".
    return fail(e.kind() == deform::Error::Kind::input      ? DEFORM_ERROR_INPUT
                : e.kind() == deform::Error::Kind::argument ? DEFORM_ERROR_ARGUMENT
                                                            : DEFORM_ERROR_INTERNAL,
                e.what());
  } catch (const std::bad_alloc&) {
    return fail(DEFORM_ERROR_INTERNAL, "out of memory");
  } catch (const std::exception& e) {
    return fail(DEFORM_ERROR_INTERNAL, e.what());
  } catch (...) {
    return fail(DEFORM_ERROR_INTERNAL, "unknown failure");
  }
}

// Wraps `character` in a new handle at *out, with the clips and warnings `source` holds (shared, never copied), its
// staging poses and clip cursors allocated once. Throws std::bad_alloc.
deform_status adopt(deform::Character character, std::shared_ptr<const CharacterSource> source, deform_character** out);

}  // namespace deform_c
