#pragma once
// Private to deform::io: typed reading of the JSON formats (pose, lattice and rig files), every error naming the file
// and the key path of the value, e.g. `arm.rig.json: key 'lattices[0].degree[1]': 0 is outside [1, 16]`.
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace deform::detail {

// Parses a whole document of at most 64 levels of nesting (deeper: Error::at_byte where it goes too deep, checked in
// one pass before anything is built). Malformed JSON throws Error::at_byte (0-based offset of the byte where parsing
// stopped, message "malformed JSON: ..."); a number the parser cannot hold (1e999) throws Error::in_file ("invalid
// JSON").
nlohmann::json parse_json(std::string_view text, const std::string& file);

// One value of a parsed document and its key path: "" for the root, then `.key` for a member and `[i]` for an
// element ("lattices[0].select.by"). Each typed accessor checks the value and throws deform::Error (kind input,
// element "key 'PATH'", no element for the root) when it is not what the format wants. Holds references: the file
// name and the document must outlive the reader.
class JsonReader {
 public:
  JsonReader(const std::string& file, const nlohmann::json& value, std::string path = {})
      : file_(file), value_(value), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& message) const;

  const nlohmann::json& value() const noexcept { return value_; }
  const std::string& path() const noexcept { return path_; }
  bool is_null() const noexcept { return value_.is_null(); }
  bool is_string() const noexcept { return value_.is_string(); }
  bool is_object() const noexcept { return value_.is_object(); }

  // Checks that the value is an object ("must be an object") whose keys are all in `allowed`; the first other key
  // fails as "unknown key (expected a, b, c)".
  void expect_object(std::initializer_list<const char*> allowed) const;
  // Whether the value is an object with member `key`.
  bool has(const std::string& key) const { return value_.is_object() && value_.contains(key); }
  // The member `key` of an object: "is missing" (at that key's path) when there is none.
  JsonReader at(const std::string& key) const;
  // The element `index` of an array whose size the caller has checked (array_size, expect_array).
  JsonReader at(std::size_t index) const {
    return JsonReader(file_, value_[index], path_ + "[" + std::to_string(index) + "]");
  }

  // The size of an array ("must be an array").
  std::size_t array_size() const;
  // Checks an array of exactly `size` elements ("must have 3 elements, not 2").
  void expect_array(std::size_t size) const;

  std::string text() const;  // "must be a string"
  bool boolean() const;      // "must be true or false"
  // A number that is finite as a 32-bit float ("must be a number", "is not a finite number").
  float number() const;
  // number(), within [min, max], or (min, max] when `min_open` ("must be in (0, 3.4028235e+38]").
  float number(float min, float max, bool min_open = false) const;
  // An integer in [min, max] ("must be an integer", "17 is outside [0, 9]").
  std::int64_t integer(std::int64_t min, std::int64_t max) const;
  // An array of three number()s; an element's error names its own path ("offset[1]").
  glm::vec3 vec3() const;
  // An array of three integers, element a within [min[a], max[a]].
  glm::ivec3 ivec3(glm::ivec3 min, glm::ivec3 max) const;

 private:
  std::string member_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  const std::string& file_;
  const nlohmann::json& value_;
  std::string path_;
};

}  // namespace deform::detail
