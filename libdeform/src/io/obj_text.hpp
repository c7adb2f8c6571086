#pragma once
// Private: the line and token scanning shared by the OBJ and MTL readers. Allocation-free except for joining
// `\`-continued lines; integers through std::from_chars, floats through read_decimal (float_text.hpp), both
// locale-independent and without exceptions.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "deform/runtime/error.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/normals.hpp"
#include "deform/io/obj.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/offline/topology.hpp"
#include "float_text.hpp"

namespace deform::obj_text {

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

// The statements of an OBJ or MTL text, one per line: `#` starts a comment, a line ending in `\` continues on the
// next one, CR before LF is dropped. line() is the 1-based line where the current statement starts.
class LineReader {
 public:
  // A UTF-8 byte order mark before the first line is skipped (editors on Windows write one).
  explicit LineReader(std::string_view text) : text_(text.starts_with("\xEF\xBB\xBF") ? text.substr(3) : text) {}

  bool next(std::string_view& statement) {
    if (position_ >= text_.size()) return false;
    line_ = next_line_;
    std::string_view raw = take_line();
    if (ends_with_backslash(raw)) {
      joined_.assign(before_backslash(raw)).push_back(' ');
      while (position_ < text_.size()) {
        raw = take_line();
        if (!ends_with_backslash(raw)) {
          joined_.append(raw);
          break;
        }
        joined_.append(before_backslash(raw)).push_back(' ');
      }
      raw = joined_;
    }
    if (const auto hash = raw.find('#'); hash != std::string_view::npos) raw = raw.substr(0, hash);
    statement = trim(raw);
    return true;
  }

  std::int64_t line() const { return line_; }

 private:
  std::string_view take_line() {
    const char* begin = text_.data() + position_;
    const auto* end = static_cast<const char*>(std::memchr(begin, '\n', text_.size() - position_));
    std::size_t length = end ? static_cast<std::size_t>(end - begin) : text_.size() - position_;
    position_ += length + (end ? 1 : 0);
    ++next_line_;
    if (length > 0 && begin[length - 1] == '\r') --length;
    return {begin, length};
  }
  // A line continues when its last non-blank byte is '\\' (blanks after it are tolerated); the writer never ends a
  // name so (obj_safe_name).
  static bool ends_with_backslash(std::string_view raw) {
    raw = trim(raw);
    return !raw.empty() && raw.back() == '\\';
  }
  // The line without its final backslash and the blanks after it.
  static std::string_view before_backslash(std::string_view raw) {
    while (!raw.empty() && is_blank(raw.back())) raw.remove_suffix(1);
    return raw.substr(0, raw.size() - 1);
  }

  std::string_view text_;
  std::size_t position_ = 0;
  std::int64_t line_ = 0;
  std::int64_t next_line_ = 1;
  std::string joined_;
};

// Blank-separated tokens of one statement.
class Tokens {
 public:
  explicit Tokens(std::string_view statement) : rest_(statement) {}

  bool next(std::string_view& token) {
    std::size_t i = 0;
    while (i < rest_.size() && is_blank(rest_[i])) ++i;
    if (i == rest_.size()) {
      rest_ = {};
      return false;
    }
    std::size_t j = i;
    while (j < rest_.size() && !is_blank(rest_[j])) ++j;
    token = rest_.substr(i, j - i);
    rest_.remove_prefix(j);
    return true;
  }
  // What is left of the statement, trimmed (a name that may contain blanks).
  std::string_view rest() const { return trim(rest_); }

 private:
  std::string_view rest_;
};

// Where a statement is, for errors and warnings.
struct Place {
  const std::string& file;
  std::int64_t line;

  [[noreturn]] void fail(std::string_view element, std::string message) const {
    throw Error::at_line(file, line, std::string(element), std::move(message));
  }
};

inline std::string quoted(std::string_view token) {
  constexpr std::size_t shown = 40;
  std::string text = "'";
  for (const char c : token.substr(0, shown)) {  // control characters as \xNN: a message stays one printable line
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      text += c;
    } else {
      constexpr char hex[] = "0123456789abcdef";
      text += {'\\', 'x', hex[byte >> 4], hex[byte & 15]};
    }
  }
  if (token.size() > shown) text.append("...");
  return text.append("'");
}

// A finite float. Accepts a leading '+'; a value too small for a float rounds to zero or a denormal as usual.
inline float parse_float(std::string_view token, const Place& place, std::string_view element) {
  std::string_view digits = token;
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-') digits.remove_prefix(1);
  const char* begin = digits.data();
  const char* end = begin + digits.size();
  float value = 0.0f;
  auto [stop, error] = detail::read_decimal(begin, end, value);
  if (error == std::errc::result_out_of_range) {
    double wide = 0.0;
    const auto result = detail::read_decimal(begin, end, wide);
    stop = result.ptr;
    error = result.ec;
    if (error == std::errc() && std::fabs(wide) <= double(std::numeric_limits<float>::max()))
      value = static_cast<float>(wide);
    else if (error == std::errc() || error == std::errc::result_out_of_range)
      place.fail(element, "number " + quoted(token) + " is out of range");
  }
  if (error != std::errc() || stop != end) place.fail(element, "malformed number " + quoted(token));
  if (!std::isfinite(value)) place.fail(element, "number " + quoted(token) + " is not finite");
  return value;
}

inline std::int64_t parse_integer(std::string_view token, const Place& place, std::string_view element) {
  std::string_view digits = token;
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-') digits.remove_prefix(1);
  std::int64_t value = 0;
  const auto [stop, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error == std::errc::result_out_of_range) place.fail(element, "integer " + quoted(token) + " is out of range");
  if (error != std::errc() || stop != digits.data() + digits.size())
    place.fail(element, "malformed integer " + quoted(token));
  return value;
}

// Reads between `min` and `max` numbers into `out`; anything else on the statement is an error.
inline int parse_floats(Tokens& tokens, float* out, int min, int max, const Place& place, std::string_view element) {
  int count = 0;
  std::string_view token;
  while (tokens.next(token)) {
    if (count == max)
      place.fail(element, "too many numbers (expected " +
                              (min == max ? std::to_string(max) : std::to_string(min) + " to " + std::to_string(max)) +
                              ")");
    out[count++] = parse_float(token, place, element);
  }
  if (count < min)
    place.fail(element, "expected " + (min == max ? std::to_string(min) : "at least " + std::to_string(min)) +
                            " numbers, found " + std::to_string(count));
  return count;
}

inline void warn(Warnings* warnings, const std::string& file, std::int64_t line, std::string_view message) {
  if (!warnings) return;
  std::string text = file.empty() ? std::string("<memory>") : file;
  if (line > 0) text.append(": line ").append(std::to_string(line));
  // Names and paths from the file are escaped as errors escape them: a warning stays one line.
  warnings->messages.push_back(escape_control_characters(text.append(": ").append(message)));
}

// Statements a reader skips, reported once per keyword (first line and count) so a file of a million `l` lines
// gives one warning. At most `max_kinds` keywords are named; the rest are counted together.
class SkippedStatements {
 public:
  void add(std::string_view keyword, std::int64_t line) {
    keyword = keyword.substr(0, max_keyword_bytes);  // a "keyword" can be a gigabyte of garbage: keep a bounded copy
    for (auto& kind : kinds_)
      if (kind.keyword == keyword) {
        ++kind.count;
        return;
      }
    if (kinds_.size() < max_kinds) kinds_.push_back({std::string(keyword), line, 1});
    else ++others_;
  }
  void report(Warnings* warnings, const std::string& file) const {
    for (const auto& kind : kinds_)
      warn(warnings, file, kind.first_line,
           "statement " + obj_text::quoted(kind.keyword) + " is not supported: " + std::to_string(kind.count) +
               " skipped");
    if (others_ > 0) warn(warnings, file, 0, std::to_string(others_) + " more unsupported statements skipped");
  }

 private:
  static constexpr std::size_t max_kinds = 16;
  static constexpr std::size_t max_keyword_bytes = 64;
  struct Kind {
    std::string keyword;
    std::int64_t first_line;
    std::size_t count;
  };
  std::vector<Kind> kinds_;
  std::size_t others_ = 0;
};

// `name` relative to `folder` unless absolute, normalised, with '/' separators.
std::string resolve_path(const std::string& folder, std::string_view name);

// parse_mtl with its textures (`map_Kd`) resolved in `base_folder` and confined to `root`, the folder of the model
// that named the MTL file, and the folders `policy` allows (resolve_referenced_file): a texture elsewhere is refused.
std::vector<Material> parse_mtl_confined(std::string_view text, const std::string& name, const std::string& base_folder,
                                         const std::string& root, Warnings* warnings, const ReferencePolicy& policy);

}  // namespace deform::obj_text
