// Bounded whole-file reads and atomic writes (POSIX).
#include "deform/io/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "deform/runtime/error.hpp"

namespace deform {
namespace {

namespace fs = std::filesystem;

std::string errno_text() { return std::strerror(errno); }

// Closes a descriptor on every path out of a scope.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

bool write_all(int fd, const std::uint8_t* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    data += written;
    size -= static_cast<std::size_t>(written);
  }
  return true;
}

template <class Container>
Container read_all(const std::string& path, std::uint64_t max_bytes) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer; the type is checked before anything is read.
  Descriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK)};
  if (file.fd < 0) throw Error::in_file(path, "", "cannot open for reading: " + errno_text());
  struct stat info {};
  if (::fstat(file.fd, &info) != 0) throw Error::in_file(path, "", "cannot read its attributes: " + errno_text());
  if (S_ISDIR(info.st_mode)) throw Error::in_file(path, "", "is a directory, not a file");
  if (!S_ISREG(info.st_mode)) throw Error::in_file(path, "", "is not a regular file (a device, FIFO or socket)");
  const auto size = static_cast<std::uint64_t>(info.st_size);
  if (size > max_bytes)
    throw Error::in_file(path, "", "file is " + std::to_string(size) + " bytes, more than the limit of " +
                                       std::to_string(max_bytes));
  Container data(static_cast<std::size_t>(size), {});
  std::size_t done = 0;
  while (done < data.size()) {  // a file that shrinks while read ends early; one that grows is read to `size`
    const ssize_t got = ::read(file.fd, reinterpret_cast<char*>(data.data()) + done, data.size() - done);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw Error::in_file(path, "", "read failed: " + errno_text());
    if (got == 0) break;
    done += static_cast<std::size_t>(got);
  }
  data.resize(done);
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
  // What the user named: a symbolic link is followed (the link stays, its target is written), a device or FIFO is
  // written directly (it cannot be replaced), a regular file is replaced atomically with its mode and owner kept.
  std::error_code ec;
  fs::path target(path);
  if (fs::is_symlink(fs::symlink_status(target, ec))) {
    const fs::path resolved = fs::weakly_canonical(target, ec);
    if (ec) throw Error::in_file(path, "", "cannot resolve the symbolic link: " + ec.message());
    target = resolved;
  }
  struct stat existing {};
  const bool exists = ::stat(target.c_str(), &existing) == 0;
  if (exists && S_ISDIR(existing.st_mode)) throw Error::in_file(path, "", "is a directory, not a file");
  if (exists && !S_ISREG(existing.st_mode)) {
    Descriptor out{::open(target.c_str(), O_WRONLY | O_CLOEXEC)};
    if (out.fd < 0) throw Error::in_file(path, "", "cannot open for writing: " + errno_text());
    if (!write_all(out.fd, data.data(), data.size())) throw Error::in_file(path, "", "write failed: " + errno_text());
    return;
  }

  // A temporary file beside the target, named so that one left by a killed process is recognisable:
  // .NAME.deform-tmp-NUMBER (docs/reliability.md).
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::random_device entropy;
  std::string temp;
  Descriptor out;
  for (int attempt = 0; attempt < 16 && out.fd < 0; ++attempt) {
    temp = (folder / ("." + target.filename().string() + ".deform-tmp-" + std::to_string(entropy()))).string();
    out.fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (out.fd < 0 && errno != EEXIST) break;
  }
  if (out.fd < 0) throw Error::in_file(path, "", "cannot create a temporary file beside it: " + errno_text());

  std::string failure;
  if (!write_all(out.fd, data.data(), data.size())) failure = "write failed: " + errno_text();
  if (failure.empty() && exists) {
    // Keep the replaced file's permissions, and its owner where this process may set it (root, or the same owner).
    if (::fchmod(out.fd, existing.st_mode & 07777) != 0) failure = "cannot keep the file's mode: " + errno_text();
    if (failure.empty() && ::fchown(out.fd, existing.st_uid, existing.st_gid) != 0 && errno != EPERM)
      failure = "cannot keep the file's owner: " + errno_text();
  }
  if (failure.empty() && ::fsync(out.fd) != 0) failure = "fsync failed: " + errno_text();
  const int fd = out.fd;
  out.fd = -1;
  if (::close(fd) != 0 && failure.empty()) failure = "close failed: " + errno_text();
  if (failure.empty() && std::rename(temp.c_str(), target.c_str()) != 0) failure = "rename failed: " + errno_text();
  if (!failure.empty()) {
    std::remove(temp.c_str());
    throw Error::in_file(path, "", failure);
  }
}

void write_file_atomic(const std::string& path, std::string_view text) {
  write_file_atomic(path, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

}  // namespace deform
