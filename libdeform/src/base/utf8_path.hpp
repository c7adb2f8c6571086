#pragma once
// Base (private to libdeform, not installed; docs/architecture.md, "Walls"): paths between the API's UTF-8 strings and
// std::filesystem, for the layers that touch files (io, import; never runtime).
// Every path libdeform takes or returns is UTF-8. std::filesystem::path(std::string), path::string() and the file
// streams' std::string constructors read and write the bytes in the system's narrow encoding: on POSIX that is the
// bytes themselves, on Windows the ANSI code page, which garbles (or refuses) any name outside ASCII. Every place
// that turns an API string into a path, or a path back into an API string, goes through these instead; on POSIX they
// are the narrow conversions, byte for byte.
#include <filesystem>
#include <string>
#include <string_view>

#include "deform/runtime/error.hpp"

namespace deform::utf8_path {

// The path a UTF-8 string names: on Windows the wide path it spells. Throws deform::Error (input, naming the string)
// on Windows when the bytes are not UTF-8, as no wide name corresponds to them.
inline std::filesystem::path from_utf8(std::string_view utf8) {
#ifdef _WIN32
  try {
    return std::filesystem::path(std::u8string(utf8.begin(), utf8.end()));
  } catch (const std::filesystem::filesystem_error&) {
    throw Error::in_file(std::string(utf8), "", "the file name is not UTF-8");
  }
#else
  return std::filesystem::path(std::string(utf8));
#endif
}

// A path's UTF-8 string, in the system's separators.
inline std::string to_utf8(const std::filesystem::path& path) {
#ifdef _WIN32
  const std::u8string text = path.u8string();
  return std::string(text.begin(), text.end());
#else
  return path.string();
#endif
}

// A path's UTF-8 string with '/' as the separator.
inline std::string generic_utf8(const std::filesystem::path& path) {
#ifdef _WIN32
  const std::u8string text = path.generic_u8string();
  return std::string(text.begin(), text.end());
#else
  return path.generic_string();
#endif
}

}  // namespace deform::utf8_path
