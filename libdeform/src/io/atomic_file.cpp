#include "deform/io/atomic_file.hpp"
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <fcntl.h>
#include <unistd.h>

#include "deform/runtime/error.hpp"
namespace deform {
namespace {

std::string errno_text() { return std::strerror(errno); }

template <class Container>
Container read_all(const std::string& path, std::uint64_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error::in_file(path, "", "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error::in_file(path, "", "cannot open for reading: " + errno_text());
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error::in_file(path, "", "cannot determine the file size");
  if (static_cast<std::uint64_t>(size) > max_bytes)
    throw Error::in_file(path, "", "file is " + std::to_string(size) + " bytes, more than the limit of " +
                                       std::to_string(max_bytes));
  in.seekg(0, std::ios::beg);
  Container data(static_cast<std::size_t>(size), {});
  if (size > 0 && !in.read(reinterpret_cast<char*>(data.data()), size))
    throw Error::in_file(path, "", "read failed: " + errno_text());
  return data;
}

}  // namespace

std::vector<std::uint8_t> read_file_bytes(const std::string& path, std::uint64_t max_bytes) {
  return read_all<std::vector<std::uint8_t>>(path, max_bytes);
}

std::string read_file_text(const std::string& path, std::uint64_t max_bytes) {
  return read_all<std::string>(path, max_bytes);
}

void write_file_atomic(const std::string& path, std::span<const std::uint8_t> data) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::random_device entropy;
  std::string temp;
  int fd = -1;
  for (int attempt = 0; attempt < 16 && fd < 0; ++attempt) {
    temp = (folder / ("." + target.filename().string() + ".tmp" + std::to_string(entropy()))).string();
    fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) throw Error::in_file(path, "", "cannot create a temporary file beside it: " + errno_text());

  const std::uint8_t* cursor = data.data();
  std::size_t left = data.size();
  bool ok = true;
  while (ok && left > 0) {
    const ssize_t written = ::write(fd, cursor, left);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) ok = false;
    else {
      cursor += written;
      left -= static_cast<std::size_t>(written);
    }
  }
  std::string failure = ok ? std::string() : "write failed: " + errno_text();
  if (ok && ::fsync(fd) != 0) failure = "fsync failed: " + errno_text(), ok = false;
  if (::close(fd) != 0 && ok) failure = "close failed: " + errno_text(), ok = false;
  if (ok && std::rename(temp.c_str(), path.c_str()) != 0) failure = "rename failed: " + errno_text(), ok = false;
  if (!ok) {
    std::remove(temp.c_str());
    throw Error::in_file(path, "", failure);
  }
}

void write_file_atomic(const std::string& path, std::string_view text) {
  write_file_atomic(path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace deform
