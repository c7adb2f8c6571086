// deform::shortest_double: the float's shortest round-trip text, carried as a double for JSON writers.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "deform/io/text.hpp"

TEST_CASE("shortest_double prints as the float's shortest form and reads back as the same float") {
  CHECK(nlohmann::json(deform::shortest_double(0.1f)).dump() == "0.1");
  CHECK(nlohmann::json(double(0.1f)).dump() == "0.10000000149011612");
  CHECK(nlohmann::json(deform::shortest_double(-3.0f)).dump() == "-3.0");
  CHECK(nlohmann::json(deform::shortest_double(1e-7f)).dump() == "1e-07");
  CHECK(nlohmann::json(deform::shortest_double(-0.0f)).dump() == "0.0");  // never "-0.0"
  CHECK(std::isinf(deform::shortest_double(std::numeric_limits<float>::infinity())));
  CHECK(std::isnan(deform::shortest_double(std::numeric_limits<float>::quiet_NaN())));
  std::mt19937 random(7);
  std::uniform_int_distribution<std::uint32_t> bits;
  for (int i = 0; i < 100000; ++i) {
    const std::uint32_t b = bits(random);
    float x = 0.0f;
    std::memcpy(&x, &b, sizeof x);
    if (!std::isfinite(x) || x == 0.0f) continue;
    const double printed = nlohmann::json::parse(nlohmann::json(deform::shortest_double(x)).dump()).get<double>();
    REQUIRE(static_cast<float>(printed) == x);
  }
}

// float_text.hpp (private to deform::io): the same text and the same numbers as std::to_chars and std::from_chars,
// on standard libraries that lack them for floats too (emscripten's libc++).
#include <charconv>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "float_text.hpp"

namespace {

float float_from_bits(std::uint32_t b) {
  float x = 0.0f;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

template <typename T>
bool same_bits(T a, T b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

}  // namespace

TEST_CASE("append_shortest writes std::to_chars's plain form of a float") {
  const std::vector<std::pair<float, std::string_view>> cases = {
      {0.1f, "0.1"},
      {-3.0f, "-3"},
      {1e-7f, "1e-07"},
      {1e5f, "1e+05"},
      {1e4f, "10000"},
      {0.001f, "0.001"},
      {1e-4f, "1e-04"},
      {1.5e-5f, "1.5e-05"},
      {123456789.0f, "123456792"},  // fixed, so the exact integer and not the shortest digits "12345679" + "0"
      {9.8765434e11f, "987654324224"},
      {3e10f, "3e+10"},
      {4294967296.0f, "4294967296"},
      {-0.0f, "-0"},
      {0.0f, "0"},
      {3.4028235e38f, "3.4028235e+38"},
      {1e-45f, "1e-45"},
      {-1.17549435e-38f, "-1.1754944e-38"},
      {std::numeric_limits<float>::infinity(), "inf"},
      {-std::numeric_limits<float>::infinity(), "-inf"},
      {std::numeric_limits<float>::quiet_NaN(), "nan"},
      {-std::numeric_limits<float>::quiet_NaN(), "-nan"}};
  for (const auto& [value, text] : cases) CHECK(deform::detail::shortest_text(value) == text);
  // Every 65,521st bit pattern, and every power of two with its neighbours (where the round-trip interval is
  // lopsided): each reads back as the same float, and is std::to_chars's text where the library has one.
  std::vector<std::uint32_t> patterns;
  for (std::uint64_t b = 0; b <= 0xffffffffu; b += 65521) patterns.push_back(static_cast<std::uint32_t>(b));
  for (std::uint32_t exponent = 0; exponent < 256; ++exponent)
    for (std::uint32_t sign : {0u, 0x80000000u})
      for (std::uint32_t mantissa : {0u, 1u, 2u, 0x7fffffu}) patterns.push_back(sign | exponent << 23 | mantissa);
  for (const std::uint32_t b : patterns) {
    const float x = float_from_bits(b);
    const std::string text = deform::detail::shortest_text(x);
    INFO("bits " << b << ": " << text);
    REQUIRE(text.size() <= 15);
#if defined(__cpp_lib_to_chars)
    char buffer[32];
    const auto expected = std::to_chars(buffer, buffer + sizeof buffer, x);
    REQUIRE(text == std::string_view(buffer, static_cast<std::size_t>(expected.ptr - buffer)));
#endif
    if (std::isnan(x)) continue;
    float back = 0.0f;
    const auto read = deform::detail::read_decimal(text.data(), text.data() + text.size(), back);
    REQUIRE(read.ec == std::errc());
    REQUIRE(read.ptr == text.data() + text.size());
    REQUIRE(same_bits(back, x));
  }
}

namespace {

struct Expected {
  std::string_view text;
  std::errc ec;
  std::size_t length;  // of the number read
  float value;         // where ec is success
};

template <typename T>
void check_against_standard(std::string_view text) {
#if defined(__cpp_lib_to_chars)
  INFO(text);
  T ours = T(7), theirs = T(7);
  const auto a = deform::detail::read_decimal(text.data(), text.data() + text.size(), ours);
  const auto b = std::from_chars(text.data(), text.data() + text.size(), theirs);
  CHECK(a.ec == b.ec);
  CHECK(a.ptr == b.ptr);
  if (b.ec == std::errc() && !std::isnan(theirs)) CHECK(same_bits(ours, theirs));
  if (b.ec == std::errc() && std::isnan(theirs)) CHECK(std::isnan(ours));
#else
  (void)text;
#endif
}

}  // namespace

TEST_CASE("read_decimal reads what std::from_chars reads, with its errors") {
  const std::vector<Expected> cases = {
      {"1.5", std::errc(), 3, 1.5f},
      {"-0.1", std::errc(), 4, -0.1f},
      {".5", std::errc(), 2, 0.5f},
      {"5.", std::errc(), 2, 5.0f},
      {"1e3x", std::errc(), 3, 1000.0f},
      {"1e", std::errc(), 1, 1.0f},  // an exponent without digits is not part of the number
      {"2e+", std::errc(), 1, 2.0f},
      {"0x1p3", std::errc(), 1, 0.0f},    // no hexadecimal: "0", then 'x'
      {"1e-45", std::errc(), 5, 1e-45f},  // the smallest denormal
      {"0e999", std::errc(), 5, 0.0f},
      {"-0", std::errc(), 2, -0.0f},
      {"1e60", std::errc::result_out_of_range, 4, 0.0f},
      {"-1e39", std::errc::result_out_of_range, 5, 0.0f},
      {"1e-60", std::errc::result_out_of_range, 5, 0.0f},
      {"0.000e-99999", std::errc(), 12, 0.0f},
      {"+1", std::errc::invalid_argument, 0, 0.0f},
      {" 1", std::errc::invalid_argument, 0, 0.0f},
      {"", std::errc::invalid_argument, 0, 0.0f},
      {"-", std::errc::invalid_argument, 0, 0.0f},
      {".", std::errc::invalid_argument, 0, 0.0f},
      {"e5", std::errc::invalid_argument, 0, 0.0f},
      {"inf", std::errc(), 3, std::numeric_limits<float>::infinity()},
      {"-Infinity", std::errc(), 9, -std::numeric_limits<float>::infinity()},
      {"infinite", std::errc(), 3, std::numeric_limits<float>::infinity()},
  };
  for (const Expected& c : cases) {
    INFO(c.text);
    float value = 7.0f;
    const auto result = deform::detail::read_decimal(c.text.data(), c.text.data() + c.text.size(), value);
    CHECK(result.ec == c.ec);
    CHECK(result.ptr == c.text.data() + c.length);
    CHECK(same_bits(value, c.ec == std::errc() ? c.value : 7.0f));  // unchanged on an error
    check_against_standard<float>(c.text);
    check_against_standard<double>(c.text);
  }
  float nan = 0.0f;
  const std::string_view payload = "nan(x1)";
  const auto read = deform::detail::read_decimal(payload.data(), payload.data() + payload.size(), nan);
  CHECK(read.ec == std::errc());
  CHECK(read.ptr == payload.data() + payload.size());
  CHECK(std::isnan(nan));
  for (std::string_view text :
       {"nan(x1)", "-nan", "NaN", "nan(", "1e-46", "7.006e-46", "7.1e-46", "3.4028236e38", "3.40282357e38", "1e-320",
        "1e-330", "2.4703282292062328e-324", "1.7976931348623159e308", "123456789012345678901234567890e-50",
        "0.1000000000000000055511151231257827021181583404541015625"}) {
    check_against_standard<float>(text);
    check_against_standard<double>(text);
  }
}
