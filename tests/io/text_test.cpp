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
