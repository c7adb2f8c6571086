#pragma once
// libdeform's error contract, in one place:
//
//  - Files and user data (readers, importers, rig and lattice set-ups): a bad input throws deform::Error of kind
//    `input`, naming the file (or "<memory>" for in-memory input), where in it (a 1-based line for text formats, a
//    byte offset for binary ones) and, where known, the element (a bone, a vertex, a JSON key). what() is one line:
//      "arm.sk: byte 412: bone 3: child count 9999 overruns the file"
//  - Invalid arguments to a bind-time call (a constructor, a binding, a solver set-up): deform::Error of kind
//    `argument`, naming the element and what is wrong, with no file:  "invalid argument: bone 7: effector out of range"
//  - The environment refused (a full disk, permissions, a read-only file system, a FIFO without a reader): kind
//    `environment`, naming the file and the system's reason: "out/o.gltf: write failed: No space left on device".
//    The CLI exits 1 for it, 2 for input and argument errors.
//  - Per-frame calls (every job's run(), the stateful steps, Character::update) never throw and never allocate: they
//    return a Status, ok or a static reason, and change nothing when it is not ok. Each job's validate() returns the
//    same Status at bind time, saying why a call would be refused.
//  - Names say which of the two a check is: `validate()` returns a Status (a job's checks); `require_valid...()`
//    throws deform::Error (the bind-time checks of clips, lattice frames and settings).
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "deform/runtime/export.hpp"

namespace deform {

class DEFORM_RUNTIME_API Error : public std::runtime_error {
 public:
  enum class Kind { input, argument, environment };
  enum class Where { none, line, byte };

  // `message` says what is wrong; the other fields say where. Use the factories below.
  Error(Kind kind, std::string file, Where where, std::int64_t position, std::string element, std::string message);

  static Error at_line(std::string file, std::int64_t line, std::string element, std::string message) {
    return Error(Kind::input, std::move(file), Where::line, line, std::move(element), std::move(message));
  }
  static Error at_byte(std::string file, std::int64_t offset, std::string element, std::string message) {
    return Error(Kind::input, std::move(file), Where::byte, offset, std::move(element), std::move(message));
  }
  static Error in_file(std::string file, std::string element, std::string message) {
    return Error(Kind::input, std::move(file), Where::none, 0, std::move(element), std::move(message));
  }
  // An argument of an API call is invalid (no file involved).
  static Error invalid_argument(std::string element, std::string message) {
    return Error(Kind::argument, std::string(), Where::none, 0, std::move(element), std::move(message));
  }

  // The system refused an operation on `file` (not the file's content): see the contract above.
  static Error environment(std::string file, std::string message) {
    return Error(Kind::environment, std::move(file), Where::none, 0, std::string(), std::move(message));
  }

  Kind kind() const noexcept { return kind_; }
  // The file (or "<memory>"); empty for Kind::argument.
  const std::string& file() const noexcept { return file_; }
  Where where() const noexcept { return where_; }
  // 1-based line (Where::line) or 0-based byte offset (Where::byte); 0 when Where::none.
  std::int64_t position() const noexcept { return position_; }
  // "bone 3", "vertex 17", "key 'bones.elbow'"; empty when the error is about the whole file.
  const std::string& element() const noexcept { return element_; }
  // The bare message, without the location prefix.
  const std::string& message() const noexcept { return message_; }

 private:
  Kind kind_;
  std::string file_;
  Where where_;
  std::int64_t position_;
  std::string element_;
  std::string message_;
};

// The result of a validate() or a per-frame call: ok, or the reason it was refused, a static string (no allocation,
// as ACL's error_result). Converts to true when ok, so `if (!job.run())` reads as before.
class Status {
 public:
  constexpr Status() noexcept = default;
  static constexpr Status failure(const char* reason) noexcept { return Status(reason); }

  constexpr bool ok() const noexcept { return reason_ == nullptr; }
  constexpr explicit operator bool() const noexcept { return ok(); }
  // "ok", or why not (e.g. "bone index out of range").
  constexpr const char* reason() const noexcept { return reason_ == nullptr ? "ok" : reason_; }

 private:
  constexpr explicit Status(const char* reason) noexcept : reason_(reason) {}
  const char* reason_ = nullptr;
};

// `text` with each control character (below 0x20, and 0x7f) written as \xNN, as Error's what() writes what it quotes:
// a name or path taken from a file prints as one line whatever bytes it holds. Used for every warning a reader gives.
DEFORM_RUNTIME_API std::string escape_control_characters(std::string_view text);

// Non-fatal findings of a reader (a missing MTL or texture), one line each, with file and line.
struct Warnings {
  std::vector<std::string> messages;
};

}  // namespace deform
