#include "cli.hpp"

#include <charconv>
#include <cmath>
#include <iostream>
#include <stdexcept>
#include <string>

#include "deform/runtime/error.hpp"

namespace cli {

Args::Args(std::vector<std::string> argv, std::vector<std::string> value_flags, std::vector<std::string> switch_flags) {
  auto is_in = [](const std::vector<std::string>& list, const std::string& s) {
    for (const std::string& item : list)
      if (item == s) return true;
    return false;
  };
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--help" || a == "-h") {
      help_ = true;
    } else if (a.size() > 2 && a.rfind("--", 0) == 0) {
      std::string flag = a, inline_value;
      const std::size_t eq = a.find('=');
      const bool has_inline = eq != std::string::npos;
      if (has_inline) flag = a.substr(0, eq), inline_value = a.substr(eq + 1);
      if (is_in(value_flags, flag)) {
        if (has_inline) values_.emplace_back(flag, inline_value);
        else if (i + 1 < argv.size()) values_.emplace_back(flag, argv[++i]);
        else throw UsageError(flag + " needs a value");
      } else if (is_in(switch_flags, flag) && !has_inline) {
        switches_.push_back(flag);
      } else {
        throw UsageError("unknown option " + a);
      }
    } else {
      positionals_.push_back(a);
    }
  }
}

bool Args::has(std::string_view flag) const {
  for (const auto& s : switches_)
    if (s == flag) return true;
  return value(flag).has_value();
}

std::optional<std::string> Args::value(std::string_view flag) const {
  std::optional<std::string> found;
  for (const auto& [f, v] : values_)
    if (f == flag) found = v;
  return found;
}

std::vector<std::string> Args::values(std::string_view flag) const {
  std::vector<std::string> found;
  for (const auto& [f, v] : values_)
    if (f == flag) found.push_back(v);
  return found;
}

std::string Args::required(std::string_view flag) const {
  auto v = value(flag);
  if (!v) throw UsageError(std::string(flag) + " is required");
  return *v;
}

double parse_number(const std::string& text, std::string_view what) {
  double value = 0.0;
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (begin != end && *begin == '+') ++begin;
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end || begin == end || !std::isfinite(value))
    throw UsageError(std::string(what) + ": '" + text + "' is not a finite number");
  return value;
}

long long parse_integer(const std::string& text, std::string_view what, long long min, long long max) {
  long long value = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size() || text.empty())
    throw UsageError(std::string(what) + ": '" + text + "' is not an integer");
  if (value < min || value > max)
    throw UsageError(std::string(what) + ": " + text + " is outside [" + std::to_string(min) + ", " +
                     std::to_string(max) + "]");
  return value;
}

glm::vec3 parse_vec3(const std::string& text, std::string_view what) {
  glm::vec3 v(0.0f);
  std::size_t start = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t comma = text.find(',', start);
    const bool last = axis == 2;
    if (last != (comma == std::string::npos)) throw UsageError(std::string(what) + ": '" + text + "' is not X,Y,Z");
    const std::string part = text.substr(start, last ? std::string::npos : comma - start);
    const double d = parse_number(part, what);
    // A point in space (a target, a pole): beyond 1e18 the squared distances to it overflow a float, and a result
    // computed from it would not be finite.
    if (std::abs(d) > 1.0e18)
      throw UsageError(std::string(what) + ": '" + part + "' is out of range (beyond 1e18, distances to it overflow)");
    v[axis] = static_cast<float>(d);
    start = comma + 1;
  }
  return v;
}

// Invalid UTF-8 (a non-UTF-8 output path, a name from a file) is printed as U+FFFD instead of failing the dump after
// the outputs were written.
// nlohmann writes a NaN or an infinity as null, which a reader takes for "no value": a result that is not finite is a
// defect to report (exit 1), never printed. Checked before anything is written to stdout.
template <class Json>
void require_finite(const Json& value, const std::string& where) {
  if (value.is_number_float() && !std::isfinite(value.template get<double>()))
    throw std::logic_error("internal error: the result " + (where.empty() ? std::string("value") : where) +
                           " is not finite (not printed)");
  if (value.is_object())
    for (auto item = value.begin(); item != value.end(); ++item) require_finite(item.value(), where + "/" + item.key());
  if (value.is_array())
    for (std::size_t i = 0; i < value.size(); ++i) require_finite(value[i], where + "/" + std::to_string(i));
}

void require_finite_json(const nlohmann::json& document) { require_finite(document, ""); }
void require_finite_json(const nlohmann::ordered_json& document) { require_finite(document, ""); }

void print_json(const nlohmann::json& document) {
  require_finite(document, "");
  std::cout << document.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
}
void print_json_in_order(const nlohmann::ordered_json& document) {
  require_finite(document, "");
  std::cout << document.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << '\n';
}

// Warnings quote names and paths from files: control characters are escaped (the readers do; this keeps any other
// message to one line as well).
void note(const std::string& message) { std::cerr << "deform: " << deform::escape_control_characters(message) << '\n'; }

nlohmann::json to_json(glm::vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); }

}  // namespace cli
