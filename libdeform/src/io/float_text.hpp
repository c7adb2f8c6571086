#pragma once
// Private to deform::io: floats to and from decimal text, locale-independent, without exceptions, and the same on
// every standard library. std::to_chars and std::from_chars for floats are missing from some (emscripten's libc++),
// so the digits come from Debian's dragonbox (shortest round trip) and the numbers from Debian's fast_float; the
// layout and the error rules around them are those of std::to_chars/std::from_chars (tests/io/text_test.cpp checks
// both against the standard library's wherever it has them).
// Every number libdeform writes as text takes the form of append_shortest: OBJ, .skw, the JSON writers (through
// shortest_double, deform/io/text.hpp) and messages that quote a limit. Every float it reads goes through
// read_decimal.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <dragonbox/dragonbox.h>
#include <fast_float/fast_float.h>
#include <string>
#include <system_error>
#include <type_traits>

namespace deform::detail {

// Appends the text std::to_chars(first, last, value) writes to `out`: the shortest digits that read back as `value`
// (ties to the nearer, then to even), in fixed or scientific form, whichever is shorter (fixed on a tie); an integer
// in fixed form with its exact digits ("0.1", "-3", "1e-07", "1e+05", "123456790", "-0", "inf", "-nan"). At most 15
// characters ("-1.17549435e-38"), no separator.
inline void append_shortest(std::string& out, float value) {
  if (std::signbit(value)) out.push_back('-');
  if (std::isnan(value)) {
    out.append("nan");
    return;
  }
  if (std::isinf(value)) {
    out.append("inf");
    return;
  }
  if (value == 0.0f) {
    out.push_back('0');
    return;
  }
  const auto decimal = jkj::dragonbox::to_decimal(std::fabs(value));
  char digits[10];  // a float's shortest form has at most 9 digits
  int count = 0;
  for (std::uint32_t rest = decimal.significand; rest != 0; rest /= 10) digits[count++] = char('0' + rest % 10);
  for (int i = 0; i < count / 2; ++i) std::swap(digits[i], digits[count - 1 - i]);
  const int exponent = decimal.exponent;  // value = digits × 10^exponent
  // Fixed when it is no longer than scientific: "d.ddde+XX" has count + (count > 1) + 4 characters (a float's
  // decimal exponent has two digits).
  const bool fixed = count == 1 ? (-3 <= exponent && exponent <= 4) : (-(count + 3) <= exponent && exponent <= 5);
  if (fixed && exponent >= 0) {
    // An integer below 10^14: its exact digits, which read back as `value` as the shortest ones do.
    out.append(std::to_string(static_cast<std::uint64_t>(std::fabs(value))));
  } else if (fixed) {
    const int whole = count + exponent;  // digits before the point, or zeros after it where negative
    if (whole > 0) {
      out.append(digits, static_cast<std::size_t>(whole)).push_back('.');
      out.append(digits + whole, static_cast<std::size_t>(count - whole));
    } else {
      out.append("0.").append(static_cast<std::size_t>(-whole), '0').append(digits, static_cast<std::size_t>(count));
    }
  } else {
    out.push_back(digits[0]);
    if (count > 1) out.append(".").append(digits + 1, static_cast<std::size_t>(count - 1));
    const int scientific = exponent + count - 1;
    const int magnitude = scientific < 0 ? -scientific : scientific;
    out.push_back('e');
    out.push_back(scientific < 0 ? '-' : '+');
    out.push_back(char('0' + magnitude / 10));
    out.push_back(char('0' + magnitude % 10));
  }
}

inline std::string shortest_text(float value) {
  std::string text;
  append_shortest(text, value);
  return text;
}

// What std::from_chars(first, last, value) does for a float or a double in chars_format::general: the longest
// prefix that is a decimal number ("-1.5e3", ".5", "inf", "nan(…)"; no '+', no spaces, no hexadecimal), rounded to
// nearest. `ptr` is past it; `ec` is invalid_argument (ptr == first) where there is none, result_out_of_range where
// the number rounds to infinity or to zero without being zero; `value` changes only on success.
struct DecimalResult {
  const char* ptr;
  std::errc ec;
};

template <typename T>
DecimalResult read_decimal(const char* first, const char* last, T& value) noexcept {
  static_assert(std::is_same_v<T, float> || std::is_same_v<T, double>);
  T parsed = 0;
  const auto result = fast_float::from_chars(first, last, parsed);
  if (result.ec != std::errc()) return {result.ptr, result.ec};
  const char* mantissa = first + (*first == '-' ? 1 : 0);
  const bool literal = *mantissa == 'i' || *mantissa == 'I' || *mantissa == 'n' || *mantissa == 'N';
  if (!literal) {
    if (std::isinf(parsed)) return {result.ptr, std::errc::result_out_of_range};
    if (parsed == 0) {
      for (const char* c = mantissa; c != result.ptr && *c != 'e' && *c != 'E'; ++c)
        if (*c >= '1' && *c <= '9') return {result.ptr, std::errc::result_out_of_range};
    }
  }
  value = parsed;
  return {result.ptr, std::errc()};
}

}  // namespace deform::detail
