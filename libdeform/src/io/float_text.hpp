#pragma once
// Private to deform::io: a float as the shortest decimal text that reads back as the same float (std::to_chars:
// locale-independent; "0.1", "-3", "1e-07", "inf", "nan"). Every number libdeform writes as text takes this form:
// OBJ, .skw, the JSON writers (through shortest_double, deform/io/text.hpp) and messages that quote a limit.
#include <charconv>
#include <string>

namespace deform::detail {

// Appends the text to `out`: at most 15 characters ("-1.17549435e-38"), no separator.
inline void append_shortest(std::string& out, float value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

inline std::string shortest_text(float value) {
  std::string text;
  append_shortest(text, value);
  return text;
}

}  // namespace deform::detail
