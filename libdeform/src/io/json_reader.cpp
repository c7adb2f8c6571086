// Typed JSON reading with key paths in the errors (json_reader.hpp).
#include "json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "deform/runtime/error.hpp"
#include "float_text.hpp"

namespace deform::detail {

namespace {

// Deepest nesting of arrays and objects a document may have: no format of libdeform needs more than 5, and a
// million-level document must be refused before a parser or a destructor walks it.
constexpr int max_json_depth = 64;

// One linear pass over the text, outside strings, before anything is built.
void check_depth(std::string_view text, const std::string& file) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_json_depth)
        throw Error::at_byte(file, static_cast<std::int64_t>(i), "",
                             "JSON nested deeper than " + std::to_string(max_json_depth) + " levels");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

}  // namespace

nlohmann::json parse_json(std::string_view text, const std::string& file) {
  check_depth(text, file);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {  // e.byte: 1-based index of the last byte read
    const std::int64_t offset = e.byte > 0 ? static_cast<std::int64_t>(e.byte) - 1 : 0;
    throw Error::at_byte(file, offset, "", std::string("malformed JSON: ") + e.what());
  } catch (const nlohmann::json::exception& e) {
    throw Error::in_file(file, "", std::string("invalid JSON: ") + e.what());
  }
}

void JsonReader::fail(const std::string& message) const {
  throw Error::in_file(file_, path_.empty() ? std::string() : "key '" + path_ + "'", message);
}

void JsonReader::expect_object(std::initializer_list<const char*> allowed) const {
  if (!value_.is_object()) fail("must be an object");
  for (const auto& item : value_.items()) {
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* key) { return item.key() == key; })) {
      std::string expected;
      for (const char* key : allowed) expected += (expected.empty() ? "" : ", ") + std::string(key);
      JsonReader(file_, item.value(), member_path(item.key())).fail("unknown key (expected " + expected + ")");
    }
  }
}

JsonReader JsonReader::at(const std::string& key) const {
  if (!has(key)) JsonReader(file_, value_, member_path(key)).fail("is missing");
  return JsonReader(file_, value_[key], member_path(key));
}

std::size_t JsonReader::array_size() const {
  if (!value_.is_array()) fail("must be an array");
  return value_.size();
}

void JsonReader::expect_array(std::size_t size) const {
  if (array_size() != size)
    fail("must have " + std::to_string(size) + " elements, not " + std::to_string(value_.size()));
}

std::string JsonReader::text() const {
  if (!value_.is_string()) fail("must be a string");
  return value_.get<std::string>();
}

bool JsonReader::boolean() const {
  if (!value_.is_boolean()) fail("must be true or false");
  return value_.get<bool>();
}

float JsonReader::number() const {
  if (!value_.is_number()) fail("must be a number");
  const double x = value_.get<double>();
  if (!std::isfinite(x) || std::abs(x) > double(std::numeric_limits<float>::max())) fail("is not a finite number");
  return static_cast<float>(x);
}

float JsonReader::number(float min, float max, bool min_open) const {
  const float x = number();
  if (x < min || (min_open && x == min) || x > max)
    fail("must be in " + std::string(min_open ? "(" : "[") + shortest_text(min) + ", " + shortest_text(max) + "]");
  return x;
}

std::int64_t JsonReader::integer(std::int64_t min, std::int64_t max) const {
  if (!value_.is_number_integer()) fail("must be an integer");
  const std::string range = "[" + std::to_string(min) + ", " + std::to_string(max) + "]";
  if (value_.is_number_unsigned()) {  // may exceed the int64 range
    const std::uint64_t x = value_.get<std::uint64_t>();
    if (max < 0 || x > static_cast<std::uint64_t>(max)) fail(std::to_string(x) + " is outside " + range);
    if (static_cast<std::int64_t>(x) < min) fail(std::to_string(x) + " is outside " + range);
    return static_cast<std::int64_t>(x);
  }
  const std::int64_t x = value_.get<std::int64_t>();
  if (x < min || x > max) fail(std::to_string(x) + " is outside " + range);
  return x;
}

glm::vec3 JsonReader::vec3() const {
  expect_array(3);
  glm::vec3 v;
  for (std::size_t a = 0; a < 3; ++a) v[static_cast<glm::length_t>(a)] = at(a).number();
  return v;
}

glm::ivec3 JsonReader::ivec3(glm::ivec3 min, glm::ivec3 max) const {
  expect_array(3);
  glm::ivec3 v;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto axis = static_cast<glm::length_t>(a);
    v[axis] = static_cast<int>(at(a).integer(min[axis], max[axis]));
  }
  return v;
}

}  // namespace deform::detail
