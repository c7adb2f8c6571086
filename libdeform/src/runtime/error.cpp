#include "deform/runtime/error.hpp"

namespace deform {
namespace {

std::string format(Error::Kind kind, const std::string& file, Error::Where where, std::int64_t position,
                   const std::string& element, const std::string& message) {
  std::string text = kind == Error::Kind::argument ? std::string("invalid argument")
                     : file.empty()                ? std::string("<memory>")
                                                   : file;
  if (where != Error::Where::none) {
    text.append(where == Error::Where::line ? ": line " : ": byte ");
    text.append(std::to_string(position));
  }
  if (!element.empty()) text.append(": ").append(element);
  text.append(": ").append(message);
  return text;
}

}  // namespace

Error::Error(Kind kind, std::string file, Where where, std::int64_t position, std::string element,
             std::string message)
    : std::runtime_error(format(kind, file, where, position, element, message)),
      kind_(kind),
      file_(std::move(file)),
      where_(where),
      position_(position),
      element_(std::move(element)),
      message_(std::move(message)) {}

}  // namespace deform
