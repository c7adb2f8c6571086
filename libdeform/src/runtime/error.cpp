#include "deform/runtime/error.hpp"

#include <algorithm>

namespace deform {
namespace {

// Elements and messages quote the input (a key, a name): a hostile file can make them megabytes long or put line
// breaks in them. Control characters are written as \xNN, and the text is cut to this many bytes (at a UTF-8
// character boundary) with "..." and its full length, so what() stays one short line.
constexpr std::size_t max_quoted_bytes = 200;

std::string shortened(std::string text) {
  if (std::any_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }))
    text = escape_control_characters(text);
  if (text.size() <= max_quoted_bytes) return text;
  std::size_t cut = max_quoted_bytes;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;  // not inside a UTF-8 sequence
  const std::size_t full = text.size();
  text.resize(cut);
  return text + "... (" + std::to_string(full) + " bytes)";
}

std::string format(Error::Kind kind, const std::string& file, Error::Where where, std::int64_t position,
                   const std::string& element, const std::string& message) {
  std::string text = kind == Error::Kind::argument ? std::string("invalid argument")
                     : file.empty()                ? std::string("<memory>")
                                                   : escape_control_characters(file);  // a path a model named
  if (where != Error::Where::none) {
    text.append(where == Error::Where::line ? ": line " : ": byte ");
    text.append(std::to_string(position));
  }
  if (!element.empty()) text.append(": ").append(element);
  text.append(": ").append(message);
  return text;
}

}  // namespace

std::string escape_control_characters(std::string_view text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte != 0x7f) {
      escaped += c;
      continue;
    }
    constexpr char hex[] = "0123456789abcdef";
    escaped += "\\x";
    escaped += hex[byte >> 4];
    escaped += hex[byte & 15];
  }
  return escaped;
}

Error::Error(Kind kind, std::string file, Where where, std::int64_t position, std::string element, std::string message)
    : std::runtime_error(format(kind, file, where, position, shortened(element), shortened(message))),
      kind_(kind),
      file_(std::move(file)),
      where_(where),
      position_(position),
      element_(shortened(std::move(element))),
      message_(shortened(std::move(message))) {}

}  // namespace deform
