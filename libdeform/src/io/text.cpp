// Floats in text output (deform/io/text.hpp).
#include "deform/io/text.hpp"

#include <string>

#include "float_text.hpp"

namespace deform {

double shortest_double(float value) {
  if (value == 0.0f) return 0.0;
  const std::string text = detail::shortest_text(value);  // at most 15 characters: no heap allocation
  double result = 0.0;
  detail::read_decimal(text.data(), text.data() + text.size(), result);  // reads "inf", "-inf" and "nan" as well
  return result;
}

}  // namespace deform
