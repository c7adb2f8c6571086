// The confinement rule for files a model names (deform/io/referenced_file.hpp, docs/security.md).
#include "deform/io/referenced_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>

#ifdef _WIN32
#include <fstream>
#else
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

#include "deform/runtime/error.hpp"
#include "utf8_path.hpp"

namespace deform {
namespace {

namespace fs = std::filesystem;
using utf8_path::from_utf8;
using utf8_path::to_utf8;

// The path a UTF-8 string names; empty where it names none (on Windows, bytes that are not UTF-8).
fs::path path_or_empty(const std::string& utf8) {
  try {
    return from_utf8(utf8);
  } catch (const Error&) {
    return {};
  }
}

// `path` with every existing component's links resolved and the rest normalised; empty when it cannot be resolved
// (a component that exists but cannot be examined).
fs::path canonical_or_empty(const fs::path& path) {
  std::error_code error;
  fs::path absolute = fs::absolute(path, error);
  if (error) return {};
  fs::path result = fs::weakly_canonical(absolute, error);
  if (error) return {};
  return result;
}

// True when `inner` (canonical) lies strictly below `outer` (canonical).
bool below(const fs::path& inner, const fs::path& outer) {
  if (inner.empty() || outer.empty()) return false;
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (o->empty() && std::next(o) == outer.end()) break;  // a trailing separator ("/a/b/")
    if (i == inner.end() || *i != *o) return false;
  }
  return i != inner.end() && !i->empty();
}

[[noreturn]] void refuse(const std::string& referrer, std::int64_t line, const std::string& key, std::string message) {
  if (line > 0) throw Error::at_line(referrer, line, key, std::move(message));
  throw Error::in_file(referrer, key, std::move(message));
}

}  // namespace

std::string decode_uri_reference(std::string_view uri) {
  const auto hex = [](char c) {
    return c <= '9' ? c - '0' : static_cast<char>(std::tolower(static_cast<unsigned char>(c))) - 'a' + 10;
  };
  std::string decoded;
  decoded.reserve(uri.size());
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      decoded.push_back(static_cast<char>(hex(uri[i + 1]) * 16 + hex(uri[i + 2])));
      i += 2;
    } else {
      decoded.push_back(uri[i]);
    }
  }
  return decoded;
}

std::string resolve_referenced_file_in(const std::string& folder, const std::string& referrer,
                                       std::string_view reference, const std::string& key,
                                       const ReferencePolicy& policy, ReferenceSyntax syntax, std::int64_t line) {
  const std::string name = syntax == ReferenceSyntax::uri ? decode_uri_reference(reference) : std::string(reference);
  if (name.empty()) refuse(referrer, line, key, "names no file");
  if (name.find('\0') != std::string::npos) refuse(referrer, line, key, "the file name holds a NUL byte");
  const fs::path base = folder.empty() ? fs::path(".") : from_utf8(folder);
  const fs::path named = path_or_empty(name);
  if (named.empty()) refuse(referrer, line, key, "the file name is not UTF-8");
  const fs::path real = canonical_or_empty(named.is_absolute() ? named : base / named);
  const fs::path real_folder = canonical_or_empty(base);
  if (!real.empty() && below(real, real_folder)) return to_utf8(real);
  for (const std::string& allowed : policy.allow_outside)
    if (!real.empty() && !allowed.empty() && below(real, canonical_or_empty(path_or_empty(allowed))))
      return to_utf8(real);
  // Nothing about the file itself is said (not whether it exists, nor its size): only what the model wrote. Kept
  // short, as a message is cut at 200 bytes (error.hpp) and the name is what the reader needs.
  refuse(referrer, line, key,
         "refused, outside the model's folder (--allow-outside DIR allows one): '" + std::string(reference) + "'");
}

std::string resolve_referenced_file(const std::string& referrer, std::string_view reference, const std::string& key,
                                    const ReferencePolicy& policy, ReferenceSyntax syntax, std::int64_t line) {
  const std::string folder = to_utf8(from_utf8(referrer).parent_path());
  return resolve_referenced_file_in(folder.empty() ? "." : folder, referrer, reference, key, policy, syntax, line);
}

bool lies_inside(const std::string& path, const std::string& folder) {
  if (path.empty() || folder.empty()) return false;
  return below(canonical_or_empty(path_or_empty(path)), canonical_or_empty(path_or_empty(folder)));
}

std::string image_format(const std::string& path) {
  std::array<unsigned char, 32> head{};
  std::size_t size = 0;
#ifdef _WIN32
  // Only a regular file is read (a device or pipe name is not).
  const fs::path file = path_or_empty(path);
  std::error_code error;
  if (file.empty() || !fs::is_regular_file(file, error)) return {};
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  size = static_cast<std::size_t>(in.gcount());
#else
  // O_NONBLOCK: a FIFO named as a texture must not hang the check; only a regular file is read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) return {};
  struct stat info {};
  if (::fstat(fd, &info) == 0 && S_ISREG(info.st_mode)) {
    while (size < head.size()) {
      const ssize_t got = ::read(fd, head.data() + size, head.size() - size);
      if (got <= 0) break;
      size += static_cast<std::size_t>(got);
    }
  }
  ::close(fd);
#endif
  const auto starts = [&](std::string_view magic, std::size_t at = 0) {
    return size >= at + magic.size() &&
           std::equal(magic.begin(), magic.end(), head.begin() + static_cast<std::ptrdiff_t>(at),
                      [](char m, unsigned char b) { return static_cast<unsigned char>(m) == b; });
  };
  using namespace std::string_view_literals;
  if (starts("\x89PNG\r\n\x1a\n"sv)) return "png";
  if (starts("\xff\xd8\xff"sv)) return "jpeg";
  if (starts("GIF87a"sv) || starts("GIF89a"sv)) return "gif";
  if (starts("DDS "sv)) return "dds";
  if (starts("\xabKTX"sv)) return "ktx";
  if (starts("II*\0"sv) || starts("MM\0*"sv)) return "tiff";
  if (starts("#?RADIANCE"sv) || starts("#?RGBE"sv)) return "hdr";
  if (starts("8BPS"sv)) return "psd";
  if (starts("RIFF"sv) && starts("WEBP"sv, 8)) return "webp";
  if (starts("BM"sv)) return "bmp";
  std::string extension = to_utf8(path_or_empty(path).extension());
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".tga" && size >= 18) return "tga";
  return {};
}

}  // namespace deform
