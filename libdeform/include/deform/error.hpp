#pragma once
// Errors from files and user data: a value with context, never a crash and never a silent fix.
//
// Every reader in libdeform throws deform::Error when its input is invalid. The error names the file (or "<memory>"
// for in-memory input), where in it (a 1-based line for text formats, a byte offset for binary ones) and, where
// known, the element (a bone id, a vertex index, a JSON key). what() gives the one-line human message
//   "arm.sk: byte 412: bone 3: child count 9999 overruns the file"
// Per-frame functions never throw: they validate their arguments up front and return false.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "deform/export.hpp"

namespace deform {

class DEFORM_API Error : public std::runtime_error {
 public:
  enum class Where { none, line, byte };

  // `message` says what is wrong; the other fields say where. Use the factories below.
  Error(std::string file, Where where, std::int64_t position, std::string element, std::string message);

  static Error at_line(std::string file, std::int64_t line, std::string element, std::string message) {
    return Error(std::move(file), Where::line, line, std::move(element), std::move(message));
  }
  static Error at_byte(std::string file, std::int64_t offset, std::string element, std::string message) {
    return Error(std::move(file), Where::byte, offset, std::move(element), std::move(message));
  }
  static Error in_file(std::string file, std::string element, std::string message) {
    return Error(std::move(file), Where::none, 0, std::move(element), std::move(message));
  }

  const std::string& file() const noexcept { return file_; }
  Where where() const noexcept { return where_; }
  // 1-based line (Where::line) or 0-based byte offset (Where::byte); 0 when Where::none.
  std::int64_t position() const noexcept { return position_; }
  // "bone 3", "vertex 17", "key 'bones.elbow'"; empty when the error is about the whole file.
  const std::string& element() const noexcept { return element_; }
  // The bare message, without the location prefix.
  const std::string& message() const noexcept { return message_; }

 private:
  std::string file_;
  Where where_;
  std::int64_t position_;
  std::string element_;
  std::string message_;
};

}  // namespace deform
